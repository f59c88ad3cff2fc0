"""The cost of robot_localization's EKF per sensor message, in microseconds: turning a message into
a measurement (the Husky's wheel odometry twist, its IMU's differential orientation and its
gyro's twist, in two_d_mode, as kalman_measurements prepares them) and fusing it (the
filter's prediction to the message's time and its correction). The localization/ layer alone
(no node, tf or topics), on a robot turning at 0.8 rad/s.

    .venv/bin/python bench/ekf_bench.py [--before DIR] [--messages 3000]

--before DIR also measures the package's source taken from DIR (an earlier commit's src/:
`git archive COMMIT src | tar -x -C /tmp/before`, then --before /tmp/before/src), each version
in its own process, in the same run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from _result import BenchResult

#: the Husky's localization.yaml: odom0 fuses vx, vy, vz, vyaw; imu0 roll, pitch, yaw
#: (differential) and their rates
ODOM_CONFIG = [False] * 6 + [True, True, True, False, False, True] + [False] * 3
IMU_CONFIG = [False] * 3 + [True] * 3 + [False] * 3 + [True] * 3 + [False] * 3
KINDS = ("odometry twist", "IMU orientation", "IMU angular velocity")
FUSE = "fuse (predict + correct)"


def measure(messages: int) -> dict[str, float]:
    """CPU µs per message of each kind's preparation and of the filter's predict+correct, the best
    of three passes of `messages` messages (CPU time: a shared machine's preemptions left out)."""
    import numpy as np

    from twil_control.localization import kalman_measurements as km
    from twil_control.localization.kalman_filter import StateEstimator
    from twil_control.localization.kalman_state import matrix_from_rpy

    odom_config, imu_config = np.array(ODOM_CONFIG), np.array(IMU_CONFIG)
    odom_cov = np.diag([1e-3, 1e-3, 1e6, 1e6, 1e6, 3e-2])
    imu_cov = np.diag([0.0, 0.0, 0.0, 1e-6, 1e-6, 1e-3])
    gyro_cov = np.diag([0.0, 0.0, 0.0, 1e-6, 1e-6, 1e-4])
    forward, zero = np.array([0.5, 0.0, 0.0]), np.zeros(3)

    def prepare(kind: str, k: int, state, memory) -> km.Measurement:
        t = 0.02 * k + 0.005 * KINDS.index(kind)
        m = km.Measurement(kind, t)
        if kind == "odometry twist":
            turn = np.array([0.0, 0.0, 0.8])
            km.prepare_twist(m, forward, turn, odom_cov, odom_config, km.IDENTITY, state, True)
        elif kind == "IMU orientation":
            pose = (matrix_from_rpy(0.001, -0.002, 0.8 * t), zero)
            args = (km.IDENTITY, None, memory, 0.02, True, False, True, state, True)
            km.prepare_pose(m, pose, imu_cov, imu_config, *args)
        else:
            km.prepare_twist(
                m, zero, np.array([0.0, 0.0, 0.79]), gyro_cov, imu_config, km.IDENTITY, state, True
            )
        return m

    def fused(n: int) -> list:
        estimator, memory, out = StateEstimator(), km.PoseSensorMemory(), []
        for k in range(n):
            for kind in KINDS:
                out.append(prepare(kind, k, estimator.state, memory))
        return out

    estimator = StateEstimator()
    for m in fused(20):  # numba compiles, or loads its cache, on the first calls
        estimator.process_measurement(m)
    figures: dict[str, float] = {}
    for kind in KINDS:
        best = float("inf")
        for _ in range(3):
            memory, state = km.PoseSensorMemory(), np.zeros(15)
            start = time.process_time()
            for k in range(messages):
                prepare(kind, k, state, memory)
            best = min(best, time.process_time() - start)
        figures[f"prepare {kind}"] = best / messages * 1e6
    measurements = fused(messages // 3)
    best = float("inf")
    for _ in range(3):
        estimator = StateEstimator()
        start = time.process_time()
        for m in measurements:
            estimator.process_measurement(m)
        best = min(best, time.process_time() - start)
    figures[FUSE] = best / (len(measurements) - 1) * 1e6  # the first initialises the filter
    return figures


def run_version(src: Path | None, messages: int) -> dict[str, float]:
    """measure() in a process of its own, with the package's source from `src` if given."""
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    command = [sys.executable, __file__, "--measure", "--messages", str(messages)]
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="an earlier checkout's src/ to compare with")
    parser.add_argument("--messages", type=int, default=3000)
    parser.add_argument("--measure", action="store_true", help=argparse.SUPPRESS)
    opts = parser.parse_args()
    if opts.measure:
        print(json.dumps(measure(opts.messages)))
        return 0
    out = BenchResult("ekf_bench", "robot_localization's EKF: CPU µs per message prepared and fused")
    versions = [("after", None)] + ([("before", opts.before.resolve())] if opts.before else [])
    results = {label: run_version(src, opts.messages) for label, src in versions}
    for label, figures in results.items():
        print(f"{label}: " + ", ".join(f"{k} {v:.1f} µs" for k, v in figures.items()), flush=True)
        for key, value in figures.items():
            out.add(
                key,
                value,
                "µs",
                row=label if opts.before else None,
                headline=key == FUSE and label == "after",
            )
    if opts.before:
        for key in results["after"]:
            out.add(key, results["before"][key] / results["after"][key], "x", row="speed-up")
    out.records.update(results)
    out.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
