"""The one way a control law's input is turned into a number before it is checked."""

from __future__ import annotations

import math


def as_float(value) -> float:
    """``float(value)``; NaN for what is not a number (None, a word, a list), so that the caller's
    finiteness or range check refuses it with its own message."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan
