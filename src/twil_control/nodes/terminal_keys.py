"""Key presses from the launch's terminal, for the keyboard teleop nodes.

Every node runs in the launch's process, so a keyboard teleop reads the terminal the launch
was started from, as teleop_twist_keyboard reads its own under roslaunch. The terminal is put
in cbreak mode (keys arrive one by one, unechoed, Ctrl-C still ends the launch) while a
reader is open, and restored when it closes or the process exits. Reading never blocks: the
keys typed since the last call, in order. Without a terminal on stdin (a pipe, /dev/null,
CI) nothing is read and the caller says so once.
"""

from __future__ import annotations

import atexit
import os
import select
import sys


class TerminalKeys:
    def __init__(self, stream=None) -> None:
        self.stream = stream if stream is not None else sys.stdin
        self._saved = None
        try:
            self.fd = self.stream.fileno()
            self.available = os.isatty(self.fd)
        except (AttributeError, OSError, ValueError):
            self.fd, self.available = -1, False
        if self.available:
            import termios
            import tty

            self._saved = termios.tcgetattr(self.fd)
            tty.setcbreak(self.fd)
            atexit.register(self.close)

    def read(self) -> str:
        """The keys typed since the last call ("" when none)."""
        if not self.available:
            return ""
        keys = []
        while select.select([self.fd], [], [], 0.0)[0]:
            data = os.read(self.fd, 64)
            if not data:
                break
            keys.append(data.decode(errors="replace"))
        return "".join(keys)

    def close(self) -> None:
        if self._saved is not None:
            import termios

            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
            self._saved = None
