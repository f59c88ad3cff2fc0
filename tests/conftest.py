"""Shared fixtures, helpers to read bags, and the order in which pytest-xdist hands out test files."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Writer

from twil_control import PACKAGE_ROOT
from twil_control.core import messages


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """`--dist loadfile` hands out the costliest test files first (support/file_order.py)."""
    if config.getvalue("dist") != "loadfile":
        return None
    from support.file_order import CostliestFileFirst

    return CostliestFileFirst(config, log)


@pytest.fixture
def root() -> Path:
    return PACKAGE_ROOT


def read_bag(path: Path, topics: Iterable[str] | None = None) -> dict[str, list]:
    """{topic: [(time_ns, message), ...]} of a bag, through rosbags' AnyReader; only `topics` when
    given (a navigation run's maps and costmaps take seconds to decode)."""
    out: dict[str, list] = {}
    with AnyReader([Path(path)]) as reader:
        wanted = () if topics is None else [c for c in reader.connections if c.topic in set(topics)]
        if topics is not None and not wanted:
            return out  # (an empty collection would read every topic)
        for conn, t, raw in reader.messages(connections=wanted):
            out.setdefault(conn.topic, []).append((t, reader.deserialize(raw, conn.msgtype)))
    return out


def bag_connections(path: Path) -> dict[str, tuple[str, str, int]]:
    """{topic: (msgtype, md5sum, count)}."""
    with AnyReader([Path(path)]) as reader:
        return {c.topic: (c.msgtype, c.digest, c.msgcount) for c in reader.connections}


def write_bag(path: Path, topics: dict[str, list], compression: bool = True) -> Path:
    """A bag of {topic: [(t seconds, message)]} written with rosbags' Writer (not the project's
    recorder: tests of the bag tools need bags the project did not make)."""
    w = Writer(path)
    if compression:
        w.set_compression(Writer.CompressionFormat.LZ4)
    w.open()
    for topic, msgs in topics.items():
        typ = msgs[0][1].__msgtype__
        msgdef, md5 = messages.definition(typ)
        conn = w.add_connection(topic, typ, msgdef=msgdef, md5sum=md5)
        for t, m in msgs:
            w.write(conn, int(round(t * 1e9)), messages.serialize(m))
    w.close()
    return path


@pytest.fixture
def meshcat_freed_here():
    """Collects garbage on the test's own (main) thread after the test. Drake's Meshcat may only
    be used and destroyed on the thread that made it; a ViewNode left in a reference cycle would
    otherwise be collected by whichever thread next triggers a collection (a later test's server
    thread), and Meshcat's destructor aborts the process there."""
    yield
    import gc

    gc.collect()
