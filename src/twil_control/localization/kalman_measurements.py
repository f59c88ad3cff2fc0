"""A sensor message turned into a robot_localization measurement: a 15-vector, its 15x15
covariance and the update vector of the variables it corrects (RosFilter::preparePose,
prepareTwist, prepareAcceleration, forceTwoD).

Transforms are (R, t), as a tf lookup gives them. The update vector is rotated with the data, so a
sensor mounted at 90 degrees measures the other axis; IMU orientations, differential and relative
sensors are treated as robot_localization treats them (docs/localization.md). The arithmetic of
a twist and the covariances' rotations are compiled with numba (run once per sensor message).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from .kalman_state import (
    ACCEL,
    POSE,
    STATE_SIZE,
    TWIST,
    TWO_D_ZEROED,
    VPITCH,
    VROLL,
    VX,
    VYAW,
    matrix_from_rpy,
    normalize_angle,
    rpy_from_matrix,
)

Transform = tuple[np.ndarray, np.ndarray]  # (R 3x3, t 3)
IDENTITY: Transform = (np.eye(3), np.zeros(3))


@dataclass
class Measurement:
    """What the filter fuses: the 15-vector, its covariance, the update vector, the stamp."""

    topic: str
    time: float
    z: np.ndarray = field(default_factory=lambda: np.zeros(STATE_SIZE))
    covariance: np.ndarray = field(default_factory=lambda: np.zeros((STATE_SIZE, STATE_SIZE)))
    update: np.ndarray = field(default_factory=lambda: np.zeros(STATE_SIZE, dtype=bool))
    rejection_threshold: float = math.inf
    control: np.ndarray | None = None
    control_time: float = 0.0


def compose(a: Transform, b: Transform) -> Transform:
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def inverse(a: Transform) -> Transform:
    return a[0].T, -(a[0].T @ a[1])


@numba.njit(cache=True)
def rotated_mask(rot: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Which of the 3 variables a configured mask measures after rotation `rot` (a row of
    R diag(mask) of length >= 1e-6)."""
    out = np.empty(3, dtype=np.bool_)
    for i in range(3):
        length2 = 0.0
        for j in range(3):
            scaled = rot[i, j] * mask[j]
            length2 += scaled * scaled
        out[i] = length2 >= 1e-12
    return out


def cross(a, b) -> np.ndarray:
    """a x b of 3-vectors (numpy's cross costs ten times more on vectors this small)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@numba.njit(cache=True)
def _product6(a: np.ndarray, b: np.ndarray, transpose_b: bool) -> np.ndarray:
    """a @ b (or a @ b.T) of two 6x6 matrices, written out: every term is summed, so a NaN or an
    infinity anywhere in a row or column reaches the result as in numpy's product."""
    out = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            total = 0.0
            for k in range(6):
                total += a[i, k] * (b[j, k] if transpose_b else b[k, j])
            out[i, j] = total
    return out


@numba.njit(cache=True)
def rotated_covariance6(rot: np.ndarray, covariance6: np.ndarray) -> np.ndarray:
    """B C B^T with B = diag(R, R): a 6x6 covariance in the frame `rot` turns into (the whole
    product, so that a NaN or infinite variance spreads as numpy's would)."""
    b = np.zeros((6, 6))
    b[:3, :3] = rot
    b[3:, 3:] = rot
    return _product6(_product6(b, covariance6, False), b, True)


@numba.njit(cache=True)
def _force_two_d(z: np.ndarray, covariance: np.ndarray, update: np.ndarray) -> None:
    for i in TWO_D_ZEROED:
        z[i] = 0.0
        covariance[i, i] = 1e-6
        update[i] = True


def force_two_d(m: Measurement) -> None:
    """two_d_mode: z, roll, pitch and their rates and az measured as 0 with variance 1e-6."""
    _force_two_d(m.z, m.covariance, m.update)


@numba.njit(cache=True)
def _twist_into(z, covariance, update, rot, origin, linear, angular, covariance6, config, state, two_d):
    """prepare_twist's arithmetic, into the measurement's arrays."""
    wx, wy, wz = state[VROLL], state[VPITCH], state[VYAW]
    offset = (
        origin[1] * wz - origin[2] * wy,
        origin[2] * wx - origin[0] * wz,
        origin[0] * wy - origin[1] * wx,
    )
    for i in range(3):
        z[VX + i] = (rot[i, 0] * linear[0] + rot[i, 1] * linear[1] + rot[i, 2] * linear[2]) + offset[i]
        z[VROLL + i] = rot[i, 0] * angular[0] + rot[i, 1] * angular[1] + rot[i, 2] * angular[2]
    update[VX : VX + 3] = rotated_mask(rot, config[VX : VX + 3])
    update[VROLL : VROLL + 3] = rotated_mask(rot, config[VROLL : VROLL + 3])
    covariance[VX : VX + 6, VX : VX + 6] = rotated_covariance6(rot, covariance6)
    if two_d:
        _force_two_d(z, covariance, update)


def _floats(a) -> np.ndarray:
    """`a` as a new C-ordered, writable float64 array: the one array type the compiled functions
    are compiled (and cached) for, whatever tf or a message hands over."""
    return np.array(a, dtype=np.float64, order="C")


def prepare_twist(
    m: Measurement,
    linear: np.ndarray,
    angular: np.ndarray,
    covariance6: np.ndarray,
    config: np.ndarray,
    target: Transform,
    state: np.ndarray,
    two_d: bool,
) -> None:
    """Fill `m` from a twist in a sensor frame; `target` is the sensor frame in base_link. The
    sensor's offset adds the velocity of the base's rotation (t x w, w the state's rates)."""
    rot, origin = target
    _twist_into(
        m.z,
        m.covariance,
        m.update,
        _floats(rot),
        _floats(origin),
        _floats(linear),
        _floats(angular),
        _floats(covariance6),
        np.array(config, dtype=np.bool_),
        _floats(state),
        bool(two_d),
    )


def prepare_acceleration(
    m: Measurement,
    acceleration: np.ndarray,
    covariance3: np.ndarray,
    config: np.ndarray,
    target: Transform,
    state: np.ndarray,
    angular_acceleration: np.ndarray,
    gravity: float | None,
    attitude: np.ndarray | None,
    relative: bool,
    two_d: bool,
) -> None:
    """Fill `m` from an IMU's linear acceleration; `target` is the IMU frame in base_link.
    With `gravity` (remove_gravitational_acceleration), g along the world's +z seen in the
    sensor frame is subtracted: through the message's attitude (a rotation matrix), or the
    state's when the message has none (attitude None). The offset's tangential and
    centripetal terms are added as robot_localization adds them."""
    rot, origin = target
    acc = np.asarray(acceleration, dtype=float).copy()
    if gravity is not None:
        g = np.array([0.0, 0.0, gravity])
        if attitude is None:
            world_sensor = matrix_from_rpy(*state[3:6]) @ rot
            acc -= world_sensor.T @ g
        elif relative:
            acc -= rot.T @ attitude.T @ g
        else:
            acc -= attitude.T @ g
    rates = state[[VROLL, VPITCH, VYAW]]
    m.z[ACCEL] = rot @ acc + cross(origin, angular_acceleration) - cross(cross(origin, rates), rates)
    m.update[12:15] = rotated_mask(_floats(rot), np.array(config[12:15], dtype=np.bool_))
    m.covariance[ACCEL, ACCEL] = rot @ covariance3 @ rot.T
    if two_d:
        force_two_d(m)


@dataclass
class PoseSensorMemory:
    """What a pose sensor's earlier messages leave behind: the previous measurement and its
    covariance (differential), the first measurement (relative), the previous stamp."""

    previous: Transform | None = None
    previous_covariance: np.ndarray | None = None
    initial: Transform | None = None


def imu_orientation_in_base(orientation: np.ndarray, target: Transform) -> np.ndarray:
    """The IMU's world orientation as the base's: the mounting's roll, pitch and yaw subtracted
    from the measured ones, then (roll, pitch, yaw) turned by the mounting's yaw as a vector
    (an IMU mounted sideways measures the base's roll as its pitch)."""
    r0, p0, y0 = rpy_from_matrix(target[0])
    r, p, y = rpy_from_matrix(orientation)
    angles = np.array([normalize_angle(r - r0), normalize_angle(p - p0), normalize_angle(y - y0)])
    angles = matrix_from_rpy(0.0, 0.0, y0) @ angles
    return matrix_from_rpy(*angles)


def prepare_pose(
    m: Measurement,
    pose: Transform,
    covariance6: np.ndarray,
    config: np.ndarray,
    target: Transform,
    source: Transform | None,
    memory: PoseSensorMemory,
    dt: float,
    differential: bool,
    relative: bool,
    imu: bool,
    state: np.ndarray,
    two_d: bool,
    twist_frame: Transform = IDENTITY,
) -> bool:
    """Fill `m` from a pose (or an IMU's orientation, `imu`); False when there is nothing to
    fuse yet (a differential sensor's first message).

    `target` is the message frame in the world frame (identity for a differential sensor,
    whose changes are taken in its own frame; for an IMU, its frame in base_link); `source`,
    when the pose is of another frame than base_link (pose_use_child_frame), base_link in that
    frame; `dt` the time since the sensor's previous message; `twist_frame` the frame a
    differential sensor's velocity is in (the pose's frame) in base_link.
    """
    update = np.array(config, dtype=np.bool_)
    if imu:
        turn = matrix_from_rpy(0.0, 0.0, rpy_from_matrix(target[0])[2])
    else:
        turn = target[0]
    turn = _floats(turn)
    update[0:3] = rotated_mask(turn, update[0:3])
    update[3:6] = rotated_mask(turn, update[3:6])
    covariance = _floats(covariance6)
    if source is not None:
        covariance = rotated_covariance6(_floats(source[0].T), covariance)
    rotated = rotated_covariance6(turn, covariance)
    if imu:
        pose = (imu_orientation_in_base(pose[0], target), pose[1])
        target = IDENTITY
    if differential:
        previous, previous_covariance = memory.previous, memory.previous_covariance
        memory.previous, memory.previous_covariance = pose, covariance
        if previous is None or previous_covariance is None or dt <= 0.0:  # (set together)
            return False
        delta = compose(inverse(previous), pose)
        delta = compose((target[0], np.zeros(3)), delta)
        twist_config = np.zeros(STATE_SIZE, dtype=bool)
        twist_config[TWIST] = update[POSE]
        twist_covariance = (rotated + rotated_covariance6(turn, previous_covariance)) * dt
        rpy = np.array(rpy_from_matrix(delta[0]))
        prepare_twist(m, delta[1] / dt, rpy / dt, twist_covariance, twist_config, twist_frame, state, two_d)
        return True
    if source is not None:
        pose = compose(pose, source)
    if relative:
        if memory.initial is None:
            memory.initial = pose
        pose = compose(inverse(memory.initial), pose)
    pose = compose(target, pose)
    m.z[0:3] = pose[1]
    m.z[3:6] = rpy_from_matrix(pose[0])
    m.update[POSE] = update[POSE]
    m.covariance[POSE, POSE] = rotated
    if two_d:
        force_two_d(m)
    return True
