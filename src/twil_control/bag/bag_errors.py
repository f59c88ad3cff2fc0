"""The one exception type of the bag tools: a sentence naming the problem and what to do.

The command line prints it as one line and exits with code 2 (bad input); the Python API
raises it. Near misses get a "did you mean".
"""

from __future__ import annotations

import difflib

from twil_control.errors import TwilControlError


class BagError(TwilControlError):
    """A bag, topic, field or option the bag tools cannot use; the message says why."""


class UnindexedBagError(BagError):
    """A bag without a usable index (a recorder's .active file, a truncated copy)."""

    def __init__(
        self, path, valid_end: int, size: int, chunks: int, messages: int, reason: str, cut: bool = False
    ) -> None:
        self.path, self.valid_end, self.size = path, valid_end, size
        self.chunks, self.messages = chunks, messages
        where = (
            f"truncated at byte {size}, inside a record that starts at byte {valid_end}"
            if cut
            else f"unindexed; its records are complete up to byte {valid_end} of {size}"
        )
        super().__init__(
            f"{path}: bag has no index ({reason}; {where}; {messages} complete messages in "
            f"{chunks} complete chunks{' and the cut one' if cut else ''} are recoverable); recover "
            f"it with: python -m twil_control.bag reindex {path} -o FIXED.bag"
        )


def did_you_mean(name: str, choices, n: int = 3) -> str:
    """' (did you mean X?)' for near misses of name among choices, else ''."""
    close = difflib.get_close_matches(name, list(choices), n=n, cutoff=0.6)
    return f" (did you mean {' or '.join(close)}?)" if close else ""


def listing(choices, limit: int = 40) -> str:
    """A comma-separated list, shortened after `limit` entries."""
    choices = list(choices)
    text = ", ".join(choices[:limit])
    return text + (f", ... ({len(choices) - limit} more)" if len(choices) > limit else "")


def size_text(n: float) -> str:
    """Bytes as rosbag info prints sizes: '148.9 KB', '1.0 GB' (units of 1024)."""
    for unit in ("B", "KB", "MB", "GB", "TB"):
        if n < 1024 or unit == "TB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return ""
