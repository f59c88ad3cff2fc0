"""The sweep's progress line: done/total, failed, running, elapsed and ETA.

Shown only on a terminal and not under CI, like the launch CLI's progress line, so that logs
stay clean.
"""

from __future__ import annotations

import os
import sys
import time
from typing import TextIO


def progress_wanted(stream: TextIO = sys.stderr) -> bool:
    return stream.isatty() and not os.environ.get("CI")


class ProgressLine:
    def __init__(self, total: int, already: int, enabled: bool, stream: TextIO = sys.stderr):
        self.total, self.already = total, already  # runs in the sweep, done before this start
        self.enabled, self.stream = enabled, stream
        self.start = time.monotonic()
        self.shown = False

    def text(self, done: int, failed: int, running: int) -> str:
        """``done`` counts runs finished in this invocation (the ETA is extrapolated from them)."""
        elapsed = time.monotonic() - self.start
        remaining = self.total - self.already - done
        eta = f"{elapsed / done * remaining:.0f} s" if done else "?"
        return (
            f"sweep: {self.already + done}/{self.total} done, {failed} failed, "
            f"{running} running, {elapsed:.0f} s elapsed, ETA {eta}"
        )

    def update(self, done: int, failed: int, running: int) -> None:
        if self.enabled:
            self.stream.write("\r" + self.text(done, failed, running) + "\x1b[K")
            self.stream.flush()
            self.shown = True

    def close(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()
            self.shown = False
