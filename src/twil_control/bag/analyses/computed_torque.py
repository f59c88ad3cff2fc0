"""A computed-torque controller's run (the WAM: effort_controllers/ComputedTorqueController).

Topics: a trajectory_msgs/JointTrajectoryPoint ``.../command`` (the reference steps) and
``/joint_states``. Per joint: the RMS and largest deviation of the measured error from the
ideal response (54) e0 (1 + wn t) exp(-wn t) after each reference step (with the error rate
at the step, see analyses.step_response), also as a percentage of |e0| for the joints a step
moves (|e0| > 0.01 rad), and the error at the end. wn is the controller's sqrt(kp): bags do not
record parameters, so it is the `wn` option (default 5 rad/s, the lab's kp = 25, kd = 10).
"""
from __future__ import annotations

import numpy as np

from ..reader import Bag
from ..signals import rms
from .common import AnalysisSkipped, Figure, Result, arm_joint_names, joint_states, seconds
from .step_response import draw_step_tracking, step_tracking

NAME = "computed_torque"
COMMAND = "trajectory_msgs/JointTrajectoryPoint"
MOVED = 0.01   # rad: a smaller |e0| is not a step of that joint (relative figures skip it)


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
    cmd_qd = np.array([list(c.velocities) if len(c.velocities) == n else [0.0] * n for _, c in cmds], float)
    wn = options.get("wn")
    tr = step_tracking(t, q, qd, cmd_t, cmd_q, cmd_qd, wn=wn or 5.0)
    dev = tr["deviation"]
    e0_of_sample = np.abs(tr["e0"][tr["step"]])
    moved = e0_of_sample > MOVED
    rel = {}
    for j, name in enumerate(joints):
        if moved[:, j].any():
            rel[name] = float(100 * rms(dev[moved[:, j], j] / e0_of_sample[moved[:, j], j]))
    m = {
        "steps": len(cmds),
        "wn": wn or 5.0,
        "wn_source": "option" if wn else "default 5 rad/s (parameters are not recorded in bags)",
        "rms_deviation_rad": {nm: float(v) for nm, v in zip(joints, rms(dev, axis=0))},
        "max_deviation_rad": {nm: float(v) for nm, v in zip(joints, np.abs(dev).max(axis=0))},
        "rms_deviation_percent_of_e0": rel,
        "rms_deviation_all_joints_rad": float(rms(dev)),
        "final_error_rad": {nm: float(v) for nm, v in zip(joints, tr["error"][-1])},
        "step_times_s": [float(x) for x in cmd_t],
    }
    return Result(m, [Figure("ct_tracking", "Joint error q_r - q (solid) and ideal response (54) (dashed)",
                             lambda fig: draw_step_tracking(fig, tr, joints)),
                      Figure("ct_deviation", "Deviation of the error from the ideal response",
                             lambda fig: _draw_dev(fig, tr, joints))])
