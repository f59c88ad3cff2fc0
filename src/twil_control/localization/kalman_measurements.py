"""A sensor message turned into a robot_localization measurement: a 15-vector, its 15x15
covariance and the update vector of the variables it corrects (RosFilter::preparePose,
prepareTwist, prepareAcceleration, forceTwoD).

Transforms are (R, t), as a tf lookup gives them. The update vector is rotated with the data, so a
sensor mounted at 90 degrees measures the other axis; IMU orientations, differential and relative
sensors are treated as robot_localization treats them (docs/localization.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .kalman_state import (
    ACCEL,
    POSE,
    STATE_SIZE,
    TWIST,
    TWO_D_ZEROED,
    VPITCH,
    VROLL,
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


def rotated_mask(rot: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Which of the 3 variables a configured mask measures after rotation `rot` (a row of
    R diag(mask) of length >= 1e-6)."""
    scaled = rot * mask
    return np.einsum("ij,ij->i", scaled, scaled) >= 1e-12


def cross(a, b) -> np.ndarray:
    """a x b of 3-vectors (numpy's cross costs ten times more on vectors this small)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def block_rotation(rot: np.ndarray) -> np.ndarray:
    """diag(R, R): a 6-vector's (linear, angular) or (position, orientation) rotation."""
    out = np.zeros((6, 6))
    out[:3, :3] = out[3:, 3:] = rot
    return out


def force_two_d(m: Measurement) -> None:
    """two_d_mode: z, roll, pitch and their rates and az measured as 0 with variance 1e-6."""
    for i in TWO_D_ZEROED:
        m.z[i] = 0.0
        m.covariance[i, i] = 1e-6
        m.update[i] = True


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
    rates = state[[VROLL, VPITCH, VYAW]]
    m.z[TWIST] = np.concatenate([rot @ linear + cross(origin, rates), rot @ angular])
    m.update[6:9] = rotated_mask(rot, config[6:9])
    m.update[9:12] = rotated_mask(rot, config[9:12])
    r6 = block_rotation(rot)
    m.covariance[TWIST, TWIST] = r6 @ covariance6 @ r6.T
    if two_d:
        force_two_d(m)


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
    m.update[12:15] = rotated_mask(rot, config[12:15])
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
    update = config.copy()
    if imu:
        turn = matrix_from_rpy(0.0, 0.0, rpy_from_matrix(target[0])[2])
    else:
        turn = target[0]
    update[0:3] = rotated_mask(turn, config[0:3])
    update[3:6] = rotated_mask(turn, config[3:6])
    covariance = np.array(covariance6, dtype=float)
    if source is not None:
        rs = block_rotation(source[0])
        covariance = rs.T @ covariance @ rs
    r6 = block_rotation(turn)
    rotated = r6 @ covariance @ r6.T
    if imu:
        pose = (imu_orientation_in_base(pose[0], target), pose[1])
        target = IDENTITY
    if differential:
        previous, previous_covariance = memory.previous, memory.previous_covariance
        memory.previous, memory.previous_covariance = pose, covariance
        if previous is None or dt <= 0.0:
            return False
        delta = compose(inverse(previous), pose)
        delta = compose((target[0], np.zeros(3)), delta)
        twist_config = np.zeros(STATE_SIZE, dtype=bool)
        twist_config[TWIST] = update[POSE]
        twist_covariance = (rotated + r6 @ previous_covariance @ r6.T) * dt
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
