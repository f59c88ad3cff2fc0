"""Why launches shorten Python's GIL switch interval (launch.runner.SWITCH_INTERVAL): pydrake's
Simulator takes the GIL back at every step, so a Python thread running beside the simulation
(slam_gmapping's worker) makes each step wait until that thread is made to let go.

Prints, in one run, the bare qbot plant's simulated seconds per wall second alone, and beside a
thread that runs Python without pause, at Python's default interval (5 ms) and at the runner's.

    .venv/bin/python bench/gil_bench.py [--duration 1]
"""
from __future__ import annotations

import argparse
import sys
import threading
import time

from _common import DEFAULT_WORLD
from twil_control.launch.runner import SWITCH_INTERVAL
from twil_control.world.simulation import Simulation


def advance_rtf(simulator, duration: float) -> float:
    start, t0 = time.perf_counter(), simulator.get_context().get_time()
    simulator.AdvanceTo(t0 + duration)
    return duration / (time.perf_counter() - start)


def beside_python(simulator, duration: float, interval: float) -> float:
    """Real-time factor with a thread running Python bytecode all along, at this interval."""
    previous, stop = sys.getswitchinterval(), threading.Event()

    def spin():
        n = 0
        while not stop.is_set():
            n += 1
    sys.setswitchinterval(interval)
    thread = threading.Thread(target=spin)
    thread.start()
    try:
        return advance_rtf(simulator, duration)
    finally:
        stop.set()
        thread.join()
        sys.setswitchinterval(previous)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds per case")
    args = parser.parse_args()
    sim = Simulation()
    sim.add_world(DEFAULT_WORLD)
    sim.spawn("qbot", "qbot")
    sim.finalize()
    simulator = sim.build()
    simulator.Initialize()
    simulator.AdvanceTo(0.2)   # warm up
    alone = advance_rtf(simulator, args.duration)
    default = beside_python(simulator, args.duration, 0.005)
    short = beside_python(simulator, args.duration, SWITCH_INTERVAL)
    print(f"bare qbot plant, {args.duration:g} s simulated per case (real-time factor):")
    print(f"  alone:                                         {alone:7.2f}x")
    print(f"  beside a Python thread, switch interval 5 ms:  {default:7.2f}x  ({alone / default:5.1f} times slower)")
    print(f"  beside a Python thread, switch interval {1e3 * SWITCH_INTERVAL:.1f} ms: {short:7.2f}x  "
          f"({alone / short:5.1f} times slower)")


if __name__ == "__main__":
    main()
