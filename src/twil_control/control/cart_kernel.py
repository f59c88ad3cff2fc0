"""The cart controller's 1 kHz update: the paper's equations composed into one compiled call (numba).

`cart_step` is the whole update (the steps of docs/cart_controller.md), each step the one
implementation of its equation that the Python API calls too (docs/formulas.md). One call
because each call from Python costs about a microsecond and the update has a millisecond;
tests/test_cart_kernel.py checks the composition against the equations, with Drake's dynamics
as the oracle. The arrays' layout is in `cart_step`'s docstring.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import rigid_body_kernel as rbk
from .backstepping import command
from .computed_torque import commanded_acceleration
from .diff_odometry import ODO_HEADING, ODO_SIZE, ODO_X, ODO_Y, odometry_step
from .platform_model import (
    constants,
    feedback_linearization,
    planar_mass_properties,
    saturate_pair,
    wheel_velocities_to_body,
)
from .trajectory import held_reference

__all__ = [
    "IN_POSE",
    "IN_POSE_REF",
    "IN_AGE",
    "IN_PLANAR",
    "IN_SIZE",
    "ODO_SIZE",
    "OUT_V",
    "OUT_TAU",
    "OUT_TAU_RAW",
    "OUT_SCALE",
    "OUT_K",
    "OUT_U",
    "OUT_REF",
    "out_size",
    "step_params",
    "step_index",
    "planar_state",
    "cart_step",
]

IN_POSE, IN_POSE_REF, IN_AGE, IN_PLANAR = 0, 3, 6, 7
IN_SIZE = 8
OUT_V, OUT_TAU, OUT_TAU_RAW, OUT_SCALE, OUT_K, OUT_U, OUT_REF = 0, 2, 4, 6, 7, 11, 13
# params: r, b, wheel spin inertia, wheel effort limit, goal tolerance, reference timeout, the law
# (backstepping.CORRECTED / PRINTED), 1 to derive K5..K8 from M or 0 to use the given ones, the
# given K5..K8, the nine gains (control.gains order), then kp (n) and kd (n)
P_R, P_B, P_IW, P_LIMIT, P_TOL, P_TIMEOUT, P_LAW, P_DERIVE, P_K, P_GAINS, P_KP = (
    0,
    1,
    2,
    3,
    4,
    5,
    6,
    7,
    8,
    12,
    21,
)
# index: where the base's positions and velocities start in x, the base's index in v, the right and
# left wheel's (hardware) index, n, then per arm joint its position and its velocity in x, and its
# hardware index
I_QB, I_VB, I_BASE, I_WR, I_WL, I_N, I_ARM = range(7)


def out_size(n: int) -> int:
    return OUT_REF + 6 * n


def step_params(
    r, b, wheel_inertia, wheel_limit, tolerance, timeout, law, constants_given, gains, kp, kd
) -> np.ndarray:
    """params; constants_given: K5..K8 to use, or None to derive them from M at every update."""
    derive, K = (1.0, (0.0,) * 4) if constants_given is None else (0.0, tuple(constants_given))
    return np.concatenate(
        [[r, b, wheel_inertia, wheel_limit, tolerance, timeout, law, derive], K, gains, kp, kd]
    ).astype(float)


def step_index(q_base, v_base, base, wheels, arm_q, arm_v, arm_hw) -> np.ndarray:
    return np.concatenate(
        [[q_base, v_base, base, wheels[0], wheels[1], len(arm_q)], arm_q, arm_v, arm_hw]
    ).astype(np.int64)


@njit(cache=True)
def planar_state(x, q_base, v_base, px, py, yaw, u1, u2):
    """The base's state in x (Drake's free body: q = [qw, qx, qy, qz, p], v = [w_W, v_W]) for a
    platform at (px, py, yaw) on the floor moving with u1 along its heading and turning at u2."""
    c, s = math.cos(yaw), math.sin(yaw)
    x[q_base], x[q_base + 1], x[q_base + 2], x[q_base + 3] = (
        math.cos(0.5 * yaw),
        0.0,
        0.0,
        math.sin(0.5 * yaw),
    )
    x[q_base + 4], x[q_base + 5], x[q_base + 6] = px, py, 0.0
    x[v_base], x[v_base + 1], x[v_base + 2] = 0.0, 0.0, u2
    x[v_base + 3], x[v_base + 4], x[v_base + 5] = u1 * c, u1 * s, 0.0


@njit(cache=True)
def _platform(inp, params, M, base, u1, u2, out, vdot):
    """The law, K5..K8, the wheel pair into out; the base's commanded acceleration into vdot:
    u_dot = s v (10) along the heading and about the vertical, and u1 u2 across the heading."""
    yaw = inp[IN_POSE + 2]
    v1, v2 = command(
        params[P_LAW],
        inp[IN_POSE],
        inp[IN_POSE + 1],
        yaw,
        inp[IN_POSE_REF],
        inp[IN_POSE_REF + 1],
        inp[IN_POSE_REF + 2],
        u1,
        u2,
        params[P_GAINS:P_KP],
        params[P_TOL],
    )
    r, b = params[P_R], params[P_B]
    if params[P_DERIVE] != 0.0:
        m, d, inertia, _ = planar_mass_properties(M, base, yaw)
        k5, k6, k7, k8 = constants(m, inertia, d, r, b, params[P_IW], 1.0)
    else:
        k5, k6, k7, k8 = params[P_K], params[P_K + 1], params[P_K + 2], params[P_K + 3]
    tau_r, tau_l = feedback_linearization(v1, v2, u1, u2, k5, k6, k7, k8)
    sat_r, sat_l, scale = saturate_pair(tau_r, tau_l, params[P_LIMIT])
    out[OUT_V], out[OUT_V + 1] = v1, v2
    out[OUT_TAU], out[OUT_TAU + 1] = sat_r, sat_l
    out[OUT_TAU_RAW], out[OUT_TAU_RAW + 1] = tau_r, tau_l
    out[OUT_SCALE] = scale
    out[OUT_K], out[OUT_K + 1], out[OUT_K + 2], out[OUT_K + 3] = k5, k6, k7, k8
    c, s = math.cos(yaw), math.sin(yaw)
    a_long, a_lat = scale * v1, u1 * u2
    vdot[base], vdot[base + 1], vdot[base + 2] = 0.0, 0.0, scale * v2
    vdot[base + 3], vdot[base + 4], vdot[base + 5] = a_long * c - a_lat * s, a_long * s + a_lat * c, 0.0


@njit(cache=True, nogil=True)
def cart_step(
    inp,
    params,
    index,
    position,
    velocity,
    q_s,
    qd_s,
    qdd_s,
    odo,
    x,
    tree,
    extra,
    work,
    M,
    vdot,
    tau,
    out,
    effort,
):
    """One whole update. The controller builds the arrays once (`step_params`, `step_index`,
    `out` of `out_size(n)`):

    - inp (IN_SIZE): pose (x, y, theta), its reference, the age of the arm's reference sample
      (s), and 1 for the pose from the wheel odometry and the base's state planar from it and u
      (written here), 0 if inp's pose and x's base already hold the true ones (ground truth);
    - x: the control model's state (Drake's positions, then velocities); M, vdot, tau, work,
      tree, extra: rigid_body_kernel's;
    - out: v1, v2, tau_right, tau_left (applied), the pair before saturation, the torque scale,
      K5..K8, u1, u2, then the held arm reference q_r, qd_r, qdd_r, the arm's joint positions
      and velocities and its commanded accelerations (n each): the OUT_* indices.
    """
    n = index[I_N]
    arm_q, arm_v, arm_hw = (
        index[I_ARM : I_ARM + n],
        index[I_ARM + n : I_ARM + 2 * n],
        index[I_ARM + 2 * n : I_ARM + 3 * n],
    )
    wr, wl = index[I_WR], index[I_WL]
    u1, u2 = wheel_velocities_to_body(velocity[wr], velocity[wl], params[P_R], params[P_B])
    out[OUT_U], out[OUT_U + 1] = u1, u2
    if inp[IN_PLANAR] != 0.0:
        odometry_step(odo, position[wl], position[wr], params[P_R], 2.0 * params[P_B])
        inp[IN_POSE], inp[IN_POSE + 1], inp[IN_POSE + 2] = odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING]
        planar_state(x, index[I_QB], index[I_VB], odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING], u1, u2)
    nq = x.shape[0] - vdot.shape[0]
    age, timeout = inp[IN_AGE], params[P_TIMEOUT]
    ref, arm, acc = OUT_REF, OUT_REF + 3 * n, OUT_REF + 5 * n
    for k in range(n):
        x[arm_q[k]] = out[arm + k] = position[arm_hw[k]]
        x[arm_v[k]] = out[arm + n + k] = velocity[arm_hw[k]]
        out[ref + k], out[ref + n + k], out[ref + 2 * n + k] = held_reference(
            q_s[k], qd_s[k], qdd_s[k], age, timeout
        )
    rbk.kinematics(tree, x, nq, work)
    rbk.mass_matrix(tree, extra, work, M)
    _platform(inp, params, M, index[I_BASE], u1, u2, out, vdot)
    commanded_acceleration(
        out[arm : arm + n],
        out[arm + n : acc],
        out[ref : ref + n],
        out[ref + n : ref + 2 * n],
        out[ref + 2 * n : ref + 3 * n],
        params[P_KP : P_KP + n],
        params[P_KP + n : P_KP + 2 * n],
        out[acc : acc + n],
    )
    for k in range(n):
        vdot[arm_v[k] - nq] = out[acc + k]
    rbk.inverse_dynamics(tree, extra, x, nq, vdot, work, tau)
    effort[wr], effort[wl] = out[OUT_TAU], out[OUT_TAU + 1]
    for k in range(n):
        effort[arm_hw[k]] = tau[arm_v[k] - nq]
