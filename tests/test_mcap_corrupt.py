"""Corrupt MCAP files: every read checks CRCs (bag/mcap_format.py). A chunk whose bytes changed
is named with its number, time range and message count, and every bag command refuses the file;
reindex and convert leave the chunk out, count what they dropped, and write only bytes that
matched their CRC. A recorder's .mcap.active that ends at a chunk boundary is not "cut".
"""

from __future__ import annotations

import struct

import numpy as np
import pytest
from mcap.reader import make_reader

from twil_control.bag.__main__ import main as bag_main
from twil_control.bag.convert import convert
from twil_control.bag.mcap_format import CorruptMcapError, read_index
from twil_control.bag.mcap_writer import McapWriter
from twil_control.bag.reader import Bag
from twil_control.bag.reindex import reindex
from twil_control.core import messages
from twil_control.errors import TwilControlError

CHUNKS, PER_CHUNK = 5, 10  # 0.1 s apart, chunks of 1 s
TOPIC = "/qbot/odom_x"


def value(i: int) -> float:
    return 0.3001104923995829 + i


def write_mcap(path) -> None:
    definition, md5 = messages.definition("std_msgs/Float64")
    w = McapWriter(path, chunk_seconds=1.0)
    w.open()
    conn = w.add_connection(TOPIC, "std_msgs/msg/Float64", msgdef=definition, md5sum=md5)
    for i in range(CHUNKS * PER_CHUNK):
        w.write(conn, int(i * 1e8), struct.pack("<d", value(i)))
    w.close()


def flip(path, at: int) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0x01
    path.write_bytes(bytes(data))


@pytest.fixture
def corrupt(tmp_path):
    """A 5-chunk MCAP file with one byte flipped inside chunk 2's compressed records."""
    path = tmp_path / "run.mcap"
    write_mcap(path)
    index = read_index(path)
    assert len(index.chunks) == CHUNKS
    ci = index.chunk_index[index.chunks[1].pos]
    flip(path, ci.chunk_start_offset + ci.chunk_length - 3)  # the last bytes of its zstd frame
    return path


def test_a_corrupt_chunk_is_named_by_every_read(corrupt, capsys):
    with pytest.raises(CorruptMcapError) as error:
        Bag(corrupt)
    text = str(error.value)
    assert "chunk 2 of 5 (t = 1.000 .. 1.900 s, 10 messages)" in text and "reindex" in text
    assert isinstance(error.value, TwilControlError)
    for argv in (["info", str(corrupt)], ["export", str(corrupt), TOPIC, "-o", str(corrupt) + ".csv"]):
        assert bag_main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "corrupt chunk 2 of 5" in err, err


def test_reindex_and_convert_leave_the_chunk_out_and_count_it(corrupt, tmp_path, capsys):
    out = tmp_path / "fixed.mcap"
    assert bag_main(["reindex", str(corrupt), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "left out corrupt chunk 2 of 5 (t = 1.000 .. 1.900 s, 10 messages)" in err
    assert "10 messages dropped with 1 corrupt chunk" in err
    r = reindex(corrupt, tmp_path / "again.mcap")
    assert (r.messages, r.corrupt_messages, [c.number for c in r.corrupt]) == (40, 10, [2])
    # what was written matches its CRCs (the mcap package's own check) and holds no byte of chunk 2
    with out.open("rb") as f:
        got = [(m.log_time, m.data) for _, _, m in make_reader(f, validate_crcs=True).iter_messages()]
    kept = [i for i in range(50) if not 10 <= i < 20]
    assert got == [(int(i * 1e8), struct.pack("<d", value(i))) for i in kept]
    bag = Bag(out)  # every CRC checked on open
    _, x = bag.columns(TOPIC, ["data"])
    assert np.array_equal(np.asarray(x["data"]), [value(i) for i in kept])
    c = convert(corrupt, tmp_path / "fixed.bag")
    assert (c.messages, c.dropped) == (40, 10)
    assert Bag(tmp_path / "fixed.bag").topics[TOPIC].count == 40


def test_bytes_changed_outside_the_chunks_fail_the_data_crc(tmp_path):
    path = tmp_path / "run.mcap"
    write_mcap(path)
    index = read_index(path)
    offset = next(iter(index.chunk_index[index.chunks[2].pos].message_index_offsets.values()))
    flip(path, offset + 1 + 8 + 2 + 4 + 3)  # a time inside chunk 3's message index
    with pytest.raises(CorruptMcapError, match="data section's CRC is 0x"):
        Bag(path)


def test_an_active_file_that_ends_at_a_chunk_boundary_is_not_cut(tmp_path, capsys):
    path = tmp_path / "run.mcap"
    write_mcap(path)
    index = read_index(path)
    boundary = index.chunks[3].pos  # chunks 1-3 and their message indexes are complete
    data = path.read_bytes()
    (tmp_path / "a.mcap.active").write_bytes(data[:boundary])
    (tmp_path / "b.mcap.active").write_bytes(data[: boundary + 40])
    assert bag_main(["reindex", str(tmp_path / "a.mcap.active"), "-o", str(tmp_path / "a.mcap")]) == 0
    out = capsys.readouterr().out
    assert "recovered 30 messages" in out and "ends inside a chunk" not in out, out
    assert bag_main(["reindex", str(tmp_path / "b.mcap.active"), "-o", str(tmp_path / "b.mcap")]) == 0
    out = capsys.readouterr().out
    assert "recovered 30 messages" in out and "ends inside a chunk" in out, out
