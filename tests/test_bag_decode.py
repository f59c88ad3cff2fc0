"""A bag whose connection declares one type and holds bytes of another (bag/reader.py): export,
plot and play say in one line which topic, which message (its index and time) and which declared
type, and exit 2, for bags and MCAP files alike; no rosbags traceback, no plot of garbage."""

from __future__ import annotations

import struct

import pytest

from twil_control.bag.__main__ import main as bag_main
from twil_control.bag.convert import convert
from twil_control.bag.writer import ChunkedWriter
from twil_control.core import messages


def _string(text: str) -> bytes:
    return struct.pack("<I", len(text)) + text.encode()


@pytest.fixture
def liar(tmp_path):
    """/chatter (std_msgs/String): message 3 is not a string; /x (std_msgs/Float64): message 2
    has 3 bytes."""
    path = tmp_path / "liar.bag"
    w = ChunkedWriter(path, chunk_seconds=0)
    w.open()
    for topic, typ, good, bad in (
        ("/chatter", "std_msgs/String", _string("hi"), b"\xff\xff\xff\x7fabc"),
        ("/x", "std_msgs/Float64", struct.pack("<d", 0.5), b"\x01\x02\x03"),
    ):
        definition, md5 = messages.definition(typ)
        conn = w.add_connection(topic, typ.replace("/", "/msg/"), msgdef=definition, md5sum=md5)
        for i in range(5):
            w.write(conn, int(1e9 + i * 1e8), bad if i == (3 if topic == "/chatter" else 2) else good)
    w.close()
    return path


@pytest.mark.parametrize("fmt", ["bag", "mcap"])
def test_export_plot_and_play_name_the_message_that_is_not_its_type(liar, tmp_path, capsys, fmt):
    path = liar if fmt == "bag" else convert(liar, tmp_path / "liar.mcap").out
    cases = [
        (["export", str(path), "/chatter", "-o", str(tmp_path / "c.csv")], "message 3 of /chatter", "1.300"),
        (["play", str(path), "--topics", "/chatter"], "message 3 of /chatter", "1.300"),
        (["plot", str(path), "/x/data", "-o", str(tmp_path / "x.png")], "message 2 of /x", "1.200"),
        (["export", str(path), "/x", "-o", str(tmp_path / "x.csv")], "message 2 of /x", "1.200"),
    ]
    for argv, which, t in cases:
        assert bag_main(argv) == 2, argv
        err = capsys.readouterr().err
        declared = "std_msgs/String" if "chatter" in which else "std_msgs/Float64"
        assert err.count("\n") == 1 and "Traceback" not in err, err
        assert f"{which} (" in err and f"t = {t} s" in err and f"is not a {declared}" in err, err
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "c.csv").exists()
