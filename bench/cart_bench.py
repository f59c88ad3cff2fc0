"""The paper's cart_linearizing_controller on TWIL + WAM: update() cost and real-time factor.

In ONE process, one after the other, for the same simulated time:
1. the bare plant: twil_wam in the default world, zero effort, no Python systems;
2. launch/twil_cart_linearizing.launch.yaml (1 kHz controller manager running the cart
   controller and joint_state_controller, the reference program at 100 Hz, odometry, ground
   truth, bag recording).
Prints both real-time factors and their ratio, the median / p99 of the controller's update()
(target p99 < 100 us) and of the whole read -> update -> write cycle, in wall and thread CPU
time, and the machine's load (the 2 cores are shared: read the CPU-time line on a busy machine).
Then the whole robot's mass matrix and inverse dynamics, hot in a loop and with the caches
evicted before each call (as in the launch, where the plant's step runs between two updates):
Drake (CalcMassMatrix, CalcForceElementsContribution, CalcInverseDynamics), the compiled kernel
the update uses (control/rigid_body_kernel.py, one kinematics pass for both) and, when the
`pin` package is installed, Pinocchio (crba, rnea) on a model built from the same URDFs. Writes
the figures to bench/results/.

    .venv/bin/python bench/cart_bench.py [--duration 5]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from _common import BenchResult, bare_plant_rtf, instrumented_launch, percentiles

LAUNCH = "launch/twil_cart_linearizing.launch.yaml"


def pinocchio_model(model):
    """Pinocchio's model of twil_wam from the same URDFs (free base; the WAM appended at the weld
    that the model directives declare, its pose read from Drake's plant), or None without `pin`."""
    try:
        import pinocchio as pin
    except ImportError:
        return None
    from twil_control import PACKAGE_ROOT

    plant = model.plant
    robot = pin.buildModelFromUrdf(str(PACKAGE_ROOT / "sim/robots/twil/twil.urdf"), pin.JointModelFreeFlyer())
    arm = pin.buildModelFromUrdf(str(PACKAGE_ROOT / "sim/robots/wam/wam.urdf"))
    X = plant.CalcRelativeTransform(
        plant.CreateDefaultContext(), plant.GetFrameByName("wam_mount"), plant.GetFrameByName("wam_base_link")
    )
    robot = pin.appendModel(
        robot, arm, robot.getFrameId("wam_mount"), pin.SE3(X.rotation().matrix(), X.translation())
    )
    robot.gravity.linear[:] = plant.gravity_field().gravity_vector()
    return robot


def dynamics_costs(model, calls: int = 300) -> dict:
    """Median microseconds per mass matrix + inverse dynamics of the control model, hot (best of
    batches) and with the caches evicted before each call, per library."""
    from pydrake.multibody.tree import MultibodyForces

    plant = model.plant
    context = plant.CreateDefaultContext()
    forces = MultibodyForces(plant)
    vdot = np.zeros(plant.num_velocities())
    evict = np.zeros(4_000_000)  # 32 MB, beyond the caches

    def drake():
        plant.CalcMassMatrix(context)
        plant.CalcForceElementsContribution(context, forces)
        plant.CalcInverseDynamics(context, vdot, forces)

    pairs = {"drake": drake, "kernel": model.dynamics}
    robot = pinocchio_model(model)
    if robot is not None:
        import pinocchio as pin

        data, q, v, a = robot.createData(), pin.neutral(robot), np.zeros(robot.nv), np.zeros(robot.nv)

        def pinocchio():
            pin.crba(robot, data, q)
            pin.rnea(robot, data, q, v, a)

        pairs["pinocchio"] = pinocchio
    costs = {}
    for name, fn in pairs.items():
        fn()
        hot, cold = [], []
        for _ in range(calls):
            start = time.perf_counter()
            for _ in range(20):
                fn()
            hot.append((time.perf_counter() - start) / 20 * 1e6)
            evict[::8] += 1.0
            start = time.perf_counter()
            fn()
            cold.append((time.perf_counter() - start) * 1e6)
        costs[name] = {"hot": float(np.min(hot)), "cold_median": float(np.median(cold))}
    return costs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    args = parser.parse_args()
    result = BenchResult(
        "cart_bench",
        "the paper's cart_linearizing_controller on TWIL + WAM: its update() and the "
        "whole 1 kHz cycle (wall and thread CPU time), the launch against the bare plant, and the "
        "control model's mass matrix + inverse dynamics by Drake, the compiled kernel and Pinocchio",
    )
    bare = bare_plant_rtf("twil_wam", "twil_wam", args.duration)
    run = instrumented_launch(LAUNCH, args.duration, controller="cart_linearizing_controller")
    print(f"cart_linearizing_controller bench (TWIL + WAM), {args.duration:g} s simulated each")
    print(f"  bare plant (twil_wam, world, zero effort):       {bare:7.2f}x real time")
    print(f"  twil_cart_linearizing launch ({run.messages} msgs):   {run.rtf:7.2f}x real time")
    print(f"  ratio launch / bare plant:                       {run.rtf / bare:7.3f}")
    print(
        f"  cart_linearizing_controller update():            {percentiles(run.update_wall_us)}"
        "   (target p99 < 100 us)"
    )
    print(f"  update(), thread CPU time:                       {percentiles(run.update_cpu_us)}")
    print(f"  whole cycle read -> update -> write, wall:       {percentiles(run.cycle_wall_us)}")
    print(f"  whole cycle, thread CPU time:                    {percentiles(run.cycle_cpu_us)}")
    print(
        f"  load average during the run: {' '.join(f'{v:.2f}' for v in os.getloadavg())} on {os.cpu_count()} cores"
    )
    costs = dynamics_costs(run.controller.model)
    for name, c in costs.items():
        print(
            f"  M + inverse dynamics, {name:9s}: hot {c['hot']:6.1f} us, caches evicted {c['cold_median']:6.1f} us"
        )
    result.add("simulated_s", args.duration, "s")
    result.add("bare_plant_rtf", bare, "x real time")
    result.add(
        "launch_rtf", run.rtf, "x real time", headline="twil_cart_linearizing launch, real-time factor"
    )
    result.add("launch_over_bare", run.rtf / bare)
    for row, us in (
        ("update(), wall", run.update_wall_us),
        ("update(), thread CPU", run.update_cpu_us),
        ("cycle, wall", run.cycle_wall_us),
        ("cycle, thread CPU", run.cycle_cpu_us),
    ):
        result.add("median", np.median(us), "us", row=row)
        result.add(
            "p99",
            np.percentile(us, 99),
            "us",
            row=row,
            **({"target": "< 100", "headline": "cart update() p99, wall"} if row == "update(), wall" else {}),
        )
        result.add("max", us.max(), "us", row=row)
    for name, c in costs.items():
        result.add("hot", c["hot"], "us", row=name, table="M + inverse dynamics")
        result.add("caches evicted", c["cold_median"], "us (median)", row=name, table="M + inverse dynamics")
    result.write()


if __name__ == "__main__":
    main()
