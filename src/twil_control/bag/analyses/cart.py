"""The cart_linearizing_controller's run: goal reached, convergence, Lyapunov V1, torques, arm.

Errors against the ground truth and against the wheel odometry, the frame the controller
converges in with its odometry pose source; V1's rise over its running minimum (V1 must not rise
under the backstepping law); the arm's tracking against its second-order-held reference and the
ideal response (54). The metrics: docs/analyze.md.
"""

from __future__ import annotations

import math

import numpy as np

from ..reader import Bag
from ..signals import max_rise, rms, settle_time, wrap
from .common import (
    ODOMETRY_FIELDS,
    AnalysisSkipped,
    Figure,
    Result,
    arm_joint_names,
    draw_lines,
    find_ground_truth,
    find_odometry,
    joint_fields,
    joint_states,
    odometry_poses,
    seconds,
)
from .step_response import draw_step_tracking, step_tracking, trajectory_tracking

NAME = "cart_controller"
STATUS = "twil_control/CartLinearizingStatus"
COMMAND = "twil_control/CartLinearizingCommand"


def detect(bag: Bag) -> dict | None:
    status = bag.topics_of_type(STATUS)
    if not status:
        return None
    ns = status[0].rsplit("/", 1)[0]
    commands = [t for t in bag.topics_of_type(COMMAND) if t.startswith(ns + "/")] or bag.topics_of_type(
        COMMAND
    )
    return {
        "status": status[0],
        "command": commands[0] if commands else None,
        "ground_truth": find_ground_truth(bag, ns),
        "odometry": find_odometry(bag, ns),
        "joint_states": "/joint_states" if "/joint_states" in bag.topics else None,
    }


def analyze(bag: Bag, topics: dict, options: dict) -> Result:
    if not topics["command"]:
        raise AnalysisSkipped("no CartLinearizingCommand topic: no reference to measure against")
    pos_tol = options.get("position_tolerance", 0.01)
    yaw_tol = math.radians(options.get("heading_tolerance_deg", 1.0))
    cmds = bag.messages(topics["command"])
    if not cmds:
        raise AnalysisSkipped(f"{topics['command']} holds no command")
    cmd_t = seconds(bag, [c[0] for c in cmds])
    ref = np.array([[m.platform_pose.x, m.platform_pose.y, m.platform_pose.theta] for _, m in cmds])
    final_ref = ref[-1]
    # the first command of the final platform reference (arm-only changes keep it)
    k0 = len(ref) - 1
    while k0 > 0 and np.allclose(ref[k0 - 1], final_ref, atol=1e-12):
        k0 -= 1
    t_ref = cmd_t[k0]
    m: dict = {
        "commands": len(cmds),
        "reference_x_m": float(final_ref[0]),
        "reference_y_m": float(final_ref[1]),
        "reference_theta_rad": float(final_ref[2]),
        "reference_time_s": float(t_ref),
    }
    figures: list[Figure] = []
    notes: list[str] = []
    # one pass over the chunks for every topic this analysis reads
    status_fields = ["e", "alpha", "psi", "V1", "tau_right", "tau_left", "torque_scale"]
    wanted = {
        topics["status"]: status_fields,
        topics["ground_truth"]: ODOMETRY_FIELDS,
        topics["odometry"]: ODOMETRY_FIELDS,
    }
    joints = None
    n_arm = len(cmds[-1][1].arm_positions)
    if topics["joint_states"] and n_arm and all(len(c.arm_positions) == n_arm for _, c in cmds):
        names = list(bag.first_message(topics["joint_states"]).name)
        joints = arm_joint_names(names, n_arm, options.get("arm_joints"))
        wanted[topics["joint_states"]] = joint_fields(bag, topics["joint_states"], joints)[1]
    bag.prefetch(wanted)

    m["converge_tolerance"] = f"{100 * pos_tol:g} cm, {math.degrees(yaw_tol):g} deg"
    paths = {}
    for source, suffix in (("ground_truth", ""), ("odometry", "_odometry")):
        if topics[source]:
            tp, pp = odometry_poses(bag, topics[source])
            pos_err, yaw_err, converge = _goal_errors(tp, pp, final_ref, t_ref, pos_tol, yaw_tol)
            m[f"final_position_error{suffix}_m"] = float(pos_err[-1])
            m[f"final_heading_error{suffix}_deg"] = float(math.degrees(yaw_err[-1]))
            m[f"converge_time{suffix}_s"] = converge
            paths[source.replace("_", " ")] = pp
    if topics["ground_truth"]:
        tg, pg = odometry_poses(bag, topics["ground_truth"])
        pos_err, yaw_err, _ = _goal_errors(tg, pg, final_ref, t_ref, pos_tol, yaw_tol)
        m["end_time_s"] = float(tg[-1])
        figures.append(
            Figure(
                "cart_error",
                "Distance and heading error to the goal (ground truth)",
                lambda fig, tg=tg, pe=pos_err, ye=yaw_err: _draw_errors(fig, tg, pe, ye, t_ref),
            )
        )
    else:
        notes.append("no ground-truth odometry: errors and convergence against the truth not measured")
    if paths:
        figures.append(
            Figure(
                "cart_path",
                f"Platform path ({', '.join(paths)}) and goal",
                lambda fig, paths=paths: _draw_path(fig, paths, final_ref),
            )
        )

    t_ns, st = bag.columns(topics["status"], status_fields)
    t_s = seconds(bag, t_ns)
    seg = t_s > t_ref + 1e-9
    if seg.any():
        v1 = st["V1"][seg]
        rise = max_rise(v1)
        m["V1_at_reference"] = float(v1[0])
        m["V1_final"] = float(v1[-1])
        m["V1_max_rise"] = rise
        m["V1_max_rise_relative"] = rise / v1[0] if v1[0] > 0 else None
        m["V1_increased"] = bool(rise > 1e-12 * max(v1[0], 1e-300))
    m["peak_tau_right_Nm"] = float(np.abs(st["tau_right"]).max()) if len(t_s) else None
    m["peak_tau_left_Nm"] = float(np.abs(st["tau_left"]).max()) if len(t_s) else None
    dt = np.median(np.diff(t_s)) if len(t_s) > 1 else 0.0
    m["torque_scaled_s"] = float((st["torque_scale"] < 1.0).sum() * dt)
    figures.append(
        Figure(
            "cart_polar",
            "Polar coordinates e, alpha, psi (20)-(22) (controller status)",
            lambda fig, t=t_s, s=st: _draw_polar(fig, t, s, t_ref),
        )
    )
    figures.append(
        Figure(
            "cart_v1",
            "Lyapunov function V1 (controller status)",
            lambda fig, t=t_s, v=st["V1"]: _draw_v1(fig, t, v, t_ref),
        )
    )
    figures.append(
        Figure(
            "cart_torques",
            "Applied wheel torques (shaded: scaled to the limit)",
            lambda fig, t=t_s, s=st: _draw_torques(fig, t, s),
        )
    )

    if joints:
        tj, q, qd = joint_states(bag, topics["joint_states"], joints)
        cmd_q = np.array([list(c.arm_positions) for _, c in cmds], dtype=float)
        wn = options.get("wn") or 5.0
        if all(len(c.arm_velocities) == n_arm and len(c.arm_accelerations) == n_arm for _, c in cmds):
            # samples of a trajectory (nodes/cart_reference.py): the controller holds them
            stamp_t = np.array([_stamp(c) for _, c in cmds])
            stamp_t = np.where(stamp_t > 0.0, stamp_t, cmd_t)
            tr = trajectory_tracking(
                tj,
                q,
                qd,
                stamp_t,
                cmd_q,
                np.array([list(c.arm_velocities) for _, c in cmds], dtype=float),
                np.array([list(c.arm_accelerations) for _, c in cmds], dtype=float),
                wn=wn,
                timeout=options.get("reference_timeout", 0.1),
            )
            m["arm_reference"] = "trajectory samples held to second order"
        else:
            tr = step_tracking(tj, q, qd, cmd_t, cmd_q, wn=wn)
            m["arm_reference"] = "steps"
        m["arm_rms_error_rad"] = {j: float(v) for j, v in zip(joints, rms(tr["error"], axis=0))}
        m["arm_rms_error_all_joints_rad"] = float(rms(tr["error"]))
        m["arm_rms_deviation_from_ideal_rad"] = {
            j: float(v) for j, v in zip(joints, rms(tr["deviation"], axis=0))
        }
        m["arm_rms_deviation_all_joints_rad"] = float(rms(tr["deviation"]))
        m["arm_final_error_rad"] = {j: float(v) for j, v in zip(joints, tr["error"][-1])}
        m["arm_wn"] = wn
        figures.append(
            Figure(
                "cart_arm",
                "Arm joint error q_r - q (solid) and ideal response (54) (dashed)",
                lambda fig, tr=tr, joints=joints: draw_step_tracking(fig, tr, joints),
            )
        )
    return Result(m, figures, notes)


def _stamp(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def _goal_errors(t, poses, goal, t_ref, pos_tol, yaw_tol):
    """(distance to the goal, |heading error|, convergence time after t_ref or None) of a pose series."""
    pos_err = np.hypot(poses[:, 0] - goal[0], poses[:, 1] - goal[1])
    yaw_err = np.abs(wrap(poses[:, 2] - goal[2]))
    after = t >= t_ref
    ts = settle_time(t[after], (pos_err[after] <= pos_tol) & (yaw_err[after] <= yaw_tol))
    return pos_err, yaw_err, None if ts is None else float(ts - t_ref)


def _draw_path(fig, paths: dict, goal) -> None:
    ax = fig.add_subplot(1, 1, 1)
    for label, p in paths.items():
        ax.plot(
            p[:, 0],
            p[:, 1],
            lw=1.4 if label == "ground truth" else 1.0,
            ls="-" if label == "ground truth" else "--",
            label=label,
        )
    start = next(iter(paths.values()))[0]
    ax.plot(start[0], start[1], "ko", label="start")
    ax.plot(goal[0], goal[1], "*", ms=12, label="goal")
    ax.arrow(goal[0], goal[1], 0.2 * math.cos(goal[2]), 0.2 * math.sin(goal[2]), width=0.01)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)


def _draw_errors(fig, t, pos_err, yaw_err, t_ref) -> None:
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    draw_lines(ax1, t, {"distance": pos_err}, "distance (m)", logy=True)
    draw_lines(ax2, t, {"heading": np.degrees(yaw_err)}, "|heading error| (deg)", logy=True)
    for ax in (ax1, ax2):
        ax.axvline(t_ref, color="k", lw=0.8, ls=":")
    ax2.set_xlabel("time (s)")


def _draw_polar(fig, t, st, t_ref) -> None:
    axes = fig.subplots(3, 1, sharex=True)
    for ax, (key, label) in zip(axes, (("e", "e (m)"), ("alpha", "alpha (rad)"), ("psi", "psi (rad)"))):
        draw_lines(ax, t, {key: st[key]}, label)
        ax.axvline(t_ref, color="k", lw=0.8, ls=":")
    axes[-1].set_xlabel("time (s)")


def _draw_v1(fig, t, v, t_ref) -> None:
    ax = fig.add_subplot(1, 1, 1)
    pos = v > 0
    draw_lines(ax, t[pos], {"V1": v[pos]}, "V1", logy=True)
    ax.axvline(t_ref, color="k", lw=0.8, ls=":")
    ax.set_xlabel("time (s)")


def _draw_torques(fig, t, st) -> None:
    ax = fig.add_subplot(1, 1, 1)
    draw_lines(ax, t, {"tau_right": st["tau_right"], "tau_left": st["tau_left"]}, "N m")
    ax.fill_between(
        t,
        0,
        1,
        where=st["torque_scale"] < 1.0,
        transform=ax.get_xaxis_transform(),
        color="0.8",
        alpha=0.6,
        lw=0,
    )
    ax.set_xlabel("time (s)")
