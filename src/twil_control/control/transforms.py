"""Rigid transforms as (translation, quaternion) pairs, numpy only.

Quaternions are (x, y, z, w), the order of geometry_msgs/Quaternion, so values move between
messages and math without reordering. Used by the tf tree (core.tf) and by nodes that turn
poses into messages; kept here because the ROS replica itself holds no robotics math.
"""

from __future__ import annotations

import math

import numpy as np

from twil_control.errors import InputError

IDENTITY_QUAT = np.array([0.0, 0.0, 0.0, 1.0])


def quat_from_yaw(yaw: float) -> np.ndarray:
    """Quaternion (x, y, z, w) of a rotation by `yaw` about +z."""
    return np.array([0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)])


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Quaternion (x, y, z, w) of fixed-axis roll, pitch, yaw (URDF's rpy, REP 103)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ]
    )


def quat_from_axis_angle(axis, angle: float) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation by `angle` about the unit vector `axis`."""
    s = math.sin(0.5 * angle)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(0.5 * angle))


def urdf_joint_pose(joint_type: str, origin, q_origin, axis, position: float) -> tuple[tuple, tuple]:
    """(translation, quaternion) of a URDF joint's child link in its parent link at `position`:
    the joint's <origin> (translation `origin`, rotation `q_origin` = quat_from_rpy of its rpy,
    both tuples of floats), then the motion along its unit <axis> (rotation for revolute and
    continuous joints, translation for prismatic; none for fixed), as robot_state_publisher
    computes it."""
    if joint_type in ("revolute", "continuous"):
        return compose_floats(origin, q_origin, (0.0, 0.0, 0.0), quat_from_axis_angle(axis, position))
    if joint_type == "prismatic":
        return compose_floats(origin, q_origin, tuple(a * position for a in axis), (0.0, 0.0, 0.0, 1.0))
    return origin, q_origin


def yaw_from_quat(q) -> float:
    """Heading (rotation about +z) of a quaternion (x, y, z, w)."""
    x, y, z, w = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def qmul(a, b) -> tuple[float, float, float, float]:
    """Hamilton product a * b (apply b, then a) in plain floats: the hot paths (tf lookups at
    100 Hz in several nodes) would pay for each small numpy array; the numpy functions below
    are these same formulas, so both give the same bits."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def qrot(q, v) -> tuple[float, float, float]:
    """Rotate the 3-vector v by the unit quaternion q (q * v * q^-1), in plain floats."""
    x, y, z, w = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return x, y, z


def compose_floats(t_ab, q_ab, t_bc, q_bc) -> tuple[tuple, tuple]:
    """X_AC = X_AB * X_BC as ((x, y, z), (x, y, z, w)) tuples of floats."""
    rx, ry, rz = qrot(q_ab, t_bc)
    return (t_ab[0] + rx, t_ab[1] + ry, t_ab[2] + rz), qmul(q_ab, q_bc)


def inverse_floats(t_ab, q_ab) -> tuple[tuple, tuple]:
    """X_BA from X_AB, as tuples of floats."""
    q_ba = (-q_ab[0], -q_ab[1], -q_ab[2], q_ab[3])
    rx, ry, rz = qrot(q_ba, t_ab)
    return (-rx, -ry, -rz), q_ba


def quat_multiply(a, b) -> np.ndarray:
    """Hamilton product a * b (apply b, then a)."""
    return np.array(qmul(a, b), dtype=float)


def quat_conjugate(q) -> np.ndarray:
    return np.array([-q[0], -q[1], -q[2], q[3]], dtype=float)


def quat_rotate(q, v) -> np.ndarray:
    """Rotate the 3-vector v by the unit quaternion q."""
    return np.array(qrot(q, v), dtype=float)


def quat_normalized(q) -> np.ndarray:
    """q / |q|; raises ValueError for a zero or non-finite quaternion."""
    q = np.asarray(q, dtype=float)
    n = float(np.linalg.norm(q))
    if not math.isfinite(n) or n < 1e-12:
        raise InputError(f"quaternion {q.tolist()} has no orientation (norm {n})")
    return q / n


def unit_floats(q) -> tuple[float, float, float, float]:
    """q / |q| for a quaternion q = (x, y, z, w) of plain floats (no check: callers hold a
    quaternion that is unit up to drift)."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    return x / n, y / n, z / n, w / n


def slerp_floats(a, b, s: float) -> tuple[float, float, float, float]:
    """Spherical interpolation from the unit quaternion a (s = 0) to b (s = 1) along the
    shorter arc, in plain floats (tf lookups interpolate at every scan in several nodes)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    dot = ax * bx + ay * by + az * bz + aw * bw
    if dot < 0.0:
        bx, by, bz, bw, dot = -bx, -by, -bz, -bw, -dot
    if dot > 0.9995:  # nearly parallel: linear interpolation is exact to rounding
        return unit_floats((ax + s * (bx - ax), ay + s * (by - ay), az + s * (bz - az), aw + s * (bw - aw)))
    theta = math.acos(dot)
    ka, kb, d = math.sin((1 - s) * theta), math.sin(s * theta), math.sin(theta)
    return (ka * ax + kb * bx) / d, (ka * ay + kb * by) / d, (ka * az + kb * bz) / d, (ka * aw + kb * bw) / d


def quat_slerp(a, b, s: float) -> np.ndarray:
    """Spherical interpolation from a (s = 0) to b (s = 1) along the shorter arc."""
    return np.array(slerp_floats(a, b, s), dtype=float)


def compose(t_ab, q_ab, t_bc, q_bc) -> tuple[np.ndarray, np.ndarray]:
    """X_AC = X_AB * X_BC for transforms given as (translation, quaternion)."""
    t, q = compose_floats(t_ab, q_ab, t_bc, q_bc)
    return np.array(t, dtype=float), np.array(q, dtype=float)


def inverse(t_ab, q_ab) -> tuple[np.ndarray, np.ndarray]:
    """X_BA from X_AB."""
    t, q = inverse_floats(t_ab, q_ab)
    return np.array(t, dtype=float), np.array(q, dtype=float)


def matrix_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation matrix of fixed-axis roll, pitch, yaw (URDF's and SDF's rpy): Rz(yaw) Ry(pitch) Rx(roll)."""
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


def rpy_from_matrix(R) -> tuple[float, float, float]:
    """Fixed-axis (roll, pitch, yaw) of a rotation matrix (the inverse of matrix_from_rpy; at
    pitch ±pi/2 the roll is taken as 0)."""
    R = np.asarray(R, dtype=float)
    pitch = math.asin(max(-1.0, min(1.0, -R[2, 0])))
    if abs(R[2, 0]) > 1.0 - 1e-12:
        return 0.0, pitch, math.atan2(-R[0, 1], R[1, 1])
    return math.atan2(R[2, 1], R[2, 2]), pitch, math.atan2(R[1, 0], R[0, 0])


def pose_matrix(x: float, y: float, z: float, roll: float, pitch: float, yaw: float) -> np.ndarray:
    """4x4 homogeneous transform of a pose written x y z roll pitch yaw (SDF's <pose>)."""
    X = np.eye(4)
    X[:3, :3] = matrix_from_rpy(roll, pitch, yaw)
    X[:3, 3] = (x, y, z)
    return X


def pose_of_matrix(X) -> tuple[float, float, float, float, float, float]:
    """(x, y, z, roll, pitch, yaw) of a 4x4 homogeneous transform."""
    X = np.asarray(X, dtype=float)
    return (float(X[0, 3]), float(X[1, 3]), float(X[2, 3]), *rpy_from_matrix(X[:3, :3]))
