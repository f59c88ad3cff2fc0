"""The paper's cart_linearizing_controller on TWIL + WAM: update() cost and real-time factor.

In ONE process, one after the other, for the same simulated time:
1. the bare plant: twil_wam in the default world, zero effort, no Python systems;
2. launch/twil_cart_linearizing.launch.yaml (1 kHz controller manager running the cart
   controller and joint_state_controller, the reference program at 100 Hz, odometry, ground
   truth, bag recording).
Prints both real-time factors and their ratio, the median / p99 of the controller's update()
(target p99 < 100 us) and of the whole read -> update -> write cycle, in wall and thread CPU
time, and the machine's load (the 2 cores are shared: read the CPU-time line on a busy machine).

    .venv/bin/python bench/cart_bench.py [--duration 5]
"""
from __future__ import annotations

import argparse
import os

from _common import bare_plant_rtf, instrumented_launch, percentiles

LAUNCH = "launch/twil_cart_linearizing.launch.yaml"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    args = parser.parse_args()
    bare = bare_plant_rtf("twil_wam", "twil_wam", args.duration)
    run = instrumented_launch(LAUNCH, args.duration, controller="cart_linearizing_controller")
    print(f"cart_linearizing_controller bench (TWIL + WAM), {args.duration:g} s simulated each")
    print(f"  bare plant (twil_wam, world, zero effort):       {bare:7.2f}x real time")
    print(f"  twil_cart_linearizing launch ({run.messages} msgs):   {run.rtf:7.2f}x real time")
    print(f"  ratio launch / bare plant:                       {run.rtf / bare:7.3f}")
    print(f"  cart_linearizing_controller update():            {percentiles(run.update_wall_us)}"
          "   (target p99 < 100 us)")
    print(f"  update(), thread CPU time:                       {percentiles(run.update_cpu_us)}")
    print(f"  whole cycle read -> update -> write, wall:       {percentiles(run.cycle_wall_us)}")
    print(f"  whole cycle, thread CPU time:                    {percentiles(run.cycle_cpu_us)}")
    print(f"  load average during the run: {' '.join(f'{v:.2f}' for v in os.getloadavg())} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
