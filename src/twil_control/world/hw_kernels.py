"""Compiled inner loops of the hardware adapter's write() (numba).

write() runs every control period; over 7 joints its numpy form (a finiteness check, clamp to
the effort limits, scatter into the plant's actuation order) is five small-array calls, about
10 us, against about 1.5 us for this one compiled call (measured, bench/ros_control_bench.py).
"""
from __future__ import annotations

import math

from numba import njit


@njit(cache=True, nogil=True)
def clamp_and_scatter_efforts(cmd, limit, tau_padded, scatter, actuation, effort) -> bool:
    """Every joint commanded in effort mode: tau_i = clamp(cmd_i, -limit_i, limit_i), with a
    non-finite command replaced by zero effort; tau goes to `effort` and to the first n slots
    of `tau_padded`, and actuation[k] = tau_padded[scatter[k]] (the padding slot stays zero for
    actuators this adapter does not drive). Returns False when a command was non-finite (the
    caller logs it)."""
    finite = True
    for i in range(cmd.shape[0]):
        c = cmd[i]
        if not math.isfinite(c):
            finite = False
            c = 0.0
        lim = limit[i]
        if c > lim:
            c = lim
        elif c < -lim:
            c = -lim
        tau_padded[i] = c
        effort[i] = c
    for k in range(actuation.shape[0]):
        actuation[k] = tau_padded[scatter[k]]
    return finite
