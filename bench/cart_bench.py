"""The paper's cart_linearizing_controller on TWIL + WAM: update() cost and real-time factor.

In ONE process, one after the other, for the same simulated time:
1. the bare plant: twil_wam in the default world, zero effort, no Python systems;
2. launch/twil_cart_linearizing.launch.yaml (1 kHz controller manager running the cart
   controller and joint_state_controller, the reference program at 100 Hz, odometry, ground
   truth, bag recording).
Prints both real-time factors and their ratio, the median / p99 of the controller's update()
(target p99 < 100 us) and of the whole read -> update -> write cycle, in wall and thread CPU
time, and the machine's load (the 2 cores are shared: read the CPU-time line on a busy machine).
Then, in a hot loop on the controller's own control model, the whole robot's mass matrix and
inverse dynamics by Drake (CalcMassMatrix, then CalcForceElementsContribution and
CalcInverseDynamics) against Pinocchio's (crba, rnea), the pair the update uses. Writes the
figures to bench/results/cart_bench.json.

    .venv/bin/python bench/cart_bench.py [--duration 5]
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from _common import bare_plant_rtf, instrumented_launch, percentiles, summary, write_result

LAUNCH = "launch/twil_cart_linearizing.launch.yaml"


def dynamics_costs(model, calls: int = 2000) -> tuple[float, float]:
    """(Drake, Pinocchio) microseconds per mass matrix + inverse dynamics of the control model
    at its current state, hot loop, median of 5."""
    from pydrake.multibody.tree import MultibodyForces
    import pinocchio as pin

    plant = model.plant
    context = plant.CreateDefaultContext()
    forces = MultibodyForces(plant)
    vdot = np.zeros(plant.num_velocities())

    def per_call(fn):
        samples = []
        for _ in range(5):
            start = time.perf_counter()
            for _ in range(calls):
                fn()
            samples.append((time.perf_counter() - start) / calls * 1e6)
        return float(np.median(samples))

    def drake():
        plant.CalcMassMatrix(context)
        plant.CalcForceElementsContribution(context, forces)
        plant.CalcInverseDynamics(context, vdot, forces)

    def pinocchio():
        pin.crba(model.model, model.data, model.q)
        pin.rnea(model.model, model.data, model.q, model.v, model.a)
    return per_call(drake), per_call(pinocchio)


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
    drake, pinocchio = dynamics_costs(run.controller.model)
    print(f"  M + inverse dynamics, hot loop: Drake {drake:5.1f} us, Pinocchio {pinocchio:5.1f} us "
          f"(ratio {drake / pinocchio:4.1f})")
    write_result("cart_bench", {
        "duration_s": args.duration, "bare_rtf": bare, "launch_rtf": run.rtf,
        "update_wall_us": summary(run.update_wall_us), "update_cpu_us": summary(run.update_cpu_us),
        "cycle_wall_us": summary(run.cycle_wall_us), "cycle_cpu_us": summary(run.cycle_cpu_us),
        "dynamics_hot_us": {"drake": drake, "pinocchio": pinocchio}})


if __name__ == "__main__":
    main()
