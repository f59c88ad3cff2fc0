"""One BARN trial in this process, as run.py runs one: the environment it sets, the world it
picks, launch/barn.launch (jackal_helper's gazebo_launch.launch, the navigation launch, the
trial node "gym"), then the lines it prints and the line it appends to its out file.

jackal_helper is the user's, found through ROS_PACKAGE_PATH (a catkin src holding
the-barn-challenge, jackal and jackal_simulator). One trial per process: pydrake never frees a
diagram holding a Python system.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from .. import PACKAGE_ROOT
from ..errors import TwilControlError
from ..gazebo.gzserver import MAX_TIME_STEP
from . import metric

if TYPE_CHECKING:
    from ..launch.logging_setup import SimTimeStamp

LAUNCH = PACKAGE_ROOT / "launch" / "barn.launch"
#: run.py's laser: the Jackal's front Hokuyo UST-10 (jackal_description's accessories)
LASER_ENV = {"JACKAL_LASER": "1", "JACKAL_LASER_MODEL": "ust10", "JACKAL_LASER_OFFSET": "-0.065 0 0.01"}
#: simulated seconds a trial may take beyond its time limit (resets, waiting for the first motion)
MAX_SIM_TIME = 200.0


class BarnError(TwilControlError):
    """A trial that cannot run: an unknown world index, jackal_helper not found."""


@dataclass
class World:
    idx: int
    name: str  # relative to jackal_helper/worlds, as run.py prints it
    init: tuple[float, float, float]  # x, y, yaw in the world
    goal: tuple[float, float]  # relative to the initial position


def world(idx: int) -> World:
    """run.py's world and start for an index: BARN 0-299, DynaBARN 300-359."""
    if 0 <= idx < 300:
        return World(idx, f"BARN/world_{idx}.world", (-2.25, 3.0, 1.57), (0.0, 10.0))
    if 300 <= idx < 360:
        return World(idx, f"DynaBARN/world_{idx - 300}.world", (11.0, 0.0, 3.14), (-20.0, 0.0))
    raise BarnError(f"--world_idx {idx}: world index {idx} does not exist (BARN 0-299, DynaBARN 300-359)")


def jackal_helper() -> Path:
    from ..core import packages

    try:
        return packages.find("jackal_helper")
    except packages.PackageNotFoundError as error:
        raise BarnError(
            f"{error}; BARN's jackal_helper is in the-barn-challenge: put it in a catkin src/ with "
            "jackal and jackal_simulator (melodic-devel) on ROS_PACKAGE_PATH"
        ) from None


@dataclass
class TrialOutcome:
    world: World
    status: str
    time: float
    metric: float
    line: str
    build_wall: float  # s from the trial's start to simulated time 0 (the launch loaded and built)
    started_at: float  # time.perf_counter() when simulated time started
    run_wall: float  # s while simulated time ran
    run_cpu: float  # CPU s of this process while simulated time ran (as good as: build excluded)
    sim_time: float  # simulated seconds the launch ran (resets and waiting included)


def optimal_time(w: World, base: Path) -> float:
    """run.py's optimal time (path length / 2 m/s); DynaBARN has no path file, and run.py takes
    the goal's x minus the initial x as the length (negative: its metric is too)."""
    goal = (w.init[0] + w.goal[0], w.init[1] + w.goal[1])
    if w.idx >= 300:
        return (w.goal[0] - w.init[0]) / 2
    path = base / "worlds" / "BARN" / "path_files" / f"path_{w.idx}.npy"
    if not path.is_file():
        raise BarnError(f"BARN path file {path} not found (jackal_helper/worlds/BARN/path_files)")
    return metric.path_length(path, w.init[:2], goal) / 2


def run_trial(
    world_idx: int,
    out: Path,
    gui: bool = False,
    nav_launch: Path | None = None,
    bag: Path | None = None,
    seed: int = 0,
    time_limit: float = 100.0,
    time_step: float | None = None,
    echo=print,
    show_time: bool = True,
    log_stamp: SimTimeStamp | None = None,
) -> TrialOutcome:
    """Run one trial and append its line to `out`; BarnError before anything ran. `time_step`:
    the plant's step (s) in place of the world's <max_step_size>."""
    from ..launch.loader import load_launch
    from ..launch.runner import RunOptions, run
    from ..nodes.barn_run import BarnRun

    wall0 = time.perf_counter()
    w = world(world_idx)
    if not (time_limit > 0 and math.isfinite(time_limit)):
        raise BarnError(f"--time_limit must be a positive number of seconds (got {time_limit})")
    if time_step is not None and not (0 < time_step <= MAX_TIME_STEP):
        raise BarnError(f"--time_step must be in (0, {MAX_TIME_STEP:g}] seconds (got {time_step})")
    os.environ.update(LASER_ENV)
    echo(f">>>>>>>>>>>>>>>>>> Loading Gazebo Simulation with {w.name} <<<<<<<<<<<<<<<<<<")
    base = jackal_helper()
    os.environ["GAZEBO_PLUGIN_PATH"] = str(base / "plugins")
    world_file = base / "worlds" / w.name
    if not world_file.is_file():
        raise BarnError(f"world {world_file} not found (--world_idx {world_idx})")
    best = optimal_time(w, base)
    args = {
        "world_name": str(world_file),
        "gui": "true" if gui else "false",
        "init_x": repr(w.init[0]),
        "init_y": repr(w.init[1]),
        "init_yaw": repr(w.init[2]),
        "goal_x": repr(w.goal[0]),
        "goal_y": repr(w.goal[1]),
        "time_limit": repr(time_limit),
        "time_step": "" if time_step is None else repr(float(time_step)),
    }
    if nav_launch is not None:
        if not nav_launch.is_file():
            raise BarnError(f"--nav_launch {nav_launch}: no such file")
        args["nav_launch"] = str(nav_launch.absolute())
    plan = load_launch(LAUNCH, args)
    view = None
    if gui:
        from ..view.view_node import ViewOptions

        view = ViewOptions()
    options = RunOptions(
        duration=MAX_SIM_TIME + time_limit,
        bag=bag,
        realtime=1.0 if gui else 0.0,
        seed=seed,
        view=view,
        fsync=False,
    )
    clock = _StartClock(show_time)

    def on_master(master) -> None:
        clock.attach(master)
        if log_stamp is not None:  # log lines carry the simulated time, as a launch's do
            log_stamp.attach(master)

    result = run(plan, options, on_master=on_master)
    cpu_now = time.process_time()
    trial = next((n for n in result.nodes if isinstance(n, BarnRun)), None)
    if result.error is not None or trial is None or trial.result is None:
        why = result.error or (
            f"the trial did not end within {MAX_SIM_TIME + time_limit:g} s of simulated time"
            if not result.interrupted
            else "interrupted"
        )
        raise BarnError(f"world {world_idx}: the trial did not finish: {why}")
    r = trial.result
    # The trial node calls the start hook at its first timer event, before any result.
    assert clock.wall_at_start is not None and clock.cpu_at_start is not None
    run_cpu = cpu_now - clock.cpu_at_start
    if show_time:
        echo("")
    echo(">>>>>>>>>>>>>>>>>> Test finished! <<<<<<<<<<<<<<<<<<")
    echo(f"Navigation {r.status} with time {r.time:.4f} (s)")
    score = metric.nav_metric(r.success, r.time, best)
    echo(f"Navigation metric: {score:.4f}")
    line = metric.out_line(world_idx, r.success, r.collided, r.time, score, time_limit)
    with open(out, "a") as f:
        f.write(line)
    build = clock.wall_at_start - wall0
    return TrialOutcome(
        w,
        r.status,
        r.time,
        score,
        line,
        build,
        clock.wall_at_start,
        result.wall_time,
        run_cpu,
        result.sim_time,
    )


class _StartClock:
    """Hooks on the launch's master: the trial node prints run.py's running line, and the wall
    and CPU clocks are read when simulated time starts (the first timer event)."""

    def __init__(self, show_time: bool) -> None:
        self.show_time = show_time
        self.wall_at_start: float | None = None
        self.cpu_at_start: float | None = None

    def attach(self, master) -> None:
        from ..nodes.barn_run import BarnRun

        for node in master.nodes.values():
            if isinstance(node, BarnRun):
                if self.show_time:
                    node.on_look = _print_time
                node.on_start_hook = self._started

    def _started(self) -> None:
        self.wall_at_start, self.cpu_at_start = time.perf_counter(), time.process_time()


def _print_time(t: float, x: float, y: float) -> None:
    print(f"Time: {t:.2f} (s), x: {x:.2f} (m), y: {y:.2f} (m)", end="\r", file=sys.stdout, flush=True)
