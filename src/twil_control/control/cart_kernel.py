"""The cart controller's platform and arm arithmetic for one 1 kHz update, compiled (numba).

The reference implementation is the pure-Python one: backstepping.BacksteppingLaw (corrected
law and brake, (18)-(52)), platform_model.derive_constants and feedback_linearization ((9),
(14)-(15)), the saturation of the wheel pair, and computed_torque.ComputedTorqueLaw (53). Called
one by one from Python they cost about 60 us per update, most of it interpreter overhead on
scalars (bench/cart_bench.py); this module does the same arithmetic in one compiled call of a
few microseconds. tests/test_cart_kernel.py checks it against the reference to 1e-12 relative
on random states (goal, overflow and saturation cases included). Only the corrected law is
here: the printed law is a comparison law and keeps the Python path.

Layout of the arrays (the controller preallocates them once):
- gains: the nine gains in backstepping.GAIN_NAMES order;
- x: the control model's state (positions, then velocities), M: its mass matrix, `base` the
  index of the base's angular velocity in the velocities (its translational velocity follows
  at base + 3);
- out (OUT_SIZE): v1, v2, tau_right, tau_left (applied), tau_right, tau_left (before
  saturation), torque scale, K5, K6, K7, K8 (see the OUT_* indices);
- vdot: the generalised acceleration for the inverse dynamics: the base's commanded
  acceleration [alpha_W, a_W] at base..base+5 and the arm's law-(53) acceleration at arm_v.

`cart_step` is the whole update in one call: the wheel odometry (`odometry_step`, the pose
part of diff_odometry.WheelOdometry.update), the state vector, the held arm reference, the
mass matrix and inverse dynamics of the whole robot (control/rigid_body_kernel.py, one
kinematics pass), `cart_update`, and the nine efforts. Its constant inputs are packed in two
arrays (a numba call costs about 0.2 us per argument): `step_params` and `step_index` build
them; its per-update inputs are `inp` (IN_* indices) and the hardware's arrays.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import rigid_body_kernel as rbk

__all__ = ["OUT_SIZE", "OUT_V", "OUT_TAU", "OUT_TAU_RAW", "OUT_SCALE", "OUT_K", "OUT_U", "OUT_REF",
           "IN_POSE", "IN_POSE_REF", "IN_AGE", "IN_PLANAR", "IN_SIZE", "ODO_SIZE", "step_out_size", "step_params",
           "step_index", "odometry_step", "cart_step", "cart_update", "planar_state", "wrap", "corrected_or_brake"]

OUT_V, OUT_TAU, OUT_TAU_RAW, OUT_SCALE, OUT_K = 0, 2, 4, 6, 7
OUT_SIZE = 11
# cart_step's out continues: u1, u2, then the held arm reference q_r, qd_r, qdd_r (n each)
OUT_U, OUT_REF = 11, 13
# cart_step's inp: pose (x, y, theta), its reference, the age of the arm's reference sample (s),
# and 1 for the pose from the wheel odometry and the base's state planar from it and u, 0 if
# inp's pose and x's base already hold the true ones (ground truth)
IN_POSE, IN_POSE_REF, IN_AGE, IN_PLANAR = 0, 3, 6, 7
IN_SIZE = 8
# odometry_step's state: x, y, heading (continuous), the last left and right wheel angles, and
# 1 once the first angles are recorded
_ODO_X, _ODO_Y, _ODO_TH, _ODO_LEFT, _ODO_RIGHT, _ODO_STARTED = 0, 1, 2, 3, 4, 5
ODO_SIZE = 6
_EXACT_INTEGRATION_THRESHOLD = 1e-6  # diff_odometry.EXACT_INTEGRATION_THRESHOLD
# step_params: r, b, wheel inertia, wheel effort limit, goal tolerance, reference timeout,
# the nine gains, then kp (n) and kd (n)
_P_R, _P_B, _P_IW, _P_LIMIT, _P_TOL, _P_TIMEOUT, _P_GAINS, _P_KP = 0, 1, 2, 3, 4, 5, 6, 15
# step_index: q_base, v_base (in x), the base's index in v, right and left wheel (hardware
# index), n, then arm_q (n), arm_v (n, in x) and the arm's hardware indices (n)
_I_QB, _I_VB, _I_BASE, _I_WR, _I_WL, _I_N, _I_ARM = 0, 1, 2, 3, 4, 5, 6


def step_out_size(n: int) -> int:
    return OUT_REF + 3 * n


def step_params(r, b, wheel_inertia, wheel_limit, tolerance, timeout, gains, kp, kd) -> np.ndarray:
    return np.concatenate([[r, b, wheel_inertia, wheel_limit, tolerance, timeout], gains, kp, kd]).astype(float)


def step_index(q_base, v_base, base, wheels, arm_q, arm_v, arm_hw) -> np.ndarray:
    return np.concatenate([[q_base, v_base, base, wheels[0], wheels[1], len(arm_q)], arm_q, arm_v,
                           arm_hw]).astype(np.int64)

_TWO_PI = 2.0 * math.pi
_FLOAT_MAX = np.finfo(np.float64).max
# The Taylor coefficients of d/dx sin(x)/x: sum_k (-1)^k 2k x^(2k-1) / (2k+1)!, k = 1..7.
_DSINC = np.array([(-1) ** k * 2 * k / math.factorial(2 * k + 1) for k in range(1, 8)])


@njit(cache=True, nogil=True)
def wrap(a):
    """An angle wrapped to (-pi, pi] (angles.wrap_angle)."""
    w = np.fmod(a + math.pi, _TWO_PI)  # C fmod, as math.fmod (which numba lacks)
    if w < 0.0:
        w += _TWO_PI
    w -= math.pi
    return math.pi if w <= -math.pi else w


@njit(cache=True, nogil=True)
def _sinc_and_derivative(x):
    # sin(x)/x and its derivative, by series near 0 where the closed forms cancel (angles.py
    # states the limits: 1e-4 for the value, 0.5 for the derivative).
    x2 = x * x
    sc = 1.0 - x2 / 6.0 * (1.0 - x2 / 20.0) if abs(x) < 1e-4 else math.sin(x) / x
    if abs(x) < 0.5:
        acc = 0.0
        for k in range(_DSINC.shape[0] - 1, -1, -1):
            acc = acc * x2 + _DSINC[k]
        dsc = acc * x
    else:
        dsc = (math.cos(x) - math.sin(x) / x) / x
    return sc, dsc


@njit(cache=True, nogil=True)
def corrected_or_brake(x, y, th, xr, yr, thr, u1, u2, g, tolerance):
    """(v1, v2) of the corrected backstepping law, or the brake -(gamma4 u1, gamma5 u2) within
    `tolerance` of the goal or when the law is not finite (BacksteppingLaw with law=corrected)."""
    g1, g2, g4, g5 = g[0], g[1], g[2], g[3]
    l1, l2, l3, l4, l5 = g[4], g[5], g[6], g[7], g[8]
    # (18)-(22): the pose in the reference's frame, then polar
    cr, sr = math.cos(thr), math.sin(thr)
    dx, dy = x - xr, y - yr
    xb1, xb2 = cr * dx + sr * dy, -sr * dx + cr * dy
    e = math.hypot(xb1, xb2)
    psi = math.atan2(xb2, xb1)
    if psi == -math.pi:
        psi = math.pi
    alpha = wrap(wrap(th - thr) - psi)
    v1 = -g4 * u1
    v2 = -g5 * u2
    if math.isfinite(e) and e > tolerance:
        c, s = math.cos(alpha), math.sin(alpha)
        sc, dsc = _sinc_and_derivative(alpha)
        ratio = l3 / l2
        # (27)-(28) and the tracking errors (37)-(38)
        e1 = u1 + g1 * e * c
        e2 = u2 - (-g2 * alpha - g1 * c * s + g1 * ratio * c * sc * psi)
        # v_bar (46)-(47) with erratum 1
        s_e = s / e
        vb1 = -g4 * e1 - l1 / l4 * e * c + l2 / l4 * alpha * s_e - l3 / l4 * psi * s_e
        vb2 = -g5 * e2 - l2 / l5 * alpha
        # eta_dot along (30)-(32) with the actual u
        deta2_dpsi = g1 * ratio * c * sc
        deta2_dalpha = -g2 - g1 * math.cos(2.0 * alpha) + g1 * ratio * psi * (c * dsc - s * sc)
        psi_dot = s_e * u1
        alpha_dot = -s_e * u1 + u2
        w1 = vb1 + (-g1 * u1 + g1 * e * s * u2)
        w2 = vb2 + deta2_dpsi * psi_dot + deta2_dalpha * alpha_dot
        if math.isfinite(w1) and math.isfinite(w2):
            return w1, w2
    return min(max(v1, -_FLOAT_MAX), _FLOAT_MAX), min(max(v2, -_FLOAT_MAX), _FLOAT_MAX)


@njit(cache=True, nogil=True)
def planar_state(x, q_base, v_base, arm_q, arm_v, px, py, yaw, u1, u2, position, velocity, joints):
    """Write the control model's state vector x for a base moving in the plane (pose px, py,
    yaw; forward speed u1, yaw rate u2: platform_dynamics.planar_base_state) and the arm's
    joints, read at indices `joints` of the hardware's position and velocity arrays.
    q_base / v_base: where the base's 7 positions / 6 velocities start in x; arm_q / arm_v:
    where each arm joint's position / velocity is in x."""
    c, s = math.cos(yaw), math.sin(yaw)
    x[q_base] = math.cos(0.5 * yaw)
    x[q_base + 1] = 0.0
    x[q_base + 2] = 0.0
    x[q_base + 3] = math.sin(0.5 * yaw)
    x[q_base + 4] = px
    x[q_base + 5] = py
    x[q_base + 6] = 0.0
    x[v_base] = 0.0
    x[v_base + 1] = 0.0
    x[v_base + 2] = u2
    x[v_base + 3] = u1 * c
    x[v_base + 4] = u1 * s
    x[v_base + 5] = 0.0
    for k in range(arm_q.shape[0]):
        x[arm_q[k]] = position[joints[k]]
        x[arm_v[k]] = velocity[joints[k]]


@njit(cache=True, nogil=True)
def cart_update(pose, pose_ref, u1, u2, g, tolerance, x, M, base, arm_q, arm_v, r, b, wheel_inertia,
                wheel_limit, q_r, qd_r, qdd_r, kp, kd, out, vdot):
    """One update's arithmetic: the corrected law, K5..K8 from the mass matrix M at the state
    x, the feedback linearisation (9), the saturation of the wheel pair, the base acceleration
    the platform then gets, and the arm's law-(53) acceleration from its joints in x (at
    arm_q, arm_v; x holds positions then velocities, so a velocity's index in vdot is its
    index in x minus the number of positions). Results in `out` and `vdot` (module doc)."""
    yaw = pose[2]
    v1, v2 = corrected_or_brake(pose[0], pose[1], yaw, pose_ref[0], pose_ref[1], pose_ref[2],
                                u1, u2, g, tolerance)
    # planar mass properties off the mass matrix (PlatformMassModel.planar_mass_properties):
    # its base block is the whole robot's spatial inertia about base_link's origin, world axes
    i, j = base, base + 3
    m = M[j, j]
    cx, cy = M[i + 2, j + 1] / m, M[i, j + 2] / m
    c, s = math.cos(yaw), math.sin(yaw)
    d = c * cx + s * cy
    inertia = M[i + 2, i + 2] - m * (cx * cx + cy * cy)
    # K5..K8 (platform_model.derive_constants), right/left torque order
    m_eff = m + 2.0 * wheel_inertia / (r * r)
    i_eff = inertia + m * d * d + 2.0 * wheel_inertia * b * b / (r * r)
    k5, k6, k7, k8 = m * d / m_eff, -m * d / i_eff, 1.0 / (r * m_eff), b / (r * i_eff)
    # tau = F^-1 (v + f(u)) (9), f(u) = -[K5 u2^2, K6 u1 u2] (14)
    half_sum = (v1 - k5 * u2 * u2) / (2.0 * k7)
    half_diff = (v2 - k6 * u1 * u2) / (2.0 * k8)
    tau_r, tau_l = half_sum + half_diff, half_sum - half_diff
    peak = max(abs(tau_r), abs(tau_l))
    scale = 1.0 if peak <= wheel_limit else wheel_limit / peak
    out[0], out[1] = v1, v2
    out[2], out[3] = tau_r * scale, tau_l * scale
    out[4], out[5] = tau_r, tau_l
    out[6] = scale
    out[7], out[8], out[9], out[10] = k5, k6, k7, k8
    # the base then accelerates with u_dot = scale v (10), and u1 u2 across its heading
    a_long, a_lat = scale * v1, u1 * u2
    vdot[i] = 0.0
    vdot[i + 1] = 0.0
    vdot[i + 2] = scale * v2
    vdot[j] = a_long * c - a_lat * s
    vdot[j + 1] = a_long * s + a_lat * c
    vdot[j + 2] = 0.0
    nq = x.shape[0] - vdot.shape[0]
    for k in range(arm_v.shape[0]):
        q, qd = x[arm_q[k]], x[arm_v[k]]
        vdot[arm_v[k] - nq] = qdd_r[k] + kd[k] * (qd_r[k] - qd) + kp[k] * (q_r[k] - q)


@njit(cache=True, nogil=True)
def odometry_step(odo, left, right, r, separation):
    """diff_odometry.WheelOdometry.update's pose, in the array `odo` (_ODO_* layout): the first
    call records the wheel angles (rad); later ones integrate the increments exactly (an arc)
    or, for a heading change under 1e-6 rad, by RK2 (integrate_exact). Its velocity window is
    not kept (the controller does not use it)."""
    if odo[_ODO_STARTED] == 0.0:
        odo[_ODO_LEFT], odo[_ODO_RIGHT], odo[_ODO_STARTED] = left, right, 1.0
        return
    d_left = r * (left - odo[_ODO_LEFT])
    d_right = r * (right - odo[_ODO_RIGHT])
    odo[_ODO_LEFT], odo[_ODO_RIGHT] = left, right
    ds = 0.5 * (d_left + d_right)
    dtheta = (d_right - d_left) / separation
    heading = odo[_ODO_TH]
    if abs(dtheta) < _EXACT_INTEGRATION_THRESHOLD:
        direction = heading + 0.5 * dtheta
        odo[_ODO_X] += ds * math.cos(direction)
        odo[_ODO_Y] += ds * math.sin(direction)
    else:
        radius = ds / dtheta
        new_heading = heading + dtheta
        odo[_ODO_X] += radius * (math.sin(new_heading) - math.sin(heading))
        odo[_ODO_Y] -= radius * (math.cos(new_heading) - math.cos(heading))
    odo[_ODO_TH] = heading + dtheta


@njit(cache=True, nogil=True)
def cart_step(inp, params, index, position, velocity, q_s, qd_s, qdd_s, odo, x, tree, extra, work, M, vdot,
              tau, out, effort):
    """One whole update (module doc): with inp[IN_PLANAR], the odometry from the wheel angles
    (its pose then in inp[IN_POSE:]); u from the wheel rates (11)-(12); the state vector x
    (the base planar from the pose and u if inp[IN_PLANAR], the arm from its joints); the arm
    reference (q_s, qd_s, qdd_s) held to second order for inp[IN_AGE] s (trajectory.
    second_order_hold; still at the timeout's hold beyond it); M; `cart_update`; tau =
    M vdot + C v - tau_g; the efforts: the wheel pair from out, the arm's rows of tau."""
    n = index[_I_N]
    arm_q = index[_I_ARM:_I_ARM + n]
    arm_v = index[_I_ARM + n:_I_ARM + 2 * n]
    arm_hw = index[_I_ARM + 2 * n:_I_ARM + 3 * n]
    r, b = params[_P_R], params[_P_B]
    wr, wl = velocity[index[_I_WR]], velocity[index[_I_WL]]
    u1, u2 = r * (wr + wl) / 2.0, r * (wr - wl) / (2.0 * b)
    q_base, v_base = index[_I_QB], index[_I_VB]
    if inp[IN_PLANAR] != 0.0:
        odometry_step(odo, position[index[_I_WL]], position[index[_I_WR]], r, 2.0 * b)
        inp[IN_POSE], inp[IN_POSE + 1], inp[IN_POSE + 2] = odo[_ODO_X], odo[_ODO_Y], odo[_ODO_TH]
        planar_state(x, q_base, v_base, arm_q, arm_v, inp[IN_POSE], inp[IN_POSE + 1], inp[IN_POSE + 2], u1, u2,
                     position, velocity, arm_hw)
    else:
        for k in range(n):
            x[arm_q[k]] = position[arm_hw[k]]
            x[arm_v[k]] = velocity[arm_hw[k]]
    q_r, qd_r, qdd_r = out[OUT_REF:OUT_REF + n], out[OUT_REF + n:OUT_REF + 2 * n], out[OUT_REF + 2 * n:OUT_REF + 3 * n]
    age, timeout = inp[IN_AGE], params[_P_TIMEOUT]
    dt = 0.0 if age <= 0.0 else min(age, timeout)
    moving = 1.0 if age <= timeout else 0.0
    for k in range(n):
        q_r[k] = q_s[k] + dt * (qd_s[k] + 0.5 * dt * qdd_s[k])
        qd_r[k] = (qd_s[k] + dt * qdd_s[k]) * moving
        qdd_r[k] = qdd_s[k] * moving
    out[OUT_U], out[OUT_U + 1] = u1, u2
    nq = x.shape[0] - vdot.shape[0]
    rbk.kinematics(tree, x, nq, work)
    rbk.mass_matrix(tree, extra, work, M)
    cart_update(inp[IN_POSE:IN_POSE + 3], inp[IN_POSE_REF:IN_POSE_REF + 3], u1, u2, params[_P_GAINS:_P_KP],
                params[_P_TOL], x, M, index[_I_BASE], arm_q, arm_v, r, b, params[_P_IW], params[_P_LIMIT], q_r,
                qd_r, qdd_r, params[_P_KP:_P_KP + n], params[_P_KP + n:_P_KP + 2 * n], out, vdot)
    rbk.inverse_dynamics(tree, extra, x, nq, vdot, work, tau)
    effort[index[_I_WR]], effort[index[_I_WL]] = out[OUT_TAU], out[OUT_TAU + 1]
    for k in range(n):
        effort[arm_hw[k]] = tau[arm_v[k] - nq]
