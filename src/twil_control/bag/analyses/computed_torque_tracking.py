"""A computed-torque controller's run (the WAM: effort_controllers/ComputedTorqueController).

Per joint: the deviation from (54) relative to the law's commands, the tracking error and its
deviation from (54)'s ideal response, and effort clipping. Bags do not record parameters, so Kp
and Kd come from the `wn` option. The metrics: docs/analyze.md.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from functools import lru_cache

import numpy as np

from twil_control import PACKAGE_ROOT

from ..reader import Bag
from ..signals import rms
from .common import AnalysisSkipped, Figure, Result, arm_joint_names, joint_states, seconds
from .step_response import (
    draw_deviation,
    draw_step_tracking,
    error_dynamics_residual,
    step_tracking,
    trajectory_tracking,
)

NAME = "computed_torque"
COMMAND = "trajectory_msgs/JointTrajectoryPoint"
MOVED = 0.01  # rad: a smaller |e0| is not a step of that joint (relative figures skip it)


def detect(bag: Bag) -> dict | None:
    commands = [t for t in bag.topics_of_type(COMMAND) if t.endswith("/command")]
    if not commands or "/joint_states" not in bag.topics:
        return None
    return {"command": commands[0], "joint_states": "/joint_states"}


def analyze(bag: Bag, topics: dict, options: dict) -> Result:
    cmds = bag.messages(topics["command"])
    if not cmds:
        raise AnalysisSkipped(f"{topics['command']} holds no reference")
    n = len(cmds[0][1].positions)
    if any(len(c.positions) != n for _, c in cmds):
        raise AnalysisSkipped("references of different lengths")
    names = list(bag.first_message(topics["joint_states"]).name)
    joints = arm_joint_names(names, n, options.get("joints") or options.get("arm_joints"))
    t, q, qd = joint_states(bag, topics["joint_states"], joints)
    cmd_t = seconds(bag, [c[0] for c in cmds])
    cmd_q = np.array([list(c.positions) for _, c in cmds], float)
    cmd_qd, cmd_qdd = (
        np.array([list(getattr(c, f)) if len(getattr(c, f)) == n else [0.0] * n for _, c in cmds], float)
        for f in ("velocities", "accelerations")
    )
    trajectory = all(len(c.velocities) == n and len(c.accelerations) == n for _, c in cmds)
    wn = options.get("wn")
    w = wn or 5.0
    timeout = options.get("reference_timeout", 0.1)
    if trajectory:
        tr = trajectory_tracking(t, q, qd, cmd_t, cmd_q, cmd_qd, cmd_qdd, wn=w, timeout=timeout)
    else:
        tr = step_tracking(t, q, qd, cmd_t, cmd_q, cmd_qd, wn=w)
    res = error_dynamics_residual(t, q, qd, cmd_t, cmd_q, cmd_qd, cmd_qdd, w * w, 2.0 * w, timeout)
    dev = tr["deviation"]
    e0_of_sample = (
        np.abs(tr["e0"][tr["step"]]) if not trajectory else np.abs(tr["e0"][np.zeros_like(tr["step"])])
    )
    moved = e0_of_sample > MOVED
    rel = {
        name: float(100 * rms(dev[moved[:, j], j] / e0_of_sample[moved[:, j], j]))
        for j, name in enumerate(joints)
        if moved[:, j].any()
    }
    percent = {nm: (None if np.isnan(v) else float(v)) for nm, v in zip(joints, res["percent"])}
    m = {
        "reference": "trajectory samples held to second order" if trajectory else "steps",
        "commands": len(cmds),
        "wn": w,
        "wn_source": "option" if wn else "default 5 rad/s (parameters are not recorded in bags)",
        "deviation_from_54_percent": percent,
        "deviation_from_54_max_percent": max((v for v in percent.values() if v is not None), default=None),
        "rms_error_rad": {nm: float(v) for nm, v in zip(joints, rms(tr["error"], axis=0))},
        "rms_deviation_rad": {nm: float(v) for nm, v in zip(joints, rms(dev, axis=0))},
        "max_deviation_rad": {nm: float(v) for nm, v in zip(joints, np.abs(dev).max(axis=0))},
        "rms_deviation_all_joints_rad": float(rms(dev)),
        "final_error_rad": {nm: float(v) for nm, v in zip(joints, tr["error"][-1])},
    }
    if rel:
        m["rms_deviation_percent_of_e0"] = rel
    if not trajectory:
        m["steps"] = len(cmds)
        m["step_times_s"] = [float(x) for x in cmd_t]
    notes = _effort_metrics(bag, topics["joint_states"], joints, options.get("effort_limits"), m)
    figures = [
        Figure(
            "ct_tracking",
            "Joint error q_r - q (solid) and ideal response (54) (dashed)",
            lambda fig: draw_step_tracking(fig, tr, joints),
        ),
        Figure(
            "ct_residual",
            "e'' + Kd e' + Kp e per interval between joint states (0 for (54))",
            lambda fig: draw_deviation(fig, {"t": res["t"], "deviation": res["residual"]}, joints, "rad/s^2"),
        ),
    ]
    if not trajectory:
        figures.append(
            Figure(
                "ct_deviation",
                "Deviation of the error from the ideal response",
                lambda fig: draw_deviation(fig, tr, joints, "rad"),
            )
        )
    return Result(m, figures, notes)


def _effort_metrics(bag: Bag, topic: str, joints: list[str], limits, m: dict) -> list[str]:
    """Peak |effort| against the limits and the intervals at a limit, into m; notes."""
    first = bag.first_message(topic)
    names = list(first.name)
    if len(first.effort) != len(names):
        return ["no efforts in /joint_states: clipping not measured"]
    limits = dict(limits) if limits else description_effort_limits(tuple(joints))
    missing = [j for j in joints if j not in limits]
    if missing:
        return [f"no effort limit known for {', '.join(missing)} (pass effort_limits): clipping not measured"]
    fields = [f"effort[{names.index(j)}]" for j in joints]
    t_ns, cols = bag.columns(topic, fields)
    t = seconds(bag, t_ns)
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    m["peak_effort_fraction_of_limit"], m["effort_clipped_s"], clipped = {}, {}, {}
    for j, f in zip(joints, fields):
        effort, limit = np.abs(cols[f]), float(limits[j])
        at_limit = effort >= limit * (1.0 - 1e-9)
        m["peak_effort_fraction_of_limit"][j] = float(effort.max() / limit)
        m["effort_clipped_s"][j] = float(at_limit.sum() * dt)
        if at_limit.any():
            clipped[j] = ", ".join(f"{a:.2f}-{b:.2f} s" for a, b in _intervals(t, at_limit, dt))
    m["effort_clipped"] = clipped or "never"
    return []


def _intervals(t, flags, dt: float) -> list[tuple[float, float]]:
    """[(start, end)] of the runs of True in flags (end: the last flagged sample plus dt)."""
    edges = np.diff(np.concatenate([[0], flags.astype(int), [0]]))
    starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0] - 1
    return [(float(t[a]), float(t[b] + dt)) for a, b in zip(starts, ends)]


@lru_cache(maxsize=8)
def description_effort_limits(joints: tuple[str, ...]) -> dict[str, float]:
    """{joint: effort limit} from this package's URDFs (sim/robots) for the named joints, where
    one description names the joint (a name two descriptions give different limits is left out)."""
    found: dict[str, set[float]] = {}
    for urdf in sorted((PACKAGE_ROOT / "sim/robots").rglob("*.urdf")):
        for joint in ET.parse(urdf).getroot().iter("joint"):
            limit = joint.find("limit")
            if joint.get("name") in joints and limit is not None and limit.get("effort"):
                found.setdefault(joint.get("name"), set()).add(float(limit.get("effort")))
    return {j: v.pop() for j, v in found.items() if len(v) == 1}
