"""ros_control on the WAM: real-time factors and the controller manager's per-update cost.

In ONE process, one after the other, for the same simulated time:
1. the bare plant: wam_fixed in the default world, zero effort, no Python systems;
2. launch/wam_computed_torque.launch.yaml (1 kHz controller manager running
   joint_state_controller at 100 Hz and the computed-torque controller, a timed reference
   sequence, bag recording of every topic).
Prints both real-time factors, their ratio, and the median / p99 wall time of one
read -> controller_manager.update -> write cycle (targets: p99 < 100 us, launch >= 0.5 x bare),
the same cycles' thread CPU time (immune to other processes taking the core: on a shared
machine the wall-time p99 shows the OS scheduler's time slices), the machine's load, and the
cost of the control model's inverse dynamics alone.

Note: with zero effort the bare arm falls and its links hit the floor and each other, so the
"bare" plant pays for contact the controlled arm never makes; the ratio can exceed 1.

    .venv/bin/python bench/ros_control_bench.py [--duration 5]
"""

from __future__ import annotations

import argparse
import os

import numpy as np
from _common import BenchResult, bare_plant_rtf, instrumented_launch, percentiles

LAUNCH = "launch/wam_computed_torque.launch.yaml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    args = parser.parse_args()
    result = BenchResult(
        "ros_control_bench",
        "the WAM under computed torque: the controller manager's read -> "
        "update -> write cycle at 1 kHz (wall and thread CPU time), and the launch's real-time "
        "factor against the bare plant",
    )
    bare = bare_plant_rtf("wam_fixed", "wam", args.duration)
    run = instrumented_launch(LAUNCH, args.duration, controller="computed_torque_controller")
    print(f"ros_control bench (WAM, computed torque), {args.duration:g} s simulated each")
    print(f"  bare plant (wam_fixed, world, zero effort):      {bare:7.2f}x real time")
    print(f"  wam_computed_torque launch (recording {run.messages} msgs): {run.rtf:7.2f}x real time")
    print(f"  ratio launch / bare plant:                       {run.rtf / bare:7.3f}   (target >= 0.5)")
    print(
        f"  controller manager cycle ({len(run.cycle_wall_us)} cycles): {percentiles(run.cycle_wall_us)}"
        "   (target p99 < 100 us)"
    )
    print(f"  same cycles, thread CPU time:                    {percentiles(run.cycle_cpu_us)}")
    print(f"  of which computed_torque_controller update():    {percentiles(run.update_wall_us)}")
    print(
        f"  control model inverse dynamics (Drake):          {run.controller.model.measure_cost() * 1e6:6.1f} us "
        "per call (median)"
    )
    print(
        f"  load average during the run: {' '.join(f'{v:.2f}' for v in os.getloadavg())} on {os.cpu_count()} cores"
    )
    result.add("bare_plant_rtf", bare, "x real time")
    result.add("launch_rtf", run.rtf, "x real time")
    result.add(
        "launch_over_bare",
        run.rtf / bare,
        target=">= 0.5",
        headline="WAM computed torque launch / bare plant",
    )
    for label, us in (
        ("cycle, wall", run.cycle_wall_us),
        ("cycle, thread CPU", run.cycle_cpu_us),
        ("update(), wall", run.update_wall_us),
    ):
        result.add("median", np.median(us), "us", row=label)
        result.add(
            "p99",
            np.percentile(us, 99),
            "us",
            row=label,
            **(
                {"target": "< 100", "headline": "WAM 1 kHz cycle p99, wall"} if label == "cycle, wall" else {}
            ),
        )
    result.write()


if __name__ == "__main__":
    main()
