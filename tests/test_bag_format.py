"""bag/format.py: a chunk's messages located from its index data (`indexed_records`, what the
reader uses) equal the record walk of the decompressed chunk (`chunk_records`, what unindexed
bags get), message for message, on a bag the project did not write."""

from __future__ import annotations

import numpy as np
from conftest import read_bag, write_bag

from twil_control.bag import format as fmt
from twil_control.core.messages import msg_class


def test_indexed_records_equal_the_record_walk(tmp_path):
    Float64, String = msg_class("std_msgs/Float64"), msg_class("std_msgs/String")
    path = write_bag(
        tmp_path / "two.bag",
        {
            "/a": [(0.001 * k, Float64(data=float(k))) for k in range(3000)],
            "/b": [(0.0105 * k, String(data="x" * (k % 50))) for k in range(280)],  # varying sizes
        },
    )
    index = fmt.read_index(path)
    assert len(index.chunks) >= 1
    seen = {}
    with path.open("rb") as f:
        for chunk in index.chunks:
            data = fmt.read_chunk_data(f, chunk.pos)
            walked = fmt.chunk_records(data)
            got = fmt.indexed_records(f, chunk, index.size, data)
            # the same records, in the walk's (file) order once sorted by offset
            order = np.argsort(got.offset)
            for name in ("conn", "time", "offset", "length"):
                assert np.array_equal(getattr(got, name)[order], getattr(walked, name)), name
            for c, t, o, n in zip(got.conn, got.time, got.offset, got.length):
                seen.setdefault(int(c), []).append((int(t), data[o : o + n]))
    expected = read_bag(path)  # rosbags' reader
    topics = {c.id: c.topic for c in index.connections.values()}
    assert {topics[c]: len(v) for c, v in seen.items()} == {"/a": 3000, "/b": 280}
    for cid, records in seen.items():
        times = [t for t, _ in sorted(records)]
        assert times == [t for t, _ in expected[topics[cid]]]
