"""Real-time factor of the full twil_sim launch (with bag recording) against the bare plant.

Both simulate the same world and robot for the same simulated time, in one process, one after
the other, so the ratio is meaningful on a noisy machine. Prints both factors and their ratio.

    .venv/bin/python bench/twil_sim_rtf.py [--duration 5]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run
from twil_control.world.simulation import Simulation


def bare_plant_rtf(duration: float) -> float:
    """TWIL + WAM in the default world, zero actuation, no Python systems at all."""
    sim = Simulation()
    sim.add_world(PACKAGE_ROOT / "sim/worlds/default.sdf")
    sim.spawn("twil_wam", "twil_wam")
    sim.finalize()
    simulator = sim.build()
    simulator.Initialize()
    start = time.perf_counter()
    simulator.AdvanceTo(duration)
    return duration / (time.perf_counter() - start)


def launch_rtf(duration: float) -> tuple[float, int]:
    plan = load_launch(PACKAGE_ROOT / "launch/twil_sim.launch.yaml", {})
    with tempfile.TemporaryDirectory() as tmp:
        result = run(plan, RunOptions(duration=duration, bag=Path(tmp) / "bench.bag"))
    if result.error:
        raise result.error
    return result.realtime_factor, result.messages


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    args = parser.parse_args()
    bare = bare_plant_rtf(args.duration)
    full, messages = launch_rtf(args.duration)
    print(f"twil_sim bench, {args.duration:g} s simulated each")
    print(f"  bare plant (TWIL + WAM, world):        {bare:6.2f}x real time")
    print(f"  twil_sim launch (1 kHz ros_control, recording {messages} msgs): {full:6.2f}x real time")
    print(f"  ratio launch / bare plant:             {full / bare:6.3f}")


if __name__ == "__main__":
    main()
