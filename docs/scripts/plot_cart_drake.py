#!/usr/bin/env python3
"""Corrected vs printed backstepping law in the Drake simulation of TWIL + WAM.

Run:  .venv/bin/python docs/scripts/plot_cart_drake.py [--duration 15] [--goal "2 1 1.5708"] [--out docs/img]
Runs launch/twil_cart_linearizing.launch.yaml twice (law:=corrected and law:=printed, pose from
ground truth, the same goal and arm program), records each run's bag next to the figure, and
writes docs/img/drake_corrected_vs_printed.png: e, alpha, psi, V1 and the wheel torques of the
controller's status topic, and the path from ground truth, the two laws side by side. Prints the
final position and heading errors of both runs.
"""
from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from rosbags.highlevel import AnyReader  # noqa: E402

from twil_control import PACKAGE_ROOT  # noqa: E402
from twil_control.launch.loader import load_launch  # noqa: E402
from twil_control.launch.runner import RunOptions, run  # noqa: E402

STATUS = "/twil/ros_control/cart_linearizing_controller/status"
TRUTH = "/twil/ground_truth/odom"


def run_law(law: str, goal: str, duration: float, bag: Path) -> dict:
    plan = load_launch(PACKAGE_ROOT / "launch/twil_cart_linearizing.launch.yaml",
                       {"law": law, "goal": goal, "pose_source": "ground_truth"})
    result = run(plan, RunOptions(duration=duration, bag=bag))
    if result.error:
        raise result.error
    rows, path = [], []
    with AnyReader([bag]) as reader:
        conns = [c for c in reader.connections if c.topic in (STATUS, TRUTH)]
        for conn, t, raw in reader.messages(connections=conns):
            m = reader.deserialize(raw, conn.msgtype)
            if conn.topic == STATUS:
                rows.append((t * 1e-9, m.e, m.alpha, m.psi, m.V1, m.tau_right, m.tau_left))
            else:
                q = m.pose.pose.orientation
                path.append((m.pose.pose.position.x, m.pose.pose.position.y,
                             math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y ** 2 + q.z ** 2))))
    return {"status": np.array(rows), "path": np.array(path)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--goal", default="2 1 1.5707963267948966", help='"x y theta"')
    parser.add_argument("--out", type=Path, default=PACKAGE_ROOT / "docs/img")
    args = parser.parse_args()
    goal = [float(v) for v in args.goal.split()]
    runs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for law in ("corrected", "printed"):
            runs[law] = run_law(law, args.goal, args.duration, Path(tmp) / f"{law}.bag")
    fig, axes = plt.subplots(6, 2, figsize=(11, 15))
    for col, (law, data) in enumerate(runs.items()):
        s = data["status"]
        t = s[:, 0]
        for row, (k, label) in enumerate([(1, "e (m)"), (2, "alpha (rad)"), (3, "psi (rad)"), (4, "V1")]):
            axes[row, col].plot(t, s[:, k])
            axes[row, col].set_ylabel(label)
        axes[3, col].set_yscale("log")
        axes[4, col].plot(t, s[:, 5], label="tau right")
        axes[4, col].plot(t, s[:, 6], label="tau left")
        axes[4, col].set_ylabel("wheel torque (N m)")
        axes[4, col].set_xlabel("t (s)")
        axes[4, col].legend(loc="upper right")
        p = data["path"]
        axes[5, col].plot(p[:, 0], p[:, 1])
        axes[5, col].plot([p[0, 0]], [p[0, 1]], "ko", label="start")
        axes[5, col].plot([goal[0]], [goal[1]], "r*", markersize=12, label="goal")
        axes[5, col].axis("equal")
        axes[5, col].legend(loc="lower right")
        axes[5, col].set_xlabel("x (m)")
        axes[5, col].set_ylabel("y (m)")
        axes[0, col].set_title(f"{law} law (Drake, TWIL + WAM, ground-truth pose)")
        x, y, th = p[-1]
        print(f"{law:9s}: final position error {100 * math.hypot(x - goal[0], y - goal[1]):.2f} cm, heading error "
              f"{math.degrees(abs(math.remainder(th - goal[2], 2 * math.pi))):.2f} deg, V1 {s[-1, 4]:.3g}")
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    out = args.out / "drake_corrected_vs_printed.png"
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
