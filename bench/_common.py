"""What every bench does the same way: write its figures as dated JSON (BenchResult, the schema in
bench/README.md), and measure a bare plant's and a launch's real-time factor."""
from __future__ import annotations

import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import load_launch
from twil_control.bag.recorder import BagRecorder
from twil_control.launch.runner import SLICE, Launch, RunOptions, run

DEFAULT_WORLD = PACKAGE_ROOT / "sim/worlds/default.sdf"
RESULTS = Path(__file__).resolve().parent / "results"


def git_commit(root: Path = PACKAGE_ROOT) -> str:
    """The checkout's short commit, with "-dirty" when tracked files differ from it."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=root,
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


class BenchResult:
    """One bench run's figures, written as bench/results/NAME_DATE.json (bench/README.md):
    the figures, what they measure, the command, the commit, and the machine with its load and
    the hypervisor's steal over the run (the benches are ratios measured in one run because the
    machine may be shared: BENCH_NOTE says so in the file)."""

    def __init__(self, name: str, measures: str) -> None:
        self.name, self.measures = name, measures
        self.figures: dict[str, float | str] = {}
        self.units: dict[str, str] = {}
        self.command = " ".join([".venv/bin/python", f"bench/{Path(sys.argv[0]).name}", *sys.argv[1:]])
        self._load0, self._wall0 = os.getloadavg(), time.perf_counter()
        self._steal0 = host_steal_seconds()

    def add(self, key: str, value, unit: str = "") -> None:
        """A figure: a number (rounded to 4 significant digits) or a short text."""
        self.figures[key] = float(f"{value:.4g}") if isinstance(value, (int, float, np.number)) else value
        if unit:
            self.units[key] = unit

    def write(self, folder: Path = RESULTS) -> Path:
        wall = time.perf_counter() - self._wall0
        now = datetime.datetime.now(datetime.timezone.utc)
        data = {
            "name": self.name,
            "date": now.isoformat(timespec="seconds"),
            "commit": git_commit(),
            "measures": self.measures,
            "command": self.command,
            "machine": {
                "hostname": platform.node(),
                "cpu_model": cpu_model(),
                "cores": os.cpu_count(),
                "load_average_start": [round(v, 2) for v in self._load0],
                "load_average_end": [round(v, 2) for v in os.getloadavg()],
                "steal_share": round((host_steal_seconds() - self._steal0) / (max(wall, 1e-9) * (os.cpu_count() or 1)), 3),
                "python": platform.python_version(),
                "system": f"{platform.system()} {platform.machine()}",
                "note": os.environ.get("BENCH_NOTE", ""),
            },
            "wall_s": round(wall, 1),
            "figures": self.figures,
            "units": self.units,
        }
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{self.name}_{now.strftime('%Y-%m-%dT%H%M%SZ')}.json"
        path.write_text(json.dumps(data, indent=1) + "\n")
        print(f"results: {path.relative_to(PACKAGE_ROOT) if path.is_relative_to(PACKAGE_ROOT) else path}")
        return path


def host_steal_seconds() -> float:
    """CPU seconds the hypervisor has given other guests, summed over this machine's CPUs
    (/proc/stat's steal column): what a run's wall time holds beyond its own work."""
    with open("/proc/stat") as f:
        return int(f.readline().split()[8]) / os.sysconf("SC_CLK_TCK")


def bare_plant_rtf(model: str, name: str, duration: float, world: Path = DEFAULT_WORLD) -> float:
    """`model` spawned as `name` in `world`, zero actuation, no Python systems at all."""
    from twil_control.world.simulation import Simulation  # Drake only for the benches that simulate
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
    cycle_wall_us: np.ndarray     # read -> controller_manager.update -> write, per control period
    cycle_cpu_us: np.ndarray      # the same cycles in thread CPU time
    update_wall_us: np.ndarray    # update() of the named controller alone (empty if none named)
    update_cpu_us: np.ndarray     # the same calls in thread CPU time
    messages: int
    controller: object            # the named controller (for extra measurements), or None


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


def instrumented_launch(launch_file: str, duration: float, args: dict | None = None,
                        controller: str | None = None) -> LaunchCosts:
    """Run a launch the way the runner does (0.05 s slices, bag recording of its record list,
    the recorder flushed between slices), timing every control cycle and, if named, one
    controller's update()."""
    launch = Launch(load_launch(PACKAGE_ROOT / launch_file, args or {}))
    launch.build()
    launch.start()
    hw_node = next(p for n in launch.nodes for p in getattr(n, "plugins", []) + [n]
                   if getattr(p, "system", None) is not None and getattr(p, "manager", None) is not None)
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
    return LaunchCosts(duration / wall, np.array(hw_node.system.cost_log[skip:]) * 1e6, np.array(cpu[skip:]) * 1e6,
                       np.array(updates[skip:]) * 1e6, np.array(updates_cpu[skip:]) * 1e6, recorder.count,
                       target)


def percentiles(us: np.ndarray) -> str:
    """"median M us, p99 P us, max X us" of microsecond samples."""
    return f"median {np.median(us):6.1f} us, p99 {np.percentile(us, 99):6.1f} us, max {us.max():8.1f} us"


def summary(us: np.ndarray) -> dict:
    """Median, p99 and max of microsecond samples, for a results file."""
    return {"median": float(np.median(us)), "p99": float(np.percentile(us, 99)), "max": float(us.max()),
            "samples": int(len(us))}


def write_result(name: str, figures: dict, measures: str = "") -> Path:
    """A bench's figures collected by the bench itself (nested mappings and lists allowed),
    written as BenchResult writes them (the load and steal are then the end's)."""
    result = BenchResult(name, measures)
    result.figures = dict(figures)
    return result.write()
