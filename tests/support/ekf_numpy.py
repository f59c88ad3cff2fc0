"""robot_localization's EKF prediction and correction in plain numpy (numpy matrix products, np.ix_
selection, np.linalg.inv, Python loops): the same maths as the compiled localization/ekf.py,
the oracle tests/test_ekf_compiled.py holds it to.
"""

from __future__ import annotations

import math

import numpy as np

X, Y, Z, ROLL, PITCH, YAW, VX, VY, VZ, VROLL, VPITCH, VYAW, AX, AY, AZ = range(15)
STATE_SIZE = 15
ANGLES = (ROLL, PITCH, YAW)


def normalize_angle(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def wrap_state_angles(state: np.ndarray) -> None:
    for i in ANGLES:
        state[i] = normalize_angle(state[i])


_ANGLE_MASK = np.zeros(STATE_SIZE, dtype=bool)
_ANGLE_MASK[list(ANGLES)] = True


def transfer_function(state: np.ndarray, dt: float) -> np.ndarray:
    """The 15x15 matrix F with f(x) = F(x) x over `dt` (the model's linear form at x's angles)."""
    roll, pitch, yaw = state[ROLL], state[PITCH], state[YAW]
    sr, cr = math.sin(roll), math.cos(roll)
    sp, cp = math.sin(pitch), math.cos(pitch)
    sy, cy = math.sin(yaw), math.cos(yaw)
    cpi = 1.0 / cp
    tp = sp * cpi
    rot = (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )
    f = np.eye(STATE_SIZE)
    for row, axis in enumerate((X, Y, Z)):
        for col in range(3):
            f[axis, VX + col] = rot[row][col] * dt
            f[axis, AX + col] = 0.5 * rot[row][col] * dt * dt
    f[ROLL, VROLL] = dt
    f[ROLL, VPITCH] = sr * tp * dt
    f[ROLL, VYAW] = cr * tp * dt
    f[PITCH, VPITCH] = cr * dt
    f[PITCH, VYAW] = -sr * dt
    f[YAW, VPITCH] = sr * cpi * dt
    f[YAW, VYAW] = cr * cpi * dt
    f[VX, AX] = f[VY, AY] = f[VZ, AZ] = dt
    return f


def transfer_jacobian(state: np.ndarray, dt: float, f: np.ndarray) -> np.ndarray:
    """The Jacobian of f(x) = F(x) x: F plus the derivatives of F's angle-dependent entries."""
    roll, pitch, yaw = state[ROLL], state[PITCH], state[YAW]
    sr, cr = math.sin(roll), math.cos(roll)
    sp, cp = math.sin(pitch), math.cos(pitch)
    sy, cy = math.sin(yaw), math.cos(yaw)
    cpi = 1.0 / cp
    tp = sp * cpi
    vx, vy, vz = state[VX], state[VY], state[VZ]
    ax, ay, az = state[AX], state[AY], state[AZ]
    vpitch, vyaw = state[VPITCH], state[VYAW]
    half = 0.5 * dt * dt

    def moved(cx: float, cy_: float, cz: float) -> float:
        # d(position)/d(angle): the rotation's derivative row applied to v dt + a dt^2/2
        return (cx * vx + cy_ * vy + cz * vz) * dt + (cx * ax + cy_ * ay + cz * az) * half

    j = f.copy()
    j[X, ROLL] = moved(0.0, cy * sp * cr + sy * sr, -cy * sp * sr + sy * cr)
    j[X, PITCH] = moved(-cy * sp, cy * cp * sr, cy * cp * cr)
    j[X, YAW] = moved(-sy * cp, -sy * sp * sr - cy * cr, -sy * sp * cr + cy * sr)
    j[Y, ROLL] = moved(0.0, sy * sp * cr - cy * sr, -sy * sp * sr - cy * cr)
    j[Y, PITCH] = moved(-sy * sp, sy * cp * sr, sy * cp * cr)
    j[Y, YAW] = moved(cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr)
    j[Z, ROLL] = moved(0.0, cp * cr, -cp * sr)
    j[Z, PITCH] = moved(-cp, -sp * sr, -sp * cr)
    j[ROLL, ROLL] = 1.0 + (cr * tp * vpitch - sr * tp * vyaw) * dt
    j[ROLL, PITCH] = (cpi * cpi * sr * vpitch + cpi * cpi * cr * vyaw) * dt
    j[PITCH, ROLL] = (-sr * vpitch - cr * vyaw) * dt
    j[YAW, ROLL] = (cr * cpi * vpitch - sr * cpi * vyaw) * dt
    j[YAW, PITCH] = (sr * tp * cpi * vpitch + cr * tp * cpi * vyaw) * dt
    return j


def predict(
    state: np.ndarray, covariance: np.ndarray, dt: float, process_noise: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(x, P) after `dt` seconds: x = F(x) x with angles wrapped, P = J P J^T + Q dt."""
    f = transfer_function(state, dt)
    j = transfer_jacobian(state, dt, f)
    x = f @ state
    wrap_state_angles(x)
    return x, j @ covariance @ j.T + dt * process_noise


def measured_indices(measurement: np.ndarray, update: np.ndarray) -> np.ndarray:
    """The state variables a measurement corrects: those its update vector selects, less
    NaN and infinite values (robot_localization excludes them)."""
    return np.flatnonzero(update & np.isfinite(measurement))


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
    idx = measured_indices(measurement, update)
    if idx.size == 0:
        return state, covariance, False
    r = measurement_covariance[np.ix_(idx, idx)].copy()
    diag = np.abs(np.diag(r))
    np.fill_diagonal(r, np.maximum(diag, 1e-9))
    pht = covariance[:, idx]  # P H^T: H selects columns
    s_inv = np.linalg.inv(pht[idx, :] + r)
    gain = pht @ s_inv
    innovation = measurement[idx] - state[idx]
    angles = _ANGLE_MASK[idx]
    if angles.any():
        innovation[angles] = [normalize_angle(a) for a in innovation[angles]]
    if float(innovation @ s_inv @ innovation) >= rejection_threshold * rejection_threshold:
        return state, covariance, False
    x = state + gain @ innovation
    residual = np.eye(STATE_SIZE)
    residual[:, idx] -= gain
    p = residual @ covariance @ residual.T + gain @ r @ gain.T
    wrap_state_angles(x)
    return x, p, True
