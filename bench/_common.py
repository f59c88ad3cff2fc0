"""What every bench does the same way: write its figures as dated JSON (BenchResult, from
_result), and measure a bare plant's and a launch's real-time factor and a 1 kHz loop's costs."""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from _result import BenchResult, host_steal_seconds

from twil_control import PACKAGE_ROOT
from twil_control.bag.recorder import BagRecorder
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import SLICE, Launch, RunOptions, run

# BenchResult and host_steal_seconds (from _result) are here too: the benches import them from here.
__all__ = [
    "DEFAULT_WORLD",
    "BenchResult",
    "LaunchCosts",
    "bare_plant_rtf",
    "host_steal_seconds",
    "instrumented_launch",
    "launch_rtf",
    "percentiles",
]

DEFAULT_WORLD = PACKAGE_ROOT / "sim/worlds/default.sdf"


def bare_plant_rtf(model: str, name: str, duration: float, world: Path = DEFAULT_WORLD) -> float:
    """`model` spawned as `name` in `world`, zero actuation, no Python systems at all."""
    from twil_control.world.simulation import (
        Simulation,  # Drake only for the benches that simulate
    )

    sim = Simulation()
    sim.add_world(world)
    sim.spawn(model, name)
    sim.finalize()
    simulator = sim.build()
    simulator.Initialize()
    start = time.perf_counter()
    simulator.AdvanceTo(duration)
    return duration / (time.perf_counter() - start)


def launch_rtf(launch_file: str, duration: float, args: dict | None = None, **options) -> tuple[float, int]:
    """(real-time factor, messages recorded) of a launch run with bag recording (options: more
    RunOptions fields)."""
    plan = load_launch(PACKAGE_ROOT / launch_file, args or {})
    with tempfile.TemporaryDirectory() as tmp:
        result = run(plan, RunOptions(duration=duration, bag=Path(tmp) / "bench.bag", **options))
    if result.error:
        raise result.error
    return result.realtime_factor, result.messages


@dataclass
class LaunchCosts:
    rtf: float
    cycle_wall_us: np.ndarray  # read -> controller_manager.update -> write, per control period
    cycle_cpu_us: np.ndarray  # the same cycles in thread CPU time
    update_wall_us: np.ndarray  # update() of the named controller alone (empty if none named)
    update_cpu_us: np.ndarray  # the same calls in thread CPU time
    messages: int
    controller: object  # the named controller (for extra measurements), or None


def _cpu_time_probe(hw) -> list[float]:
    """Per-cycle thread CPU seconds of read -> update -> write, measured by wrapping the
    RobotHW's read_state and write: unlike the wall time it excludes the time the OS gives other
    processes (this machine's 2 cores are shared)."""
    cpu: list[float] = []
    read_state, write, start = hw.read_state, hw.write, [0.0]

    def timed_read(x):
        start[0] = time.thread_time()
        read_state(x)

    def timed_write(t, period):
        write(t, period)
        cpu.append(time.thread_time() - start[0])

    hw.read_state, hw.write = timed_read, timed_write
    return cpu


def instrumented_launch(
    launch_file: str, duration: float, args: dict | None = None, controller: str | None = None
) -> LaunchCosts:
    """Run a launch the way the runner does (0.05 s slices, bag recording of its record list,
    the recorder flushed between slices), timing every control cycle and, if named, one
    controller's update()."""
    launch = Launch(load_launch(PACKAGE_ROOT / launch_file, args or {}))
    launch.build()
    launch.start()
    hw_node = next(
        p
        for n in launch.nodes
        for p in getattr(n, "plugins", []) + [n]
        if getattr(p, "system", None) is not None and getattr(p, "manager", None) is not None
    )
    hw_node.system.cost_log = []
    cpu = _cpu_time_probe(hw_node.hw)
    updates: list[float] = []
    updates_cpu: list[float] = []
    target = None
    if controller is not None:
        target = hw_node.manager.get_controller(controller)  # loaded by the spawner at start
        inner = target.update

        def timed_update(t, period):
            c0, t0 = time.thread_time(), time.perf_counter()
            inner(t, period)
            updates.append(time.perf_counter() - t0)
            updates_cpu.append(time.thread_time() - c0)

        target.update = timed_update
    with tempfile.TemporaryDirectory() as tmp:
        recorder = BagRecorder(Path(tmp) / "bench.bag", launch.master.bus, launch.plan.record_topics)
        try:
            start = time.perf_counter()
            t = 0.0
            while t < duration - 1e-12:  # the runner's slices
                t = min(t + SLICE, duration)
                launch.simulator.AdvanceTo(t)
                launch.master.clock.set(t)
                recorder.flush()
            wall = time.perf_counter() - start
        finally:
            launch.shutdown()
            recorder.close()
    skip = 10  # the first cycles load caches and controllers
    return LaunchCosts(
        duration / wall,
        np.array(hw_node.system.cost_log[skip:]) * 1e6,
        np.array(cpu[skip:]) * 1e6,
        np.array(updates[skip:]) * 1e6,
        np.array(updates_cpu[skip:]) * 1e6,
        recorder.count,
        target,
    )


def percentiles(us: np.ndarray) -> str:
    """ "median M us, p99 P us, max X us" of microsecond samples."""
    return f"median {np.median(us):6.1f} us, p99 {np.percentile(us, 99):6.1f} us, max {us.max():8.1f} us"
