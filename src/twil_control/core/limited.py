"""A user's file processed by a library in a child process, with a memory and a time limit.

xacro and mesh conversion can be made to take a whole machine, and the kernel's OOM killer then
acts on the machine, not on the culprit. So they run in a child interpreter with RLIMIT_AS and
RLIMIT_CPU capped and a wall-clock timeout beside; going past one is a LimitError naming the file
and the option that raises the limit. The function runs by its name, so callers in any layer
hand theirs down (docs/runtime.md).
"""

from __future__ import annotations

import importlib
import math
import os
import pickle
import resource
import signal
import subprocess
import sys
from dataclasses import dataclass
from typing import Any

from ..errors import TwilControlError


@dataclass
class Limits:
    memory: int = 2 << 30  # bytes of address space of the child (RLIMIT_AS)
    seconds: float = 60.0  # CPU and wall seconds of the child
    mesh_bytes: int = 128 << 20  # a mesh file larger than this is refused before it is read
    mesh_triangles: int = 2_000_000  # non-degenerate triangles of one mesh


#: the limits in force (the launch's command line sets them)
LIMITS = Limits()


class LimitError(TwilControlError):
    """A child process that went past its memory or time limit; the message says which file."""

    def __init__(self, text: str, last_note: str | None = None) -> None:
        super().__init__(text)
        self.last_note = last_note


def size_text(n: int) -> str:
    for unit, scale in (("G", 1 << 30), ("M", 1 << 20), ("k", 1 << 10)):
        if n >= scale and n % scale == 0:
            return f"{n // scale}{unit}"
    return f"{n} bytes"


def call(function: str, args: tuple, what: str, limits: Limits | None = None) -> Any:
    """function(*args) run in a child process under the limits; its return value, or the
    exception it raised (raised again here), or LimitError naming `what` (e.g. ``xacro FILE``)."""
    limits = limits or LIMITS
    payload = pickle.dumps((function, args, limits.memory, limits.seconds))
    env = dict(os.environ)
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        env[name] = "1"  # thread pools reserve address space the limit would count
    memory = (
        f"{what}: needed more than {size_text(limits.memory)} of memory, the limit of the child "
        "process that reads it; raise it with --convert-memory SIZE"
    )
    took = (
        f"{what}: took more than {limits.seconds:g} s, the limit of the child process that reads "
        "it; raise it with --convert-time SECONDS"
    )
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "twil_control.core.limited"],
            input=payload,
            capture_output=True,
            timeout=limits.seconds + 5,
            env=env,
        )
    except subprocess.TimeoutExpired as error:
        raise LimitError(took, _last_note(error.stderr)) from None
    note = _last_note(proc.stderr)
    if proc.returncode == 0:
        try:
            kind, value = pickle.loads(proc.stdout)
        except Exception:  # the child wrote something else: report what it said
            kind, value = "crash", None
        if kind == "ok":
            _pass_on(proc.stderr)  # what the library said (xacro's warnings) reaches the user
            return value
        if kind == "error":
            assert isinstance(value, BaseException)  # what the child's error was pickled from
            raise value
        if kind == "memory":
            raise LimitError(memory, note)
    if proc.returncode in (-signal.SIGXCPU, -signal.SIGKILL):
        raise LimitError(took, note)
    said = proc.stderr.decode(errors="replace").strip().splitlines()
    tail = next((line for line in reversed(said) if not line.startswith(NOTE)), "")
    if "MemoryError" in tail or proc.returncode in (-signal.SIGSEGV, -signal.SIGABRT):
        raise LimitError(memory, note)  # out of memory where Python could not raise MemoryError
    raise LimitError(
        f"{what}: the child process that reads it ended with code {proc.returncode}: {tail}", note
    )


NOTE = "twil_control.limited: "


def note(text: str) -> None:
    """From the child: what it is working on, for the parent's error if it is stopped."""
    sys.stderr.write(f"{NOTE}{text}\n")
    sys.stderr.flush()


def _pass_on(stderr: bytes) -> None:
    text = "".join(
        line for line in stderr.decode(errors="replace").splitlines(True) if not line.startswith(NOTE)
    )
    if text:
        sys.stderr.write(text)


def _last_note(stderr: bytes | None) -> str | None:
    lines = (stderr or b"").decode(errors="replace").splitlines()
    return next((line[len(NOTE) :] for line in reversed(lines) if line.startswith(NOTE)), None)


def _is_memory(error: BaseException | None) -> bool:
    seen = 0
    while error is not None and seen < 20:
        if isinstance(error, MemoryError) or isinstance(getattr(error, "exc", None), MemoryError):
            return True
        error = error.__cause__ or error.__context__
        seen += 1
    return False


def _lower(which: int, soft: int, hard: int) -> None:
    """Set a limit, never above the one this process was given (a shell's ulimit stays in force)."""
    _, given = resource.getrlimit(which)
    if given != resource.RLIM_INFINITY:
        hard = min(hard, given)
        soft = min(soft, hard)
    resource.setrlimit(which, (soft, hard))


def _child() -> None:
    function, args, memory, seconds = pickle.load(sys.stdin.buffer)
    result_stream = sys.stdout.buffer
    sys.stdout = sys.stderr  # what the library prints must not mix with the result
    cpu = max(1, math.ceil(seconds))
    _lower(resource.RLIMIT_AS, memory, memory)
    _lower(resource.RLIMIT_CPU, cpu, cpu + 1)
    try:
        module, name = function.split(":")
        out = ("ok", getattr(importlib.import_module(module), name)(*args))
    except MemoryError:
        out = ("memory", None)
    except Exception as error:
        out = ("memory", None) if _is_memory(error) else ("error", error)
    try:
        data = pickle.dumps(out)
    except Exception:  # an exception that does not pickle: its text
        data = pickle.dumps(("error", RuntimeError(f"{type(out[1]).__name__}: {out[1]}")))
    result_stream.write(data)
    result_stream.flush()


if __name__ == "__main__":
    _child()
