"""Files the bag tools write are new files: an existing one is refused unless forced.

The check is made before the work (a clear error, nothing computed in vain) and again when
the file is created: ``open_new`` opens with O_EXCL and ``link_new`` names a finished file by
a hard link, both failing if the name appeared in between, where a plain open or rename would
replace it. ``written_beside`` has a file written under a temporary name and named at the end,
so a failed command leaves nothing, and ``--force`` replaces the old file only by a complete
new one.
"""

from __future__ import annotations

import os
import shutil
import signal
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

from .bag_errors import BagError


def check_new_output(path: Path, what: str, force: bool = False) -> Path:
    """Refuse an existing path (unless force) or a missing folder, naming the option."""
    path = Path(path)
    if not force and (path.exists() or path.is_symlink()):
        raise BagError(
            f"{what} {path} exists; it is never overwritten: choose another name, or "
            "add --force to replace it"
        )
    if not path.parent.is_dir():
        raise BagError(f"{what} {path}: folder {path.parent} does not exist")
    return path


def open_new(path: Path, force: bool = False, mode: str = "wb"):
    """Open a file for writing that must not exist (unless force), atomically checked."""
    try:
        return open(
            path, mode if force else mode.replace("w", "x"), encoding=None if "b" in mode else "utf-8"
        )
    except FileExistsError:
        raise BagError(
            f"{path} appeared meanwhile; it is never overwritten: choose another name, "
            "or add --force to replace it"
        ) from None


def link_new(src: Path, dst: Path) -> None:
    """Give the file src the name dst, failing (FileExistsError) if dst exists: a hard link
    then unlink; on a filesystem without hard links, a check and a rename."""
    try:
        os.link(src, dst)
    except FileExistsError:
        raise
    except OSError:
        if dst.exists() or dst.is_symlink():
            raise FileExistsError(17, "File exists", str(dst)) from None
        os.rename(src, dst)
        return
    os.unlink(src)


@contextmanager
def signals_held():
    """SIGINT, SIGTERM and SIGHUP that arrive inside the block are delivered when it ends: a
    temporary made there is always known to the code that removes it (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    stops = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
    previous = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in stops}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if caught:
            signal.raise_signal(caught[0])


@contextmanager
def written_beside(out: Path, force: bool = False):
    """Yield a temporary path beside `out` to write; when the block ends without error, name it
    `out` (never replacing a file that appeared meanwhile, unless force); else remove it, also
    when a signal stops the command (bag/__main__.py turns SIGTERM and SIGHUP into exceptions)."""
    with folder_beside(out) as tmp:
        part = tmp / out.name
        yield part
        if force:
            os.replace(part, out)
            return
        try:
            link_new(part, out)
        except FileExistsError:
            raise BagError(
                f"{out} appeared meanwhile; it is never overwritten: choose another name, "
                "or add --force to replace it"
            ) from None


@contextmanager
def folder_beside(out: Path):
    """A new hidden folder beside `out` (``.NAME.xxxx``), removed with what it holds when the
    block ends, however it ends: made and removed with the stop signals held."""
    tmp = None
    try:
        with signals_held():
            tmp = tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.")
        yield Path(tmp)
    finally:
        if tmp is not None:
            with signals_held():
                shutil.rmtree(tmp, ignore_errors=True)
