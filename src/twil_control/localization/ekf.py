"""robot_localization's extended Kalman filter: the omnidirectional 3D motion model, its
Jacobian, the prediction and the partial correction (Ekf::predict and Ekf::correct).

Only the measured subset is corrected, with Joseph's form and the sensor's Mahalanobis gate;
variances are kept at or above 1e-9, as robot_localization keeps them (docs/localization.md).
Compiled with numba: the filter runs once per sensor message, on 15x15 matrices whose numpy
calls cost more in overhead than in arithmetic.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .kalman_state import (
    AX,
    AY,
    AZ,
    PITCH,
    ROLL,
    STATE_SIZE,
    VPITCH,
    VROLL,
    VX,
    VY,
    VYAW,
    VZ,
    YAW,
    X,
    Y,
    Z,
)

_TWO_PI = 2.0 * math.pi


@numba.njit(cache=True)
def _wrap(angle: float) -> float:
    """`angle` in [-pi, pi): kalman_state.normalize_angle, compiled (numba's float % is Python's)."""
    return (angle + math.pi) % _TWO_PI - math.pi


@numba.njit(cache=True)
def _wrap_angles(state: np.ndarray) -> None:
    state[ROLL] = _wrap(state[ROLL])
    state[PITCH] = _wrap(state[PITCH])
    state[YAW] = _wrap(state[YAW])


@numba.njit(cache=True)
def transfer_function(state: np.ndarray, dt: float) -> np.ndarray:
    """The 15x15 matrix F with f(x) = F(x) x over `dt` (the model's linear form at x's angles)."""
    sr, cr = math.sin(state[ROLL]), math.cos(state[ROLL])
    sp, cp = math.sin(state[PITCH]), math.cos(state[PITCH])
    sy, cy = math.sin(state[YAW]), math.cos(state[YAW])
    cpi = 1.0 / cp
    tp = sp * cpi
    rot = np.empty((3, 3))
    rot[0, 0], rot[0, 1], rot[0, 2] = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
    rot[1, 0], rot[1, 1], rot[1, 2] = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
    rot[2, 0], rot[2, 1], rot[2, 2] = -sp, cp * sr, cp * cr
    f = np.eye(STATE_SIZE)
    for row in range(3):
        for col in range(3):
            f[X + row, VX + col] = rot[row, col] * dt
            f[X + row, AX + col] = 0.5 * rot[row, col] * dt * dt
    f[ROLL, VROLL] = dt
    f[ROLL, VPITCH] = sr * tp * dt
    f[ROLL, VYAW] = cr * tp * dt
    f[PITCH, VPITCH] = cr * dt
    f[PITCH, VYAW] = -sr * dt
    f[YAW, VPITCH] = sr * cpi * dt
    f[YAW, VYAW] = cr * cpi * dt
    f[VX, AX] = dt
    f[VY, AY] = dt
    f[VZ, AZ] = dt
    return f


@numba.njit(cache=True)
def _moved(state: np.ndarray, cx: float, cy: float, cz: float, dt: float) -> float:
    """d(position)/d(angle): a rotation's derivative row applied to v dt + a dt^2/2."""
    v = cx * state[VX] + cy * state[VY] + cz * state[VZ]
    a = cx * state[AX] + cy * state[AY] + cz * state[AZ]
    return v * dt + a * (0.5 * dt * dt)


@numba.njit(cache=True)
def transfer_jacobian(state: np.ndarray, dt: float, f: np.ndarray) -> np.ndarray:
    """The Jacobian of f(x) = F(x) x: F plus the derivatives of F's angle-dependent entries."""
    sr, cr = math.sin(state[ROLL]), math.cos(state[ROLL])
    sp, cp = math.sin(state[PITCH]), math.cos(state[PITCH])
    sy, cy = math.sin(state[YAW]), math.cos(state[YAW])
    cpi = 1.0 / cp
    tp = sp * cpi
    vpitch, vyaw = state[VPITCH], state[VYAW]
    j = f.copy()
    j[X, ROLL] = _moved(state, 0.0, cy * sp * cr + sy * sr, -cy * sp * sr + sy * cr, dt)
    j[X, PITCH] = _moved(state, -cy * sp, cy * cp * sr, cy * cp * cr, dt)
    j[X, YAW] = _moved(state, -sy * cp, -sy * sp * sr - cy * cr, -sy * sp * cr + cy * sr, dt)
    j[Y, ROLL] = _moved(state, 0.0, sy * sp * cr - cy * sr, -sy * sp * sr - cy * cr, dt)
    j[Y, PITCH] = _moved(state, -sy * sp, sy * cp * sr, sy * cp * cr, dt)
    j[Y, YAW] = _moved(state, cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, dt)
    j[Z, ROLL] = _moved(state, 0.0, cp * cr, -cp * sr, dt)
    j[Z, PITCH] = _moved(state, -cp, -sp * sr, -sp * cr, dt)
    j[ROLL, ROLL] = 1.0 + (cr * tp * vpitch - sr * tp * vyaw) * dt
    j[ROLL, PITCH] = (cpi * cpi * sr * vpitch + cpi * cpi * cr * vyaw) * dt
    j[PITCH, ROLL] = (-sr * vpitch - cr * vyaw) * dt
    j[YAW, ROLL] = (cr * cpi * vpitch - sr * cpi * vyaw) * dt
    j[YAW, PITCH] = (sr * tp * cpi * vpitch + cr * tp * cpi * vyaw) * dt
    return j


@numba.njit(cache=True)
def predict(
    state: np.ndarray, covariance: np.ndarray, dt: float, process_noise: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(x, P) after `dt` seconds: x = F(x) x with angles wrapped, P = J P J^T + Q dt."""
    f = transfer_function(state, dt)
    j = transfer_jacobian(state, dt, f)
    x = f @ np.ascontiguousarray(state)
    _wrap_angles(x)
    return x, j @ np.ascontiguousarray(covariance) @ j.T + dt * process_noise


def measured_indices(measurement: np.ndarray, update: np.ndarray) -> np.ndarray:
    """The state variables a measurement corrects: those its update vector selects, less
    NaN and infinite values (robot_localization excludes them)."""
    return np.flatnonzero(update & np.isfinite(measurement))


@numba.njit(cache=True)
def _measured_indices(measurement: np.ndarray, update: np.ndarray) -> np.ndarray:
    """measured_indices, compiled."""
    idx = np.empty(measurement.shape[0], dtype=np.int64)
    count = 0
    for i in range(measurement.shape[0]):
        if update[i] and np.isfinite(measurement[i]):
            idx[count] = i
            count += 1
    return idx[:count]


@numba.njit(cache=True)
def correct(
    state: np.ndarray,
    covariance: np.ndarray,
    measurement: np.ndarray,
    measurement_covariance: np.ndarray,
    update: np.ndarray,
    rejection_threshold: float = math.inf,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """(x, P, accepted) after fusing the `update`-selected entries of a 15-vector measurement
    with its 15x15 covariance. Not accepted (x, P unchanged): nothing to fuse, or a squared
    Mahalanobis distance >= rejection_threshold^2."""
    idx = _measured_indices(measurement, update)
    m = idx.size
    if m == 0:
        return state, covariance, False
    n = state.shape[0]
    r = np.empty((m, m))
    s = np.empty((m, m))
    pht = np.empty((n, m))  # P H^T: H selects columns
    for b in range(m):
        for i in range(n):
            pht[i, b] = covariance[i, idx[b]]
    for a in range(m):
        for b in range(m):
            r[a, b] = measurement_covariance[idx[a], idx[b]]
        variance = abs(r[a, a])
        r[a, a] = 1e-9 if variance < 1e-9 else variance  # (a NaN stays NaN, as np.maximum keeps it)
    for a in range(m):
        for b in range(m):
            s[a, b] = pht[idx[a], b] + r[a, b]
    s_inv = np.linalg.solve(s, np.eye(m))  # the LAPACK call (gesv) numpy's inv makes
    gain = pht @ s_inv
    innovation = np.empty(m)
    for a in range(m):
        innovation[a] = measurement[idx[a]] - state[idx[a]]
        if idx[a] == ROLL or idx[a] == PITCH or idx[a] == YAW:
            innovation[a] = _wrap(innovation[a])
    if innovation @ s_inv @ innovation >= rejection_threshold * rejection_threshold:
        return state, covariance, False
    x = state + gain @ innovation
    residual = np.eye(n)
    for b in range(m):
        for i in range(n):
            residual[i, idx[b]] -= gain[i, b]
    p = residual @ np.ascontiguousarray(covariance) @ residual.T + gain @ r @ gain.T
    _wrap_angles(x)
    return x, p, True
