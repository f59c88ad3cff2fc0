"""Writing MCAP files for ROS 1 (the MCAP "ros1" profile), with the recorder's safety rules.

The `mcap` package's Writer does the format: chunks compressed with zstd or lz4, message
indexes after each chunk, and at close a summary section (schemas, channels, chunk indexes,
statistics, summary offsets) and the footer. This module adds what a recorder that may be
killed needs, with the interface of the rosbag writer the recorder already drives
(``add_connection``, ``write``, ``close_chunk_before``, ``close``):

- Channels are ROS 1 connections: message encoding ``ros1``, schema ``ros1msg`` named
  ``pkg/Type`` holding the full concatenated definition rosbag stores, metadata ``latching``
  ("true"/"false", the profile's key), ``md5sum`` and ``callerid`` (so a bag converted to
  MCAP and back has the same connection records).
- A chunk is closed when it would span ``chunk_seconds`` of message time or hold 1 MiB
  (rosbag's chunk size), and ``close_chunk_before`` closes it on a quiet stream too.
- The bytes the Writer produces are held in memory (``_CommitFile``) and written with one
  pwrite when a chunk is closed: the file on disk always ends after a complete chunk and its
  message indexes, so a run killed hard loses at most the open chunk, and such a file is
  read back record by record (``bag reindex``).
- The file is created exclusively (O_EXCL): an existing file is never overwritten.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, IndexType, Writer

#: chunk size cap (bytes of uncompressed records): rosbag's and rosbags' chunk threshold
CHUNK_BYTES = 1 << 20
COMPRESSIONS = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
PROFILE = "ros1"
_NS = 1_000_000_000


class McapWriteError(OSError):
    """The MCAP file could not be written (the OSError it wraps says why)."""


@dataclass(frozen=True)
class McapConnection:
    """What add_connection returns: the channel's id and what the rosbag connection holds."""

    id: int
    topic: str
    msgtype: str
    msgdef: str
    md5sum: str
    latching: bool


class _CommitFile:
    """The stream the mcap Writer writes to: bytes are kept until flush(), then written at the
    file's end with one pwrite (and fdatasync if asked). A write that fails cuts the file
    back to its last complete flush and raises McapWriteError."""

    def __init__(self, fd: int, fsync: bool) -> None:
        self._fd = fd
        self._fsync = fsync
        self._buf = bytearray()
        self.committed = 0      # bytes of the file written completely

    def write(self, data) -> int:
        self._buf += data
        return len(data)

    def tell(self) -> int:
        return self.committed + len(self._buf)

    def flush(self) -> None:
        view, pos = memoryview(self._buf), self.committed
        try:
            while view:
                n = os.pwrite(self._fd, view, pos)
                view, pos = view[n:], pos + n
            if self._fsync and self._buf:
                os.fdatasync(self._fd)
        except OSError as error:
            view.release()
            self._buf.clear()
            try:
                os.ftruncate(self._fd, self.committed)
            except OSError:
                pass
            raise McapWriteError(error.errno, error.strerror or str(error)) from error
        view.release()
        self._buf.clear()
        self.committed = pos

    def close(self) -> None:
        self._buf.clear()
        os.close(self._fd)


class McapWriter:
    """A ROS 1 MCAP file written chunk by chunk (see the module docstring).

    chunk_seconds: close a chunk before it spans this much message time (0: by size only).
    compression: "zstd", "lz4" or "none".
    fsync: fdatasync after each chunk (power loss then loses at most the open chunk too).
    """

    def __init__(self, path: Path | str, chunk_seconds: float = 1.0, compression: str = "zstd",
                 fsync: bool = False) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"MCAP compression '{compression}': use one of {', '.join(COMPRESSIONS)}")
        self.path = Path(path)
        self._chunk_ns = int(round(chunk_seconds * _NS)) if chunk_seconds > 0 else 0
        self._compression = compression
        self._fsync = fsync
        self._file: _CommitFile | None = None
        self._mcap: Writer | None = None
        self._schemas: dict[str, int] = {}
        self._sequence: dict[int, int] = {}
        self._chunk_start: int | None = None     # message time of the open chunk's first message
        self._chunk_bytes = 0
        self._chunk_messages = 0
        self.messages_written = 0                # messages in chunks that reached the file
        self.chunks_written = 0

    def open(self) -> None:
        """Create the file (never over an existing one) and write the magic and header."""
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        self._file = _CommitFile(fd, self._fsync)
        self._mcap = Writer(self._file, chunk_size=1 << 62, compression=COMPRESSIONS[self._compression],
                            index_types=IndexType.ALL, repeat_channels=True, repeat_schemas=True,
                            use_chunking=True, use_statistics=True, use_summary_offsets=True)
        try:
            self._mcap.start(profile=PROFILE, library="twil_control")
            self._file.flush()
        except OSError:
            self._file.close()
            self.path.unlink(missing_ok=True)
            raise

    def add_connection(self, topic: str, msgtype: str, *, msgdef: str, md5sum: str,
                       callerid: str | None = None, latching: int | bool | None = None) -> McapConnection:
        ros1_type = msgtype.replace("/msg/", "/")
        schema = self._schemas.get(ros1_type)
        if schema is None:
            schema = self._schemas[ros1_type] = self._mcap.register_schema(ros1_type, "ros1msg", msgdef.encode())
        metadata = {"latching": "true" if latching else "false", "md5sum": md5sum}
        if callerid:
            metadata["callerid"] = callerid
        cid = self._mcap.register_channel(topic, "ros1", schema, metadata)
        return McapConnection(cid, topic, ros1_type, msgdef, md5sum, bool(latching))

    def write(self, connection: McapConnection, timestamp: int, data) -> None:
        if self._chunk_start is not None and self._chunk_ns and timestamp - self._chunk_start >= self._chunk_ns:
            self.close_chunk()
        seq = self._sequence.get(connection.id, 0)
        self._sequence[connection.id] = seq + 1
        self._mcap.add_message(connection.id, log_time=timestamp, data=bytes(data), publish_time=timestamp,
                               sequence=seq)
        if self._chunk_start is None:
            self._chunk_start = timestamp
        self._chunk_messages += 1
        self._chunk_bytes += len(data) + 31  # the message record's own header
        if self._chunk_bytes >= CHUNK_BYTES:
            self.close_chunk()

    def close_chunk_before(self, now_ns: int) -> None:
        """Close the open chunk if it began chunk_seconds or more before now_ns (a stream with
        few messages still reaches the file every chunk_seconds)."""
        if self._chunk_start is not None and self._chunk_ns and now_ns - self._chunk_start >= self._chunk_ns:
            self.close_chunk()

    def close_chunk(self) -> None:
        """Compress the open chunk and write it, with its message indexes, to the file."""
        if self._chunk_start is None:
            return
        self._mcap.flush()   # the mcap Writer's end of chunk; its stream's flush() writes the bytes
        self.messages_written += self._chunk_messages
        self.chunks_written += 1
        self._chunk_start, self._chunk_bytes, self._chunk_messages = None, 0, 0

    def close(self) -> None:
        """Write the last chunk, the summary and the footer, and close the file."""
        if self._mcap is None:
            return
        try:
            self.close_chunk()
            self._mcap.finish()   # the data end, the summary, the footer and the magic
            self._file.flush()
        finally:
            self._mcap = None
            self._file.close()

    def abort(self) -> None:
        """Close the file without writing what is not yet written (no summary)."""
        self._mcap = None
        if self._file is not None:
            self._file.close()
