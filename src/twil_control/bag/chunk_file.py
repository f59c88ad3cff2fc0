"""A bag file written a chunk at a time: what the recorder's writers (ROS bag and MCAP) write to.

A chunk's bytes are kept in memory and written with one ``pwrite`` when it is closed, so the file
always ends after a complete chunk: a process killed hard loses only the chunk it was filling.
With ``fsync`` an ``fdatasync`` follows in a thread of its own, so the simulation never waits for
the disk. A write that fails cuts the file back to its last complete chunk and raises
``BagWriteError``, and the writer can still try to write its index after them (docs/bags.md).
"""

from __future__ import annotations

import errno
import os
import threading

from twil_control.errors import TwilControlError


class BagWriteError(TwilControlError, OSError):
    """The bag file could not be written (the OSError it wraps says why)."""


def describe(error: OSError) -> str:
    """'disk full' / 'file size limit reached' / the OS's own words."""
    if error.errno == errno.ENOSPC:
        return "disk full (ENOSPC)"
    if error.errno == errno.EDQUOT:
        return "disk quota exceeded (EDQUOT)"
    if error.errno == errno.EFBIG:
        return "file size limit reached (EFBIG)"
    return error.strerror or str(error)


class _Syncer:
    """fdatasync of the bag file in a thread of its own, so the simulation never waits for the
    disk: after each chunk one is asked for; while one runs, the chunks written meanwhile are
    covered by the next. An error is kept for the writer to raise at its next chunk."""

    def __init__(self, fd: int) -> None:
        self._fd = fd
        self._cond = threading.Condition()
        self._wanted = self._closing = False
        self.error: OSError | None = None
        self._thread = threading.Thread(target=self._run, name="bag fdatasync", daemon=True)
        self._thread.start()

    def request(self) -> None:
        with self._cond:
            self._wanted = True
            self._cond.notify()

    def _run(self) -> None:
        while True:
            with self._cond:
                while not (self._wanted or self._closing):
                    self._cond.wait()
                if not self._wanted:
                    return
                self._wanted = False
            try:
                os.fdatasync(self._fd)
            except OSError as error:
                self.error = error

    def close(self) -> None:
        """Wait for the syncs asked for (the file's last data is on the disk after this)."""
        with self._cond:
            self._closing = True
            self._cond.notify()
        self._thread.join()


class ChunkFile:
    """What a writer writes to: write() and tell() as a file's, but the bytes are kept until
    commit() (or flush()), which writes them at once. seek() commits first (rosbags' Writer
    seeks only to rewrite the bag header at close).

    raw: an open file (its buffer is flushed, its position is where writing goes on; it is
    closed with this) or a file descriptor (written from its start)."""

    def __init__(self, raw, fsync: bool = False) -> None:
        if isinstance(raw, int):
            self._raw, self._fd, self._pos = None, raw, 0
        else:
            raw.flush()
            self._raw, self._fd, self._pos = raw, raw.fileno(), raw.tell()
        self._buf = bytearray()  # bytes from self._pos on, not yet written
        self._syncer = _Syncer(self._fd) if fsync else None
        self.committed = self._pos  # bytes of the file written completely

    def write(self, data) -> int:
        self._buf += data
        return len(data)

    def tell(self) -> int:
        return self._pos + len(self._buf)

    def seek(self, pos: int) -> int:
        self.commit()
        self._pos = pos
        return pos

    def commit(self) -> None:
        """Write the buffered bytes; on failure cut an append back to the last commit."""
        done = 0
        try:
            if self._syncer is not None and self._syncer.error is not None:
                raise self._syncer.error
            with memoryview(self._buf) as data:
                while done < len(data):
                    done += os.pwrite(self._fd, data[done:], self._pos + done)
        except OSError as error:
            if self._pos == self.committed:  # an append: drop its written part
                try:
                    os.ftruncate(self._fd, self.committed)
                except OSError:
                    pass
            self._buf = bytearray()  # a new one: a view of the old may live in the traceback
            raise BagWriteError(error.errno, describe(error)) from error
        self._buf = bytearray()
        self._pos += done
        self.committed = max(self.committed, self._pos)
        if done and self._syncer is not None:
            self._syncer.request()

    def flush(self) -> None:
        self.commit()

    def close(self) -> None:
        try:
            self.commit()
        finally:
            self.discard()

    def discard(self) -> None:
        """Close without writing what is buffered (waiting for a sync that runs). Safe to call
        twice."""
        self._buf = bytearray()
        if self._syncer is not None:
            self._syncer.close()
            self._syncer = None
        if self._fd is None:
            return
        if self._raw is not None:
            self._raw.close()
        else:
            os.close(self._fd)
        self._fd = None
