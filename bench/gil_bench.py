"""Why the launch runner shortens Python's GIL switch interval (launch.runner.SWITCH_INTERVAL)
and advances the simulator with interruptible=False: whenever the simulation needs the GIL (a
Python system's event; with pydrake's default, every step, to look for Ctrl-C) while a Python
thread runs beside it (slam_gmapping's worker), it waits until that thread is made to let go.

Prints, in one run, the real-time factor of the qbot plant with one 1 kHz Python system (the
controller manager's rate, here an empty event), alone and beside a thread that runs Python
without pause: with pydrake's and Python's defaults, with each change alone, and with both.

    .venv/bin/python bench/gil_bench.py [--duration 1]
"""

from __future__ import annotations

import argparse
import sys
import threading
import time

from _common import DEFAULT_WORLD, BenchResult
from pydrake.systems.framework import EventStatus, LeafSystem

from twil_control.launch.runner import SWITCH_INTERVAL
from twil_control.world.simulation import Simulation


class Tick(LeafSystem):
    """A Python event at 1 kHz that does nothing: the GIL is all it needs."""

    def __init__(self) -> None:
        super().__init__()
        self.DeclarePeriodicPublishEvent(0.001, 0.0, lambda context: EventStatus.Succeeded())


def advance_rtf(simulator, duration: float, interruptible: bool = True) -> float:
    start, t0 = time.perf_counter(), simulator.get_context().get_time()
    simulator.AdvanceTo(t0 + duration, interruptible=interruptible)
    return duration / (time.perf_counter() - start)


def beside_python(simulator, duration: float, interval: float, interruptible: bool) -> float:
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
        return advance_rtf(simulator, duration, interruptible)
    finally:
        stop.set()
        thread.join()
        sys.setswitchinterval(previous)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds per case")
    args = parser.parse_args()
    result = BenchResult(
        "gil_bench",
        "the qbot plant with one 1 kHz Python event, alone and beside a thread running "
        "Python: with pydrake's and Python's defaults and with the runner's settings",
    )
    sim = Simulation()
    sim.add_world(DEFAULT_WORLD)
    sim.spawn("qbot", "qbot")
    sim.finalize()
    sim.add_system(Tick(), "tick")
    simulator = sim.build()
    simulator.Initialize()
    simulator.AdvanceTo(0.2)  # warm up
    alone = advance_rtf(simulator, args.duration, interruptible=False)
    print(f"qbot plant with a 1 kHz Python event, default world, {args.duration:g} s simulated per case:")
    print(f"  {'alone:':85s} {alone:7.2f}x real time")
    result.add("alone_rtf", alone, "x real time")
    short = f"{1e3 * SWITCH_INTERVAL:.1f} ms"
    for label, interval, interruptible in (
        ("switch interval 5 ms, interruptible (defaults)", 0.005, True),
        (f"switch interval {short}, interruptible", SWITCH_INTERVAL, True),
        ("switch interval 5 ms, not interruptible", 0.005, False),
        (f"switch interval {short}, not interruptible (runner)", SWITCH_INTERVAL, False),
    ):
        rtf = beside_python(simulator, args.duration, interval, interruptible)
        print(f"  beside a Python thread, {label + ':':61s} {rtf:7.2f}x  ({alone / rtf:5.1f} times slower)")
        result.add(
            f"slowdown, {label}",
            alone / rtf,
            "times slower than alone",
            headline="(runner)" in label and "plant beside a Python thread, runner's settings: slowdown",
        )
    result.write()


if __name__ == "__main__":
    main()
