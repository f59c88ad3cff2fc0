"""The hardware adapter's write() last step, compiled (numba): every mode's efforts go through it.

write() runs every control period; over 7 joints a numpy form (a finiteness check, clamp to the
effort limits, scatter into the plant's actuation order) is five small-array calls, each costing
more in call overhead than this one compiled call in all.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, nogil=True)
def clamp_and_scatter_efforts(cmd, limit, tau_padded, scatter, actuation, effort) -> bool:
    """tau_i = clamp(cmd_i, -limit_i, limit_i) for each joint's effort `cmd_i` (0 for an idle
    joint), with a non-finite one replaced by zero effort; tau goes to `effort` and to the first
    n slots of `tau_padded` (`cmd` may be those slots), and actuation[k] = tau_padded[scatter[k]]
    (the padding slot stays zero for actuators this adapter does not drive). Returns False when
    an effort was non-finite (the caller logs it)."""
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
