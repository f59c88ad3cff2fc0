"""Writing MCAP files for ROS 1 (the MCAP "ros1" profile), with the recorder's safety rules.

The `mcap` package's Writer does the format; this module gives it the rosbag writer's interface
the recorder drives, channels that are ROS 1 connections (so a bag converted to MCAP and back has
the same connection records), chunks capped in time and written whole through a ``ChunkFile``,
no summary after a failed write (``bag reindex`` recovers the complete chunks), and an exclusive
create: an existing file is never overwritten (docs/mcap.md, docs/bags.md).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from mcap.writer import CompressionType, IndexType, Writer

from twil_control.errors import InputError

from .chunk_file import BagWriteError, ChunkFile, describe

#: chunk size cap (bytes of uncompressed records): rosbag's and rosbags' chunk threshold
CHUNK_BYTES = 1 << 20
COMPRESSIONS = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
PROFILE = "ros1"
_NS = 1_000_000_000


@dataclass(frozen=True)
class McapConnection:
    """What add_connection returns: the channel's id and what the rosbag connection holds."""

    id: int
    topic: str
    msgtype: str
    msgdef: str
    md5sum: str
    latching: bool


class McapWriter:
    """A ROS 1 MCAP file written chunk by chunk (see the module docstring).

    chunk_seconds: close a chunk before it spans this much message time (0: by size only).
    compression: "zstd", "lz4" or "none".
    fsync: fdatasync after each chunk, in a thread (a power loss then loses about the open
    chunk and the sync in progress).
    """

    def __init__(
        self, path: Path | str, chunk_seconds: float = 1.0, compression: str = "zstd", fsync: bool = False
    ) -> None:
        if compression not in COMPRESSIONS:
            raise InputError(f"MCAP compression '{compression}': use one of {', '.join(COMPRESSIONS)}")
        self.path = Path(path)
        self._chunk_ns = int(round(chunk_seconds * _NS)) if chunk_seconds > 0 else 0
        self._compression = compression
        self._fsync = fsync
        self._file: ChunkFile | None = None
        self._mcap: Writer | None = None
        self._schemas: dict[str, int] = {}
        self._sequence: dict[int, int] = {}
        self._chunk_start: int | None = None  # message time of the open chunk's first message
        self._chunk_bytes = 0
        self._chunk_messages = 0
        self.messages_written = 0  # messages in chunks that reached the file
        self.chunks_written = 0
        self._failed: BagWriteError | None = None

    def open(self) -> None:
        """Create the file (never over an existing one) and write the magic and header."""
        try:
            fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            raise
        except OSError as error:
            raise BagWriteError(error.errno, describe(error)) from error
        self._file = ChunkFile(fd, self._fsync)
        self._mcap = Writer(
            self._file,
            chunk_size=1 << 62,
            compression=COMPRESSIONS[self._compression],
            index_types=IndexType.ALL,
            repeat_channels=True,
            repeat_schemas=True,
            use_chunking=True,
            use_statistics=True,
            use_summary_offsets=True,
            enable_data_crcs=True,  # bag info checks the whole file without decompressing it
        )
        try:
            self._mcap.start(profile=PROFILE, library="twil_control")
            self._file.commit()
        except BagWriteError:
            self._file.discard()
            self.path.unlink(missing_ok=True)
            raise

    def add_connection(
        self,
        topic: str,
        msgtype: str,
        *,
        msgdef: str,
        md5sum: str,
        callerid: str | None = None,
        latching: int | bool | None = None,
    ) -> McapConnection:
        ros1_type = msgtype.replace("/msg/", "/")
        schema = self._schemas.get(ros1_type)
        if schema is None:
            schema = self._schemas[ros1_type] = self._mcap.register_schema(
                ros1_type, "ros1msg", msgdef.encode()
            )
        metadata = {"latching": "true" if latching else "false", "md5sum": md5sum}
        if callerid:
            metadata["callerid"] = callerid
        cid = self._mcap.register_channel(topic, "ros1", schema, metadata)
        return McapConnection(cid, topic, ros1_type, msgdef, md5sum, bool(latching))

    def write(self, connection: McapConnection, timestamp: int, data) -> None:
        if (
            self._chunk_start is not None
            and self._chunk_ns
            and timestamp - self._chunk_start >= self._chunk_ns
        ):
            self.close_chunk()
        seq = self._sequence.get(connection.id, 0)
        self._sequence[connection.id] = seq + 1
        self._mcap.add_message(
            connection.id, log_time=timestamp, data=bytes(data), publish_time=timestamp, sequence=seq
        )
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
        try:
            self._mcap.flush()  # the mcap Writer's end of chunk; its stream's flush() writes the bytes
        except BagWriteError as error:
            self._failed = error
            raise
        self.messages_written += self._chunk_messages
        self.chunks_written += 1
        self._chunk_start, self._chunk_bytes, self._chunk_messages = None, 0, 0

    def close(self) -> None:
        """Write the last chunk, the summary and the footer, and close the file. After a write
        that failed, the file is closed without a summary and BagWriteError is raised."""
        if self._mcap is None:
            return
        try:
            if self._failed is not None:
                raise BagWriteError(self._failed.errno, f"{self._failed.strerror}; no summary written")
            self.close_chunk()
            self._mcap.finish()  # the data end, the summary, the footer and the magic
            self._file.commit()
        finally:
            self._mcap = None
            self._file.discard()

    def abort(self) -> None:
        """Close the file without writing what is not yet written (no summary)."""
        self._mcap = None
        if self._file is not None:
            self._file.discard()
