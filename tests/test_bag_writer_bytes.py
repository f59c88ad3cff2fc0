"""The project's bag writer (bag/writer.py) packs message records itself: with chunks capped by
size only, its file is rosbags' Writer's byte for byte (messages on several connections, out of
time order, across chunk boundaries, uncompressed and LZ4); a connection it was not given is
refused as rosbags refuses it."""

from __future__ import annotations

import numpy as np
import pytest
from rosbags.rosbag1 import Writer, WriterError

from twil_control.bag.writer import ChunkedWriter
from twil_control.core import messages


def _write(writer, rng: np.random.Generator) -> None:
    writer.open()
    connections = []
    for i, typ in enumerate(("std_msgs/String", "geometry_msgs/Twist", "tf2_msgs/TFMessage")):
        definition, md5 = messages.definition(typ)
        connections.append(
            writer.add_connection(f"/t{i}", messages.full_type_name(typ), msgdef=definition, md5sum=md5)
        )
    for k in range(2500):  # about 2.5 MB: three 1 MiB chunks
        stamp = 1_700_000_000 * 10**9 + k * 10**6 - int(rng.integers(0, 5 * 10**6))  # not in order
        writer.write(connections[k % 3], stamp, rng.bytes(int(rng.integers(0, 2000))))
    writer.close()


@pytest.mark.parametrize("compression", [None, Writer.CompressionFormat.LZ4])
def test_records_are_rosbags_bytes(tmp_path, compression):
    ours, theirs = ChunkedWriter(tmp_path / "ours.bag", chunk_seconds=0), Writer(tmp_path / "theirs.bag")
    for writer in (ours, theirs):
        if compression is not None:
            writer.set_compression(compression)
    _write(ours, np.random.default_rng(5))
    _write(theirs, np.random.default_rng(5))
    assert (tmp_path / "ours.bag").read_bytes() == (tmp_path / "theirs.bag").read_bytes()


def test_a_connection_of_another_writer_is_refused(tmp_path):
    other = Writer(tmp_path / "other.bag")
    other.open()
    definition, md5 = messages.definition("std_msgs/String")
    stranger = other.add_connection("/elsewhere", "std_msgs/msg/String", msgdef=definition, md5sum=md5)
    writer = ChunkedWriter(tmp_path / "a.bag")
    writer.open()
    with pytest.raises(WriterError, match="no connection"):
        writer.write(stranger, 1, b"x")
    writer.close()
    other.close()
