"""The cart controller's 1 kHz update, composed of the paper's equations and compiled (numba).

One update is three compiled calls around the control model's two (Pinocchio's CRBA and RNEA,
world/platform_dynamics.py), each composing the one implementation of its equations:
- `cart_state`: the platform velocity u (11)-(12) from the wheel rates
  (platform_model.wheel_velocities_to_body); the pose, from the wheel odometry
  (diff_odometry.odometry_step) or from the simulator's state; the control model's state q, v;
  the arm's reference held to second order (trajectory.held_reference);
- `cart_command`, with the mass matrix M: the backstepping law and its brake
  (backstepping.command, (18)-(52)); K5..K8 from M (platform_model.planar_mass_properties and
  constants) or given (params P_DERIVE = 0); the feedback linearisation (9) and the wheel
  pair's saturation (platform_model); the base's acceleration (10) and the arm's law-(53)
  acceleration (computed_torque.commanded_acceleration) into `a`;
- `write_efforts`, with tau = M a + C v - tau_g: the wheel pair and the arm's rows of tau.
Every function is also callable from Python; tests/test_cart_kernel.py checks the composition.

Arrays (the controller builds them once: `params`, `index`, and `out` of `out_size(n)`):
- inp (IN_SIZE): pose (x, y, theta) (written by cart_state), its reference, the age of the arm's
  reference sample (s), and 1 for the pose from the wheel odometry and a base planar from it and
  u, 0 for the simulator's base state (ground truth, from `plant_state`);
- out: v1, v2, tau_right, tau_left (applied), the pair before saturation, the torque scale,
  K5..K8, u1, u2, then the held arm reference q_r, qd_r, qdd_r, and the arm's joint positions,
  velocities and commanded accelerations (n each), see the OUT_* indices.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .backstepping import command
from .computed_torque import commanded_acceleration
from .diff_odometry import ODO_HEADING, ODO_SIZE, ODO_X, ODO_Y, odometry_step
from .platform_model import constants, feedback_linearization, planar_mass_properties, saturate_pair, \
    wheel_velocities_to_body
from .trajectory import held_reference

__all__ = ["IN_POSE", "IN_POSE_REF", "IN_AGE", "IN_PLANAR", "IN_SIZE", "ODO_SIZE", "OUT_V", "OUT_TAU",
           "OUT_TAU_RAW", "OUT_SCALE", "OUT_K", "OUT_U", "OUT_REF", "out_size", "step_params", "step_index",
           "cart_state", "cart_command", "write_efforts"]

IN_POSE, IN_POSE_REF, IN_AGE, IN_PLANAR = 0, 3, 6, 7
IN_SIZE = 8
OUT_V, OUT_TAU, OUT_TAU_RAW, OUT_SCALE, OUT_K, OUT_U, OUT_REF = 0, 2, 4, 6, 7, 11, 13
# params: r, b, wheel spin inertia, wheel effort limit, goal tolerance, reference timeout, the law
# (backstepping.CORRECTED / PRINTED), 1 to derive K5..K8 from M or 0 to use the given ones, the
# given K5..K8, the nine gains (control.gains order), then kp (n) and kd (n)
P_R, P_B, P_IW, P_LIMIT, P_TOL, P_TIMEOUT, P_LAW, P_DERIVE, P_K, P_GAINS, P_KP = 0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 21
# index: right and left wheel (in the hardware's arrays), their (cos, sin) pairs in q, their rates
# in v, the base's position and velocity in the simulator's state, n, then per arm joint its
# position in q, its velocity in v, and its index in the hardware's arrays
I_WR, I_WL, I_WRQ, I_WLQ, I_WRV, I_WLV, I_PLANT_Q, I_PLANT_V, I_N, I_ARM = range(10)


def out_size(n: int) -> int:
    return OUT_REF + 6 * n


def step_params(r, b, wheel_inertia, wheel_limit, tolerance, timeout, law, constants_given, gains, kp,
                kd) -> np.ndarray:
    """params; constants_given: K5..K8 to use, or None to derive them from M at every update."""
    derive, K = (1.0, (0.0,) * 4) if constants_given is None else (0.0, tuple(constants_given))
    return np.concatenate([[r, b, wheel_inertia, wheel_limit, tolerance, timeout, law, derive], K, gains, kp,
                           kd]).astype(float)


def step_index(wheels, wheel_q, wheel_v, plant_q, plant_v, arm_q, arm_v, arm_hw) -> np.ndarray:
    return np.concatenate([[wheels[0], wheels[1], wheel_q[0], wheel_q[1], wheel_v[0], wheel_v[1], plant_q, plant_v,
                            len(arm_q)], arm_q, arm_v, arm_hw]).astype(np.int64)


@njit(cache=True, nogil=True)
def _free_flyer_from_drake(plant_state, iq, iv, q, v):
    """The base's state in Pinocchio's free-flyer coordinates (q = [p, qx, qy, qz, qw], v in body
    axes) from Drake's quaternion floating joint (q = [qw, qx, qy, qz, p], v = [w_W, v_W]);
    returns its yaw."""
    qw, qx, qy, qz = plant_state[iq], plant_state[iq + 1], plant_state[iq + 2], plant_state[iq + 3]
    s = 1.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
    R = np.empty((3, 3))
    R[0, 0], R[0, 1], R[0, 2] = 1 - 2 * s * (qy * qy + qz * qz), 2 * s * (qx * qy - qw * qz), 2 * s * (qx * qz + qw * qy)
    R[1, 0], R[1, 1], R[1, 2] = 2 * s * (qx * qy + qw * qz), 1 - 2 * s * (qx * qx + qz * qz), 2 * s * (qy * qz - qw * qx)
    R[2, 0], R[2, 1], R[2, 2] = 2 * s * (qx * qz - qw * qy), 2 * s * (qy * qz + qw * qx), 1 - 2 * s * (qx * qx + qy * qy)
    q[0], q[1], q[2] = plant_state[iq + 4], plant_state[iq + 5], plant_state[iq + 6]
    q[3], q[4], q[5], q[6] = qx, qy, qz, qw
    for k in range(3):  # R^T v_W, R^T w_W
        v[k] = R[0, k] * plant_state[iv + 3] + R[1, k] * plant_state[iv + 4] + R[2, k] * plant_state[iv + 5]
        v[k + 3] = R[0, k] * plant_state[iv] + R[1, k] * plant_state[iv + 1] + R[2, k] * plant_state[iv + 2]
    return math.atan2(R[1, 0], R[0, 0])


@njit(cache=True, nogil=True)
def cart_state(inp, params, index, position, velocity, plant_state, q_s, qd_s, qdd_s, odo, q, v, out):
    """u, the pose, the control model's state (q, v) and the held arm reference (module doc).
    A planar base sits at z = 0 with the yaw of the pose, moving with u1 along its heading and
    turning at u2."""
    n = index[I_N]
    arm_q, arm_v, arm_hw = index[I_ARM:I_ARM + n], index[I_ARM + n:I_ARM + 2 * n], index[I_ARM + 2 * n:I_ARM + 3 * n]
    wr, wl = index[I_WR], index[I_WL]
    u1, u2 = wheel_velocities_to_body(velocity[wr], velocity[wl], params[P_R], params[P_B])
    out[OUT_U], out[OUT_U + 1] = u1, u2
    if inp[IN_PLANAR] != 0.0:
        odometry_step(odo, position[wl], position[wr], params[P_R], 2.0 * params[P_B])
        x, y, yaw = odo[ODO_X], odo[ODO_Y], odo[ODO_HEADING]
        q[0], q[1], q[2] = x, y, 0.0
        q[3], q[4], q[5], q[6] = 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)
        v[0], v[1], v[2], v[3], v[4], v[5] = u1, 0.0, 0.0, 0.0, 0.0, u2
    else:
        yaw = _free_flyer_from_drake(plant_state, index[I_PLANT_Q], index[I_PLANT_V], q, v)
        x, y = q[0], q[1]
    inp[IN_POSE], inp[IN_POSE + 1], inp[IN_POSE + 2] = x, y, yaw
    for w, iq, iv in ((wr, index[I_WRQ], index[I_WRV]), (wl, index[I_WLQ], index[I_WLV])):
        q[iq], q[iq + 1] = math.cos(position[w]), math.sin(position[w])
        v[iv] = velocity[w]
    age, timeout = inp[IN_AGE], params[P_TIMEOUT]
    ref, arm = OUT_REF, OUT_REF + 3 * n
    for k in range(n):
        q[arm_q[k]] = out[arm + k] = position[arm_hw[k]]
        v[arm_v[k]] = out[arm + n + k] = velocity[arm_hw[k]]
        out[ref + k], out[ref + n + k], out[ref + 2 * n + k] = held_reference(q_s[k], qd_s[k], qdd_s[k], age, timeout)


@njit(cache=True, nogil=True)
def cart_command(inp, params, index, M, out, a):
    """The platform law, K5..K8, the wheel torques and the accelerations `a` (module doc). The
    base's commanded acceleration is the derivative of its body-axes velocity: u_dot = s v (10)
    along the heading and about the vertical (the centripetal u1 u2 follows from the turning axes)."""
    n = index[I_N]
    u1, u2 = out[OUT_U], out[OUT_U + 1]
    v1, v2 = command(params[P_LAW], inp[IN_POSE], inp[IN_POSE + 1], inp[IN_POSE + 2], inp[IN_POSE_REF],
                     inp[IN_POSE_REF + 1], inp[IN_POSE_REF + 2], u1, u2, params[P_GAINS:P_KP], params[P_TOL])
    r, b = params[P_R], params[P_B]
    if params[P_DERIVE] != 0.0:
        m, d, inertia, _ = planar_mass_properties(M, 0)
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
    a[:] = 0.0
    a[0], a[5] = scale * v1, scale * v2
    ref, arm = OUT_REF, OUT_REF + 3 * n
    acc = commanded_acceleration(out[arm:arm + n], out[arm + n:arm + 2 * n], out[ref:ref + n],
                                 out[ref + n:ref + 2 * n], out[ref + 2 * n:ref + 3 * n], params[P_KP:P_KP + n],
                                 params[P_KP + n:P_KP + 2 * n], out[arm + 2 * n:arm + 3 * n])
    arm_v = index[I_ARM + n:I_ARM + 2 * n]
    for k in range(n):
        a[arm_v[k]] = acc[k]


@njit(cache=True, nogil=True)
def write_efforts(index, out, tau, effort):
    """The efforts: the wheel pair from out, each arm joint's row of tau."""
    n = index[I_N]
    effort[index[I_WR]], effort[index[I_WL]] = out[OUT_TAU], out[OUT_TAU + 1]
    for k in range(n):
        effort[index[I_ARM + 2 * n + k]] = tau[index[I_ARM + n + k]]
