"""Recording the bus into a ROS 1 bag or an MCAP file (rosbag record's role).

The file is written as ``<name>.bag.active`` (``<name>.mcap.active``) and renamed to
``<name>.bag`` when closed, as rosbag record does: a file with the final name is always
complete and indexed, and a run killed hard leaves only an ``.active`` file, never one that
looks finished. Bag chunks are LZ4 compressed; MCAP files (bag/mcap_writer.py: the ROS 1
profile, zstd or lz4 chunks of at most a second of simulated time, a summary at the end) hold
the same connections and bytes. Every connection carries its message definition and md5sum,
and latched topics (/tf_static, /map) are marked latching so rosbag play re-latches them.
"""
from __future__ import annotations

import logging
from pathlib import Path

from rosbags.rosbag1 import Writer

from ..core import messages
from ..core.bus import Bus
from .mcap_writer import COMPRESSIONS, McapWriter

log = logging.getLogger(__name__)


#: the recorder's file formats, named by their file suffix
FORMATS = ("bag", "mcap")
MCAP_COMPRESSIONS = tuple(COMPRESSIONS)


class RecorderError(RuntimeError):
    """The bag cannot be written where asked."""


def format_of(path: Path, fmt: str | None = None) -> str:
    """The format a recording at `path` is written in: `fmt` if given (it must match the
    suffix), else the suffix's (.bag or .mcap)."""
    suffix = path.suffix.lstrip(".")
    if fmt is None:
        if suffix not in FORMATS:
            raise RecorderError(f"bag path {path} must end in .bag or .mcap")
        return suffix
    if fmt not in FORMATS:
        raise RecorderError(f"bag format '{fmt}' is not one of {', '.join(FORMATS)}")
    if suffix != fmt:
        raise RecorderError(f"bag path {path} must end in .{fmt} for the {fmt} format")
    return fmt


def active_path(path: Path) -> Path:
    return path.with_name(path.name + ".active")


def check_writable(path: Path, fmt: str | None = None) -> None:
    """Refuse before anything runs: never overwrite a bag, never write into a missing folder."""
    format_of(path, fmt)
    for p in (path, active_path(path)):
        if p.exists():
            raise RecorderError(f"{p} exists; bags are never overwritten: choose another --bag path")
    if not path.parent.is_dir():
        raise RecorderError(f"folder {path.parent} for the bag does not exist")


class BagRecorder:
    """Writes every message of the recorded topics, stamped with the simulated publish time."""

    def __init__(self, path: Path | str, bus: Bus, topics: list[str] | None = None, fmt: str | None = None,
                 compression: str | None = None) -> None:
        self.path = Path(path)
        self.format = format_of(self.path, fmt)
        check_writable(self.path, self.format)
        self._bus = bus
        self._topics = None if topics is None else set(topics)
        if self.format == "mcap":
            self._writer = McapWriter(active_path(self.path), compression=compression or "zstd")
        else:
            self._writer = Writer(active_path(self.path))
            self._writer.set_compression(Writer.CompressionFormat.LZ4)
        self._writer.open()
        self._connections: dict[str, object] = {}
        self._pending: list[tuple[object, int, object]] = []
        self.count = 0
        for topic, msgtype, msg in bus.latched_messages():
            self._on_message(topic, msgtype, msg, bus.clock.now())
        bus.add_listener(self._on_message)

    def write(self, topic: str, msgtype: str, msg, t: float) -> None:
        """Record one message published at simulated time t (the bus listener; also for messages
        published before the recorder subscribed)."""
        self._on_message(topic, msgtype, msg, t)

    def _on_message(self, topic: str, msgtype: str, msg, t: float) -> None:
        if self._writer is None or (self._topics is not None and topic not in self._topics):
            return
        conn = self._connections.get(topic)
        if conn is None:
            msgdef, md5 = messages.definition(msgtype)
            conn = self._connections[topic] = self._writer.add_connection(
                topic, msgtype, msgdef=msgdef, md5sum=md5,
                latching=1 if self._bus.is_latched(topic) else None)
        # Serialised and written at the next flush(), outside the 1 ms control update: the
        # writer compresses a whole chunk at a time (milliseconds). This relies on ROS's
        # intra-process rule that a message is not modified after it is published.
        self._pending.append((conn, int(round(t * 1e9)), msg))
        self.count += 1

    def flush(self) -> None:
        """Hand the messages serialised since the last flush to the writer (outside the
        simulation's events; the runner calls it between time slices)."""
        if self._writer is not None:
            for conn, stamp, msg in self._pending:
                self._writer.write(conn, stamp, self._bus.wire.serialize(msg))
            if self.format == "mcap":  # at most a second of simulated time in the open chunk
                self._writer.close_chunk_before(int(round(self._bus.clock.now() * 1e9)))
        self._pending.clear()

    def close(self) -> Path:
        """Write the index, close the file and give it its final name. Safe to call twice."""
        if self._writer is not None:
            self.flush()
            writer, self._writer = self._writer, None
            writer.close()
            active_path(self.path).rename(self.path)
            log.info("bag %s: %d messages on %d topics", self.path, self.count, len(self._connections))
        return self.path
