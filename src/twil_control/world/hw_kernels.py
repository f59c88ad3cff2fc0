"""The hardware adapter's write(), compiled (numba): every mode's efforts go through the last
step, and the velocity and position modes of implicit-PD joints through one call before it.

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


@njit(cache=True, nogil=True)
def implicit_commands(mode, implicit, active_modes, commands, position, velocity, tau, desired_state, driven):
    """The velocity / position modes without a PID, and the effort mode, for one write():
    tau_i = the effort command of a joint in effort mode, 0 otherwise; an implicit-PD joint's
    desired state is (q_i, v_i) idle or in effort mode, (q_i, velocity command) in velocity
    mode, (position command, 0) in position mode (every other joint's: (q_i, v_i), which the
    plant ignores), written to desired_state's slots driven[i]
    (positions) and n + driven[i] (velocities, n = len(desired_state) / 2). A joint whose own
    command is not finite gets zero effort and an idle desired state. `commands` (3, joints)
    holds the effort, velocity and position commands; joints in velocity or position mode that
    are not implicit (the PID joints) are left to the caller. Returns False when an active
    mode's command array (active_modes[m] != 0) holds a non-finite value, as write() reports
    them."""
    finite = True
    for m in range(3):
        if active_modes[m]:
            for i in range(commands.shape[1]):
                if not math.isfinite(commands[m, i]):
                    finite = False
    n = desired_state.shape[0] // 2
    for i in range(mode.shape[0]):
        code = mode[i]
        cmd = commands[code - 1, i] if code > 0 else 0.0
        ok = code > 0 and math.isfinite(cmd)
        tau[i] = cmd if (code == 1 and ok) else 0.0
        q, v = position[i], velocity[i]
        if implicit[i] and ok and code == 2:
            v = cmd
        elif implicit[i] and ok and code == 3:
            q, v = cmd, 0.0
        desired_state[driven[i]] = q
        desired_state[n + driven[i]] = v
    return finite
