"""Real-time factor of the full twil_sim launch (with bag recording) against the bare plant.

Both simulate the same world and robot for the same simulated time, in one process, one after
the other, so the ratio is meaningful on a noisy machine. Prints both factors and their ratio.

    .venv/bin/python bench/twil_sim_rtf.py [--duration 5]
"""

from __future__ import annotations

import argparse

from _common import BenchResult, bare_plant_rtf, launch_rtf


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    args = parser.parse_args()
    result = BenchResult(
        "twil_sim_rtf",
        "TWIL + WAM with zero effort: the twil_sim launch (1 kHz ros_control, "
        "odometry, ground truth, bag) against the bare Drake plant, same simulated time",
    )
    bare = bare_plant_rtf("twil_wam", "twil_wam", args.duration)
    full, messages = launch_rtf("launch/twil_sim.launch.yaml", args.duration)
    print(f"twil_sim bench, {args.duration:g} s simulated each")
    print(f"  bare plant (TWIL + WAM, world):        {bare:6.2f}x real time")
    print(f"  twil_sim launch (1 kHz ros_control, recording {messages} msgs): {full:6.2f}x real time")
    print(f"  ratio launch / bare plant:             {full / bare:6.3f}")
    result.add("bare_plant_rtf", bare, "x real time")
    result.add("launch_rtf", full, "x real time", headline="twil_sim launch, real-time factor")
    result.add("launch_over_bare", full / bare)
    result.add("simulated_s", args.duration, "s")
    result.write()


if __name__ == "__main__":
    main()
