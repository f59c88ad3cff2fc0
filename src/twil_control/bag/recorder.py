"""Recording the bus into a ROS 1 bag or an MCAP file (rosbag record's role).

The file is written as ``<name>.bag.active`` and named ``<name>.bag`` when closed, as rosbag record
does, so a file with the final name is always complete and indexed. Chunks hold at most
``chunk_seconds`` of simulated time and reach the file whole, so a run killed hard loses about
that much. Nothing is overwritten: the final name is given by a hard link, which fails if the
name exists, where a rename would replace it. A failed write stops the recording and keeps the
chunks before (docs/bags.md).
"""

from __future__ import annotations

import logging
import re
import shutil
from pathlib import Path

from twil_control.errors import InputError, TwilControlError

from ..core import messages
from ..core.bus import Bus
from .bag_errors import size_text
from .chunk_file import BagWriteError
from .mcap_writer import COMPRESSIONS, McapWriter
from .output import link_new
from .writer import ChunkedWriter

log = logging.getLogger(__name__)

#: the recorder's file formats, named by their file suffix
FORMATS = ("bag", "mcap")
MCAP_COMPRESSIONS = tuple(COMPRESSIONS)

#: rosbag record's default --min-space: the free space a recording needs at start.
MIN_SPACE = 1 << 30


class RecorderError(TwilControlError, RuntimeError):
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


def parse_size(text: str) -> int:
    """rosbag record's --min-space values: bytes, or a number with k, M or G (units of 1024)."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*([kKmMgG]?)[bB]?\s*", text)
    if not m:
        raise InputError(f"--min-space {text!r}: use bytes or a number with k, M or G, e.g. 1G or 500M")
    return int(float(m.group(1)) * 1024 ** " kmg".index(m.group(2).lower() or " "))


def free_space(folder: Path) -> int:
    return shutil.disk_usage(folder).free


def check_writable(path: Path, fmt: str | None = None, min_space: int = 0) -> None:
    """Refuse before anything runs: never overwrite a bag, never write into a missing folder,
    never start with less than min_space bytes free."""
    format_of(path, fmt)
    for p in (path, active_path(path)):
        if p.exists():
            raise RecorderError(f"{p} exists; bags are never overwritten: choose another --bag path")
    if not path.parent.is_dir():
        raise RecorderError(f"folder {path.parent} for the bag does not exist")
    free = free_space(path.parent)
    if free < min_space:
        raise RecorderError(
            f"only {size_text(free)} free on {path.parent} for the bag, less than "
            f"--min-space {size_text(min_space)}: free some space, record elsewhere "
            "(--bag) or lower --min-space"
        )


class BagRecorder:
    """Writes every message of the recorded topics, stamped with the simulated publish time.

    chunk_seconds: simulated seconds a chunk holds at most (0: 1 MiB chunks only).
    min_space: free bytes below which a warning is logged while recording.
    fsync: fdatasync each chunk, in a thread of its own.
    """

    def __init__(
        self,
        path: Path | str,
        bus: Bus,
        topics: list[str] | None = None,
        fmt: str | None = None,
        compression: str | None = None,
        chunk_seconds: float = 1.0,
        min_space: int = 0,
        fsync: bool = False,
    ) -> None:
        self.path = Path(path)
        self.format = format_of(self.path, fmt)
        check_writable(self.path, self.format, min_space)
        self._bus = bus
        self._topics = None if topics is None else set(topics)
        self._min_space = min_space
        self._low_space_warned = False
        active = active_path(self.path)
        if self.format == "mcap":
            self._writer = McapWriter(active, chunk_seconds, compression=compression or "zstd", fsync=fsync)
        else:
            self._writer = ChunkedWriter(active, chunk_seconds, fsync)
            self._writer.set_compression(ChunkedWriter.CompressionFormat.LZ4)
        try:
            self._writer.open()
        except BagWriteError as error:
            self._writer = None
            raise RecorderError(f"cannot create {active}: {error.strerror} ({self._free()})") from error
        self._connections: dict[str, object] = {}
        self._pending: list[tuple[object, int, object]] = []
        self.count = 0
        #: why the recording is incomplete or not at self.path (None: all is well)
        self.failure: str | None = None
        for topic, msgtype, msg in bus.latched_messages():
            self._on_message(topic, msgtype, msg, bus.clock.now())
        bus.add_listener(self._on_message)

    def write(self, topic: str, msgtype: str, msg, t: float) -> None:
        """Record one message published at simulated time t (the bus listener; also for messages
        published before the recorder subscribed)."""
        self._on_message(topic, msgtype, msg, t)

    def _on_message(self, topic: str, msgtype: str, msg, t: float) -> None:
        if self._writer is None or self.failure or (self._topics is not None and topic not in self._topics):
            return
        conn = self._connections.get(topic)
        if conn is None:
            msgdef, md5 = messages.definition(msgtype)
            conn = self._connections[topic] = self._writer.add_connection(
                topic, msgtype, msgdef=msgdef, md5sum=md5, latching=1 if self._bus.is_latched(topic) else None
            )
        # Serialised and written at the next flush(), outside the 1 ms control update: the
        # writer compresses a whole chunk at a time (milliseconds). This relies on ROS's
        # intra-process rule that a message is not modified after it is published.
        self._pending.append((conn, int(round(t * 1e9)), msg))
        self.count += 1

    def flush(self) -> None:
        """Hand the messages serialised since the last flush to the writer, and close the chunk
        once it spans chunk_seconds (outside the simulation's events; the runner calls it
        between time slices). A write that fails stops the recording and raises
        RecorderError saying why, the free space and the time reached."""
        writer = self._writer
        if writer is None or self.failure:
            self._pending.clear()
            return
        chunks = writer.chunks_written
        try:
            for conn, stamp, msg in self._pending:
                writer.write(conn, stamp, self._bus.wire.serialize(msg))
            writer.close_chunk_before(int(round(self._bus.clock.now() * 1e9)))
        except BagWriteError as error:
            self.failure = (
                f"bag {active_path(self.path)}: {error.strerror} at t = "
                f"{self._bus.clock.now():.3f} s ({self._free()}): recording stopped; "
                f"{writer.messages_written} messages in {writer.chunks_written} chunks "
                "written before are kept"
            )
            raise RecorderError(self.failure) from error
        finally:
            self._pending.clear()
        if writer.chunks_written != chunks:
            self._check_space()

    def _free(self) -> str:
        try:
            return f"{size_text(free_space(self.path.parent))} free on {self.path.parent}"
        except OSError:
            return f"free space on {self.path.parent} unknown"

    def _check_space(self) -> None:
        """rosbag record's warning: less than min_space left (once, until it is back above)."""
        if not self._min_space:
            return
        low = free_space(self.path.parent) < self._min_space
        if low and not self._low_space_warned:
            log.warning(
                "bag %s: %s, less than --min-space %s; recording goes on until the disk is full",
                active_path(self.path),
                self._free(),
                size_text(self._min_space),
            )
        self._low_space_warned = low

    def close(self) -> Path:
        """Write the last chunk and the index, then give the file its final name; returns
        where the recording is (the .active file when it could not be closed or named, with
        self.failure saying why). Safe to call twice."""
        if self._writer is None:
            return self.path if self.failure is None else active_path(self.path)
        try:
            self.flush()  # what was published since the last slice (a run stopped within one)
        except RecorderError:
            pass
        writer, self._writer = self._writer, None
        active = active_path(self.path)
        try:
            writer.close()
        except BagWriteError as error:
            self.count = writer.messages_written
            why = f"it could not be closed ({error.strerror}, {self._free()})"
            self.failure = (f"{self.failure}; " if self.failure else "") + why
            log.error(
                "bag %s: %s; its %d messages in %d complete chunks are kept: recover them "
                "with: python -m twil_control.bag reindex %s -o %s",
                active,
                why,
                writer.messages_written,
                writer.chunks_written,
                active,
                self.path,
            )
            return active
        self.count = writer.messages_written
        try:
            link_new(active, self.path)
        except FileExistsError:
            self.failure = f"{self.path} appeared during the run and is not replaced"
            log.error(
                "%s; the recording is complete and indexed in %s: rename it yourself", self.failure, active
            )
            return active
        log.info("bag %s: %d messages on %d topics", self.path, self.count, len(self._connections))
        return self.path
