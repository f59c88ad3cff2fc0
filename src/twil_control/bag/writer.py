"""The project's ROS bag writer: rosbags' Writer with chunks capped in time, written whole.

rosbags' Writer (ROS bag 2.0) is kept, with two things a recorder that may be killed or run out of
disk needs: a chunk closes once it would span ``chunk_seconds`` of message time (or 1 MiB), on a
quiet stream too, so a recording killed hard loses at most the open chunk; and it writes to a
``ChunkFile``, so a failed write cuts the file back to its last complete chunk and the index can
still be written after them (docs/bags.md).
"""

from __future__ import annotations

import struct
from pathlib import Path

from rosbags.rosbag1 import Writer

from .chunk_file import BagWriteError, ChunkFile, describe

#: rosbags' chunk size threshold (bytes of uncompressed messages), kept as the size cap.
CHUNK_BYTES = 1 << 20

_NS = 1_000_000_000

#: a message data record up to its data, as rosbags' Header writes it: the header's length (38),
#: op=2 (MSGDATA), conn=<uint32>, time=<sec, nsec>, then the data's length
_MSGDATA = struct.Struct("<L L3sB L5sL L5sLL L")


class ChunkedWriter(Writer):
    """rosbags' Writer with time-capped chunks written whole (see the module docstring).

    chunk_seconds: close a chunk before it spans this much message time (0: by size only).
    fsync: fdatasync after each chunk, in a thread (a power loss then loses about the open
    chunk and the sync in progress).
    """

    def __init__(self, path: Path | str, chunk_seconds: float = 1.0, fsync: bool = False) -> None:
        super().__init__(path)
        self.chunk_threshold = CHUNK_BYTES
        self._chunk_ns = int(round(chunk_seconds * _NS)) if chunk_seconds > 0 else 0
        self._fsync = fsync
        self.messages_written = 0  # messages in chunks that reached the file
        self._known: set[int] = set()  # ids of the connections added
        self.chunks_written = 0

    def open(self) -> None:
        """Create the file (never over an existing one) and write the bag header; if that
        fails, no file is left behind."""
        try:
            super().open()
            self.bio = ChunkFile(self.bio, self._fsync)
        except OSError as error:
            if self.bio is not None:  # created (rosbags opens it before writing the header)
                try:
                    self.bio.close()
                except OSError:
                    pass
                self.bio = None
                self.path.unlink(missing_ok=True)
            raise BagWriteError(error.errno, describe(error)) from error

    def add_connection(self, *args, **kwargs):
        connection = super().add_connection(*args, **kwargs)
        self._known.add(id(connection))  # held in self.connections: its id stays its own
        return connection

    def write(self, connection, timestamp: int, data) -> None:
        """rosbags' Writer.write, the same bytes, with the record packed by one struct (rosbags
        builds a header dict per message and looks the connection up by equality)."""
        chunk = self.chunks[-1]
        if self._chunk_ns and chunk.connections and timestamp - chunk.start >= self._chunk_ns:
            self.write_chunk(chunk)
            chunk = self.chunks[-1]
        if not self.bio or id(connection) not in self._known:
            super().write(connection, timestamp, data)  # its checks and errors
            return
        bio = chunk.data
        chunk.connections[connection.id].append((timestamp, bio.tell()))
        chunk.start = min(timestamp, chunk.start)
        chunk.end = max(timestamp, chunk.end)
        sec, nsec = divmod(timestamp, _NS)
        bio.write(
            _MSGDATA.pack(38, 4, b"op=", 2, 9, b"conn=", connection.id, 13, b"time=", sec, nsec, len(data))
        )
        bio.write(data)
        if bio.tell() > self.chunk_threshold:
            self.write_chunk(chunk)

    def close_chunk_before(self, now_ns: int) -> None:
        """Close the open chunk if it began chunk_seconds or more before now_ns (a stream with
        few messages still reaches the file every chunk_seconds)."""
        chunk = self.chunks[-1]
        if self._chunk_ns and chunk.connections and now_ns - chunk.start >= self._chunk_ns:
            self.write_chunk(chunk)

    def write_chunk(self, chunk) -> None:
        """rosbags writes the chunk and its index data into the ChunkFile; commit writes them.
        A chunk that could not be written is forgotten, so the index never points at it."""
        super().write_chunk(chunk)
        if chunk.pos == -1:  # an empty chunk: nothing was written
            return
        try:
            self.bio.commit()
        except BagWriteError:
            self.chunks.remove(chunk)
            raise
        self.messages_written += sum(len(v) for v in chunk.connections.values())
        self.chunks_written += 1

    def open_chunk_messages(self) -> int:
        return sum(len(v) for v in self.chunks[-1].connections.values())

    def close(self) -> None:
        """Write the last chunk and the index. If that fails the file keeps its complete chunks
        (unindexed: reindex recovers them) and BagWriteError is raised."""
        try:
            super().close()
        except BagWriteError:
            self.abort()
            raise

    def abort(self) -> None:
        """Close the file without writing what is not yet committed (no index)."""
        bio, self.bio = self.bio, None
        if bio is not None:
            bio.discard()
