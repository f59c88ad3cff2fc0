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
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["OUT_SIZE", "OUT_V", "OUT_TAU", "OUT_TAU_RAW", "OUT_SCALE", "OUT_K",
           "cart_update", "planar_state", "wrap", "corrected_or_brake"]

OUT_V, OUT_TAU, OUT_TAU_RAW, OUT_SCALE, OUT_K = 0, 2, 4, 6, 7
OUT_SIZE = 11

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
