"""glibc's allocator told to keep the memory a run frees, instead of handing it back to the
kernel and faulting it in again moments later.

A running launch frees and re-allocates the same few megabytes at every step and timer (Drake's
contact solver, costmaps, scans); with glibc's defaults the heap's top is trimmed as soon as
128 KiB of it is free, so each regrowth costs page faults (some 40,000 a simulated second in a
BARN episode, a tenth of its CPU time). A high trim threshold keeps those pages; the process's
memory stays at its high-water mark, as rosbag's and Gazebo's own processes do.
"""

from __future__ import annotations

import ctypes
import sys

M_TRIM_THRESHOLD = -1  # glibc's mallopt parameters (malloc.h)
M_TOP_PAD = -2
TRIM_THRESHOLD = 256 << 20  # bytes free at the heap's top before it is given back
TOP_PAD = 64 << 20  # bytes the heap grows by beyond a request (address space, not memory)


def keep_freed_memory() -> bool:
    """Set the thresholds on glibc (Linux); False (and nothing changed) elsewhere."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt  # musl has none: AttributeError
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    return bool(mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD)) and bool(mallopt(M_TOP_PAD, TOP_PAD))
