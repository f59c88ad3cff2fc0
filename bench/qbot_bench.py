"""Real-time factor of the qbot_sim launch (with bag recording) against the bare qbot plant.

Both simulate qbot in the default world for the same simulated time, in one process, one after
the other, so the ratio is meaningful on a noisy machine. Prints both factors and their ratio.
The bare plant has zero actuation and no Python systems; the launch adds the 1 kHz controller
manager (joint_state_controller + the PWM skid-steer drive), wheel odometry, ground truth, the
cmd_vel sequence and the recorder.

    .venv/bin/python bench/qbot_bench.py [--duration 10]
"""

from __future__ import annotations

import argparse

from _common import BenchResult, bare_plant_rtf, launch_rtf


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run")
    args = parser.parse_args()
    result = BenchResult(
        "qbot_bench",
        "qbot driving its cmd_vel sequence: the qbot_sim launch (PWM drive at 1 kHz, "
        "laser, odometry, bag) against the bare Drake plant, same simulated time",
    )
    bare = bare_plant_rtf("qbot", "qbot", args.duration)
    full, messages = launch_rtf("launch/qbot_sim.launch.yaml", args.duration)
    print(f"qbot bench, {args.duration:g} s simulated each")
    print(f"  bare plant (qbot, default world, zero effort): {bare:6.2f}x real time")
    print(f"  qbot_sim launch (1 kHz ros_control, recording {messages} msgs): {full:6.2f}x real time")
    print(f"  ratio launch / bare plant:                     {full / bare:6.3f}")
    result.add("bare_plant_rtf", bare, "x real time")
    result.add("launch_rtf", full, "x real time", headline="qbot_sim launch, real-time factor")
    result.add("launch_over_bare", full / bare)
    result.add("simulated_s", args.duration, "s")
    result.write()


if __name__ == "__main__":
    main()
