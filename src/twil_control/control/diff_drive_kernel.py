"""diff_drive_controller's update for one 1 kHz cycle, compiled (numba): the odometry
(diff_odometry.odometry_update / odometry_open_loop), the speed limits (speed_limiter.limited)
and the wheel speeds (skid_steer.motor_commands) in one call, each the same function the Python
API calls. The controller preallocates the arrays: limits (2, 9), per axis (linear x, angular z)
the SpeedLimiter's `row`; history (2, 2), per axis the last two limited commands; odo and window,
the WheelOdometry's `state` and `window`; left and right, each side's joint indices; out (2), the
last limited (v, w), kept across starting() as ROS keeps its last command.
"""

from __future__ import annotations

from numba import njit

from .diff_odometry import odometry_open_loop, odometry_update
from .skid_steer import motor_commands
from .speed_limiter import limited

__all__ = ["OUT_SIZE", "diff_drive_update"]

OUT_SIZE = 2


@njit(cache=True, nogil=True)
def _side_mean(position, joints):
    """The mean angle of one side's wheels, summed in order (numpy's mean for a few values)."""
    total = 0.0
    for k in range(joints.shape[0]):
        total += position[joints[k]]
    return total / joints.shape[0]


@njit(cache=True, nogil=True)
def _limit(v, row, hist, dt):
    """One axis's limited command, its history (v0, v1) moved on (SpeedLimiter.step)."""
    v = limited(v, hist[0], hist[1], dt, row)
    hist[1] = hist[0]
    hist[0] = v
    return v


@njit(cache=True, nogil=True)
def diff_drive_update(
    lin,
    ang,
    t,
    dt,
    open_loop,
    position,
    left,
    right,
    wheel_radius,
    wheel_separation,
    odo,
    window,
    limits,
    history,
    command,
    out,
):
    """The odometry from the wheel angles (or, open loop, from the last limited command), then
    the command (lin, ang) limited, as wheel speeds in command[left] and command[right].
    Returns the odometry update's result (diff_odometry: POSE_ONLY, VELOCITY_UPDATED, or a
    negative error, in which case nothing else was done)."""
    if open_loop:
        status = odometry_open_loop(odo, window, out[0], out[1], t)
    else:
        status = odometry_update(
            odo,
            window,
            _side_mean(position, left),
            _side_mean(position, right),
            t,
            wheel_radius,
            wheel_separation,
        )
    if status < 0:
        return status
    v = _limit(lin, limits[0], history[0], dt)
    w = _limit(ang, limits[1], history[1], dt)
    out[0], out[1] = v, w
    w_left, w_right = motor_commands(v, w, wheel_radius, 0.5 * wheel_separation)
    for k in range(left.shape[0]):
        command[left[k]] = w_left
    for k in range(right.shape[0]):
        command[right[k]] = w_right
    return status
