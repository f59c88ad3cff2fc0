"""Ctrl-C (or SIGTERM, SIGHUP) while a launch starts (imports, launch file, diagram build),
before time runs.

Python's own SIGINT handler raises KeyboardInterrupt anywhere, and inside a compiled module's
import, Python code that pybind11 runs, or numba's compilation that turns into a broken import,
a process that kills itself, or a lost Ctrl-C. This handler raises there only once those places
are left, sending the signal again a moment later (docs/bags.md). Once time runs the runner's own
handler takes over.
"""

from __future__ import annotations

import os
import signal
import threading

#: Signals that end a run the way Ctrl-C does (roslaunch's too): time stops, nodes shut down,
#: the bag is closed. SIGTERM comes from timeout, systemd, docker stop; SIGHUP from a closed
#: terminal.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

#: Seconds between looks at whether the import that deferred a Ctrl-C is over.
RETRY = 0.02

_retry: threading.Timer | None = None  # a retry that has not sent its signal yet


#: Folders of the JIT's code: a signal that comes while it compiles waits until it is done
_JIT = tuple(f"{os.sep}{package}{os.sep}" for package in ("numba", "llvmlite"))


def _not_here(frame) -> bool:
    """Inside an import, inside code run by exec/eval from within the program (a "<string>"
    frame with a caller; the bottom frame of `python -c` is one without), or inside numba or
    llvmlite (JIT compilation, whose callbacks from C cannot raise)."""
    while frame is not None:
        name = frame.f_code.co_filename
        if name.startswith("<frozen importlib") or (name == "<string>" and frame.f_back is not None):
            return True
        if any(part in name for part in _JIT):
            return True
        frame = frame.f_back
    return False


class StopSignal(KeyboardInterrupt):
    """A stop signal arrived before time started; `signum` says which."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _send_again(signum: int) -> None:
    global _retry
    _retry = None
    os.kill(os.getpid(), signum)


def on_stop_while_starting(signum, frame) -> None:
    global _retry
    if _not_here(frame):
        if _retry is None:  # one deferred signal at a time
            _retry = threading.Timer(RETRY, _send_again, (signum,))
            _retry.daemon = True
            _retry.start()
        return
    if _retry is not None:  # honoured now, not once more later
        _retry.cancel()
        _retry = None
    raise StopSignal(signum)
