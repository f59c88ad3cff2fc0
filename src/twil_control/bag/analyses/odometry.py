"""Wheel odometry against ground truth (qbot's /qbot/odom, TWIL's /twil/odom), PWM duty.

Odometry starts at zero in its own frame; it is put into the world frame by the transform
that makes its first pose coincide with the ground truth's (signals.align_start), then
compared at the odometry's times (ground truth interpolated): final and largest position and
yaw error, and the path length driven (ground truth) and integrated (odometry). If the skid-
steer controller's ``~pwm_duty`` (std_msgs/UInt8MultiArray [left, right], 0..254, 127 = 0 V)
is recorded: mean, min, max per side and the share of samples at full scale (0 or 254).
"""

from __future__ import annotations

import math

import numpy as np

from ..reader import Bag
from ..signals import align_start, compose, interp_poses, path_length, wrap
from .common import Figure, Result, draw_lines, odometry_poses, seconds

NAME = "odometry"
PWM_FULL = (0, 254)


def detect(bag: Bag) -> dict | None:
    odoms = bag.topics_of_type("nav_msgs/Odometry")
    for gt in (t for t in odoms if "ground_truth" in t):
        ns = gt.split("/ground_truth")[0]
        wheel = [t for t in odoms if "ground_truth" not in t and t.startswith(ns + "/")]
        if wheel:
            pwm = [t for t in bag.topics_of_type("std_msgs/UInt8MultiArray") if t.endswith("pwm_duty")]
            return {
                "odometry": sorted(wheel, key=len)[0],
                "ground_truth": gt,
                "pwm_duty": pwm[0] if pwm else None,
            }
    return None


def analyze(bag: Bag, topics: dict, options: dict) -> Result:
    to, po = odometry_poses(bag, topics["odometry"])
    tg, pg = odometry_poses(bag, topics["ground_truth"])
    T = align_start(to, po, tg, pg)
    inside = (to >= tg[0]) & (to <= tg[-1])
    to, po = to[inside], po[inside]
    pw = compose(T, po)
    gi = interp_poses(to, tg, pg)
    pos_err = np.hypot(pw[:, 0] - gi[:, 0], pw[:, 1] - gi[:, 1])
    yaw_err = np.abs(wrap(pw[:, 2] - gi[:, 2]))
    m = {
        "duration_s": float(to[-1] - to[0]),
        "final_position_error_m": float(pos_err[-1]),
        "max_position_error_m": float(pos_err.max()),
        "final_yaw_error_deg": float(math.degrees(yaw_err[-1])),
        "max_yaw_error_deg": float(math.degrees(yaw_err.max())),
        "path_length_m": path_length(pg[:, 0], pg[:, 1]),
        "odometry_path_length_m": path_length(po[:, 0], po[:, 1]),
    }
    figures = [
        Figure(
            "odometry_path",
            "Path: ground truth and wheel odometry (aligned at the start)",
            lambda fig: _draw_path(fig, pg, pw),
        ),
        Figure(
            "odometry_error",
            "Odometry error against ground truth",
            lambda fig: _draw_err(fig, to, pos_err, yaw_err),
        ),
    ]
    if topics.get("pwm_duty"):
        t, c = bag.columns(topics["pwm_duty"], ["data[0]", "data[1]"])
        for side, key in (("left", "data[0]"), ("right", "data[1]")):
            d = c[key]
            m[f"pwm_{side}_mean"] = float(d.mean())
            m[f"pwm_{side}_min"] = float(d.min())
            m[f"pwm_{side}_max"] = float(d.max())
            m[f"pwm_{side}_full_scale_fraction"] = float(np.isin(d, PWM_FULL).mean())
        ts = seconds(bag, t)
        figures.append(Figure("pwm_duty", "PWM duty (0..254, 127 = 0 V)", lambda fig: _draw_pwm(fig, ts, c)))
    return Result(m, figures)


def _draw_path(fig, pg, pw) -> None:
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(pg[:, 0], pg[:, 1], lw=1.4, label="ground truth")
    ax.plot(pw[:, 0], pw[:, 1], lw=1.2, ls="--", label="odometry")
    ax.plot(pg[0, 0], pg[0, 1], "o", color="k", label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)


def _draw_err(fig, t, pos_err, yaw_err) -> None:
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    draw_lines(ax1, t, {"position": pos_err}, "position error (m)")
    draw_lines(ax2, t, {"yaw": np.degrees(yaw_err)}, "|yaw error| (deg)")
    ax2.set_xlabel("time (s)")


def _draw_pwm(fig, t, c) -> None:
    ax = fig.add_subplot(1, 1, 1)
    draw_lines(ax, t, {"left": c["data[0]"], "right": c["data[1]"]}, "duty (ticks)")
    ax.set_xlabel("time (s)")
