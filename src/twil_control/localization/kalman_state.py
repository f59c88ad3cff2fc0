"""robot_localization's 15-variable state and the rotation conventions its filters use.

The state is x, y, z, roll, pitch, yaw, their six velocities in the body frame (vx, vy, vz,
vroll, vpitch, vyaw) and the three linear accelerations (ax, ay, az), in that order; a
sensor's ``_config`` is 15 booleans in the same order. Euler angles follow tf2: a rotation is
Rz(yaw) Ry(pitch) Rx(roll), and ``rpy_from_matrix`` is tf2's Matrix3x3::getRPY (its solution
with |pitch| <= pi/2). Angles in the state are kept in [-pi, pi) (angles::normalize_angle).
"""

from __future__ import annotations

import math

import numpy as np

X, Y, Z, ROLL, PITCH, YAW, VX, VY, VZ, VROLL, VPITCH, VYAW, AX, AY, AZ = range(15)
STATE_SIZE = 15
POSE = slice(0, 6)
TWIST = slice(6, 12)
ACCEL = slice(12, 15)
ANGLES = (ROLL, PITCH, YAW)
NAMES = (
    "X",
    "Y",
    "Z",
    "ROLL",
    "PITCH",
    "YAW",
    "X_VELOCITY",
    "Y_VELOCITY",
    "Z_VELOCITY",
    "ROLL_VELOCITY",
    "PITCH_VELOCITY",
    "YAW_VELOCITY",
    "X_ACCELERATION",
    "Y_ACCELERATION",
    "Z_ACCELERATION",
)

#: robot_localization's process noise when ``process_noise_covariance`` is not set (its diagonal)
DEFAULT_PROCESS_NOISE = np.diag(
    [0.05, 0.05, 0.06, 0.03, 0.03, 0.06, 0.025, 0.025, 0.04, 0.01, 0.01, 0.02, 0.01, 0.01, 0.015]
)
#: the initial estimate covariance when ``initial_estimate_covariance`` is not set
DEFAULT_INITIAL_COVARIANCE = np.eye(STATE_SIZE) * 1e-9
#: the variables two_d_mode measures as zero, each with variance 1e-6, in every measurement
TWO_D_ZEROED = (Z, ROLL, PITCH, VZ, VROLL, VPITCH, AZ)


def normalize_angle(angle: float) -> float:
    """`angle` in [-pi, pi) (angles::normalize_angle)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def matrix_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll) (tf2's Matrix3x3::setRPY)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def rpy_from_matrix(m: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a rotation matrix, tf2's getRPY (solution 1; at gimbal lock yaw 0)."""
    if abs(m[2, 0]) >= 1.0:
        yaw = 0.0
        if m[2, 0] < 0:
            return math.atan2(m[0, 1], m[0, 2]), math.pi / 2, yaw
        return math.atan2(-m[0, 1], -m[0, 2]), -math.pi / 2, yaw
    pitch = -math.asin(m[2, 0])
    cp = math.cos(pitch)
    roll = math.atan2(m[2, 1] / cp, m[2, 2] / cp)
    yaw = math.atan2(m[1, 0] / cp, m[0, 0] / cp)
    return roll, pitch, yaw


def matrix_from_quat(q) -> np.ndarray:
    """Rotation matrix of a unit quaternion (x, y, z, w)."""
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_from_matrix(m: np.ndarray) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) of a rotation matrix, w >= 0."""
    roll, pitch, yaw = rpy_from_matrix(m)
    return quat_from_rpy(roll, pitch, yaw)


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """tf2's Quaternion::setRPY: (x, y, z, w) of Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def wrap_state_angles(state: np.ndarray) -> None:
    """Roll, pitch and yaw of `state` into [-pi, pi), in place (FilterBase::wrapStateAngles)."""
    for i in ANGLES:
        state[i] = normalize_angle(state[i])


def control_acceleration(
    state: float, control: float, accel_limit: float, accel_gain: float, decel_limit: float, decel_gain: float
) -> float:
    """The acceleration a commanded velocity implies (FilterBase::computeControlAcceleration):
    the gain times the error, within the acceleration limit, or the deceleration's gain and
    limit when the set point (the command, or 0 if it reverses the motion) is slower."""
    error = control - state
    same_sign = abs(error) <= abs(control) + 0.01
    set_point = control if same_sign else 0.0
    decelerating = abs(set_point) < abs(state)
    limit, gain = (decel_limit, decel_gain) if decelerating else (accel_limit, accel_gain)
    return min(max(gain * error, -limit), limit)


def dynamic_process_noise(process_noise: np.ndarray, state: np.ndarray) -> np.ndarray:
    """The process noise scaled by the speed (dynamic_process_noise_covariance): its first 6x6
    block times |v|^2, v the six velocities (FilterBase::computeDynamicProcessNoiseCovariance)."""
    out = process_noise.copy()
    speed2 = float(np.dot(state[TWIST], state[TWIST]))
    out[:6, :6] = process_noise[:6, :6] * speed2
    return out
