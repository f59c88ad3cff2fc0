"""What every bench measures the same way: a bare plant's and a launch's real-time factor."""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run
from twil_control.world.simulation import Simulation

DEFAULT_WORLD = PACKAGE_ROOT / "sim/worlds/default.sdf"


def bare_plant_rtf(model: str, name: str, duration: float, world: Path = DEFAULT_WORLD) -> float:
    """`model` spawned as `name` in `world`, zero actuation, no Python systems at all."""
    sim = Simulation()
    sim.add_world(world)
    sim.spawn(model, name)
    sim.finalize()
    simulator = sim.build()
    simulator.Initialize()
    start = time.perf_counter()
    simulator.AdvanceTo(duration)
    return duration / (time.perf_counter() - start)


def launch_rtf(launch_file: str, duration: float, args: dict | None = None) -> tuple[float, int]:
    """(real-time factor, messages recorded) of a launch run with bag recording."""
    plan = load_launch(PACKAGE_ROOT / launch_file, args or {})
    with tempfile.TemporaryDirectory() as tmp:
        result = run(plan, RunOptions(duration=duration, bag=Path(tmp) / "bench.bag"))
    if result.error:
        raise result.error
    return result.realtime_factor, result.messages
