"""launch/allocator.py: after keep_freed_memory(), memory a process frees is used again without
page faults (glibc keeps the heap's top instead of trimming it); with glibc's defaults the same
churn faults every page in again. Each case runs in a fresh interpreter."""

from __future__ import annotations

import subprocess
import sys

import pytest

CHURN = """
import resource, sys
from twil_control.launch.allocator import keep_freed_memory
if sys.argv[1] == "keep":
    assert keep_freed_memory()
def churn():  # 100 MB in blocks that malloc serves (above pymalloc's 512 bytes)
    blocks = [bytes(2000) for _ in range(50_000)]
    del blocks
churn()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
churn()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(mode: str) -> int:
    done = subprocess.run([sys.executable, "-c", CHURN, mode], capture_output=True, text=True, check=True)
    return int(done.stdout)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_freed_memory_is_reused_without_page_faults():
    pages = 100_000_000 // 4096
    assert _faults("default") > 0.5 * pages  # glibc's defaults give the 100 MB back, then fault it in
    assert _faults("keep") < 0.01 * pages
