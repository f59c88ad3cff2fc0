"""Shared fixtures: the package root and helpers to read bags."""
from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.highlevel import AnyReader

from twil_control import PACKAGE_ROOT


@pytest.fixture
def root() -> Path:
    return PACKAGE_ROOT


def read_bag(path: Path) -> dict[str, list]:
    """{topic: [(time_ns, message), ...]} of a bag, through rosbags' AnyReader."""
    out: dict[str, list] = {}
    with AnyReader([Path(path)]) as reader:
        for conn, t, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t, reader.deserialize(raw, conn.msgtype)))
    return out


def bag_connections(path: Path) -> dict[str, tuple[str, str, int]]:
    """{topic: (msgtype, md5sum, count)}."""
    with AnyReader([Path(path)]) as reader:
        return {c.topic: (c.msgtype, c.digest, c.msgcount) for c in reader.connections}
