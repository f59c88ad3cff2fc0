"""How the plant's step trades fidelity for speed: the same launches, controllers and commands at
steps of 1, 2, 4 and 5 ms (gzserver's ~time_step; gazebo_ros_control then runs the controllers
once per step, as Gazebo does when the world's step is that long). Cases: the Husky's open-loop
square from its own launch files with its LMS1xx (tests/data/ros1/tryout/husky_control.launch),
and BARN trials with jackal_helper's DWA (python -m twil_control.barn --time_step). Per step: the
running phase's CPU real-time factor (simulated s per CPU s, start-up and build excluded) and,
against the 1 ms run, the Husky's final and largest pose difference, its wheel odometry's and
EKF's error against the truth; a BARN trial's outcome, time, and its path's largest distance
from the path of the 1 ms run with the same seed (--seeds: the spread of outcomes a seed alone
makes). One process per run.

    .venv/bin/python bench/physics_step_bench.py [--steps 1,2,4,5] [--cases husky,barn]
        [--worlds 0,6] [--seeds 0] [--barn-src CATKIN_SRC] [--husky-duration 27]

BARN worlds other than the vendored 0 and 6 need --barn-src, a catkin src holding
the-barn-challenge, jackal and jackal_simulator (melodic-devel), as bench/barn_bench.py's --src.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _result import ROOT, BenchResult
from rosbags.highlevel import AnyReader

ROS1 = ROOT / "tests" / "data" / "ros1"
HUSKY_LAUNCH = ROS1 / "tryout" / "husky_control.launch"
HUSKY_ENV = {"HUSKY_LMS1XX_ENABLED": "1"}
#: simulated time the Husky's run phase is counted from (the build and start come before 0)
RUN_FROM = 0.05
ODOM = "/husky_velocity_controller/odom"
FILTERED = "/odometry/filtered"


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _env() -> dict:
    env = dict(os.environ)
    extra = [str(ROS1 / "vendor"), str(ROS1 / "stubs")]
    env["ROS_PACKAGE_PATH"] = os.pathsep.join([p for p in [env.get("ROS_PACKAGE_PATH", "")] if p] + extra)
    return env


def poses(bag: Path, topics: dict[str, str]) -> dict[str, np.ndarray]:
    """(t, x, y, yaw) rows per name: a model's of /gazebo/model_states ("model:NAME") or an
    odometry topic's."""
    rows: dict[str, list] = {name: [] for name in topics}
    by_topic: dict[str, list[tuple[str, str]]] = {}
    for name, source in topics.items():
        topic = "/gazebo/model_states" if source.startswith("model:") else source
        by_topic.setdefault(topic, []).append((name, source))
    with AnyReader([bag]) as reader:
        connections = [c for c in reader.connections if c.topic in by_topic]
        for conn, t, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, conn.msgtype)
            for name, source in by_topic[conn.topic]:
                if source.startswith("model:"):
                    model = source.split(":", 1)[1]
                    if model not in msg.name:
                        continue
                    pose = msg.pose[list(msg.name).index(model)]
                else:
                    pose = msg.pose.pose
                rows[name].append((t * 1e-9, pose.position.x, pose.position.y, _yaw(pose.orientation)))
    return {name: np.array(r) for name, r in rows.items()}


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


# -- the Husky's square, one step per process ------------------------------------------------------
def husky_child(step: float, duration: float, out: Path) -> None:
    """Run the square at `step` in this process; write the run's CPU and the poses to `out`."""
    from twil_control.launch.loader import load_launch
    from twil_control.launch.runner import RunOptions, run

    os.environ.update(HUSKY_ENV)
    plan = load_launch(HUSKY_LAUNCH, {})
    plan.params.set("/gazebo/time_step", step)
    marks: list[tuple[float, float]] = []  # (simulated s, process CPU s) at each /clock

    def on_master(master) -> None:
        master.bus.subscribe(
            "/clock",
            "rosgraph_msgs/Clock",
            lambda m: marks.append((m.clock.sec + m.clock.nanosec * 1e-9, time.process_time())),
            node="/physics_step_bench",
        )

    with tempfile.TemporaryDirectory() as tmp:
        bag = Path(tmp) / "run.bag"
        result = run(plan, RunOptions(duration=duration, bag=bag, fsync=False), on_master=on_master)
        if result.error is not None:
            raise SystemExit(f"husky at {step} s: {result.error}")
        p = poses(bag, {"truth": "model:husky", "odom": ODOM, "filtered": FILTERED})
    start = next(m for m in marks if m[0] >= RUN_FROM - 1e-9)
    end = marks[-1]
    record = {"step": step, "run_sim_s": end[0] - start[0], "run_cpu_s": end[1] - start[1]}
    record.update({name: rows.tolist() for name, rows in p.items()})
    out.write_text(json.dumps(record))


def husky_run(step: float, duration: float) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "husky.json"
        command = [sys.executable, __file__, "--child", "husky", "--step", repr(step)]
        command += ["--husky-duration", repr(duration), "--child-out", str(out)]
        done = subprocess.run(command, env=_env(), cwd=ROOT, capture_output=True, text=True)
        if done.returncode != 0:
            return {"error": (done.stderr.strip().splitlines() or ["no output"])[-1]}
        record = json.loads(out.read_text())
    for key in ("truth", "odom", "filtered"):
        record[key] = np.array(record[key])
    return record


def odometry_error(truth: np.ndarray, odom: np.ndarray) -> tuple[float, float]:
    """(final position error m, final heading error rad) of an odometry topic (in its odom
    frame, which starts at the robot's first true pose) against the truth."""
    x0, y0, th0 = truth[0, 1:]
    t_end = min(truth[-1, 0], odom[-1, 0])
    o = odom[np.searchsorted(odom[:, 0], t_end - 1e-9)]
    g = truth[np.searchsorted(truth[:, 0], t_end - 1e-9)]
    c, s = math.cos(th0), math.sin(th0)
    world = (x0 + c * o[1] - s * o[2], y0 + s * o[1] + c * o[2], th0 + o[3])
    return math.hypot(world[0] - g[1], world[1] - g[2]), abs(float(_wrap(world[2] - g[3])))


def against(reference: np.ndarray, rows: np.ndarray) -> dict:
    """Final and largest difference of two (t, x, y, yaw) runs at their common stamps."""
    t = np.intersect1d(np.round(reference[:, 0], 6), np.round(rows[:, 0], 6))
    a = reference[np.isin(np.round(reference[:, 0], 6), t)]
    b = rows[np.isin(np.round(rows[:, 0], 6), t)]
    d = np.hypot(a[:, 1] - b[:, 1], a[:, 2] - b[:, 2])
    h = np.abs(_wrap(a[:, 3] - b[:, 3]))
    return {
        "final_m": float(d[-1]),
        "max_m": float(d.max()),
        "final_rad": float(h[-1]),
        "max_rad": float(h.max()),
    }


# -- BARN trials -----------------------------------------------------------------------------------
def barn_run(world: int, step: float, src: Path | None, seed: int = 0) -> dict:
    env = _env()
    if src is not None:
        env["ROS_PACKAGE_PATH"] = os.pathsep.join([str(src), env["ROS_PACKAGE_PATH"]])
    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        command = [sys.executable, "-m", "twil_control.barn", "--world_idx", str(world), "--quiet"]
        command += ["--time_step", repr(step), "--seed", str(seed), "--out", str(tmp_path / "out.txt")]
        command += ["--stats", str(tmp_path / "stats.json"), "--bag", str(tmp_path / "trial.bag")]
        done = subprocess.run(command, env=env, cwd=ROOT, capture_output=True, text=True)
        if done.returncode != 0:
            return {"error": (done.stderr.strip().splitlines() or ["no output"])[-1]}
        stats = json.loads((tmp_path / "stats.json").read_text())
        path = poses(tmp_path / "trial.bag", {"path": "model:jackal"})["path"]
    return {
        "step": step,
        "status": stats["status"],
        "time": stats["trial_time"],
        "run_cpu_s": stats["run_cpu"],
        "run_sim_s": stats["sim_time"],
        "path": path,
    }


def path_distance(reference: np.ndarray, rows: np.ndarray) -> float:
    """The largest distance from a point of `rows`' path to the nearest point of `reference`'s."""
    a, b = reference[:, 1:3], rows[:, 1:3]
    d = np.hypot(b[:, None, 0] - a[None, :, 0], b[:, None, 1] - a[None, :, 1]).min(axis=1)
    return float(d.max())


# -- the table -------------------------------------------------------------------------------------
def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", default="1,2,4,5", help="plant steps in ms; the first is the reference")
    ap.add_argument("--cases", default="husky,barn")
    ap.add_argument("--worlds", default="0,6", help="BARN worlds (0 and 6 are vendored; others: --barn-src)")
    ap.add_argument(
        "--seeds", default="0", help="BARN trials' seeds (the sensors' noise), each run at every step"
    )
    ap.add_argument(
        "--barn-src", type=Path, help="catkin src with the-barn-challenge, jackal, jackal_simulator"
    )
    ap.add_argument("--husky-duration", type=float, default=27.0, help="simulated s (the square takes 25.6)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--step", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--child-out", type=Path, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child == "husky":
        husky_child(a.step, a.husky_duration, a.child_out)
        return 0
    steps = [float(s) * 1e-3 for s in a.steps.split(",")]
    cases = [c.strip() for c in a.cases.split(",")]
    out = BenchResult(
        "physics_step_bench",
        "the plant's step against speed and fidelity: CPU real-time factor of the running phase, and "
        "the Husky's square and BARN DWA trials against the first step's run",
    )
    if a.barn_src is not None:  # the page names no machine's paths
        out.command = out.command.replace(str(a.barn_src), "CATKIN_SRC")
    if "husky" in cases:
        runs = {}
        for step in steps:
            runs[step] = husky_run(step, a.husky_duration)
            _husky_row(out, runs, steps[0], step)
    if "barn" in cases:
        for world in [int(w) for w in a.worlds.split(",")]:
            for seed in [int(k) for k in a.seeds.split(",")]:
                runs = {}
                for step in steps:
                    runs[step] = barn_run(world, step, a.barn_src, seed)
                    _barn_row(out, runs, steps[0], step, world, seed)
    out.write()
    return 0


def _husky_row(out: BenchResult, runs: dict, ref: float, step: float) -> None:
    r, row = runs[step], f"husky square, {step * 1e3:g} ms"
    if "error" in r or "error" in runs[ref]:
        out.add("error", r.get("error") or "the reference run failed", row=row, table="husky")
        print(f"{row}: {r.get('error')}", flush=True)
        return
    rtf = r["run_sim_s"] / r["run_cpu_s"]
    diff = against(runs[ref]["truth"], r["truth"])
    odom = odometry_error(r["truth"], r["odom"])
    ekf = odometry_error(r["truth"], r["filtered"])
    ref_rtf = runs[ref]["run_sim_s"] / runs[ref]["run_cpu_s"]
    figures = {
        "run CPU rtf": (rtf, "x real time"),
        "speed-up": (rtf / ref_rtf, "x"),
        "final pose diff": (diff["final_m"], "m"),
        "max pose diff": (diff["max_m"], "m"),
        "max heading diff": (diff["max_rad"], "rad"),
        "wheel odom error": (odom[0], "m"),
        "wheel odom heading error": (odom[1], "rad"),
        "EKF heading error": (ekf[1], "rad"),
    }
    for key, (value, unit) in figures.items():
        out.add(key, value, unit, row=row, table="husky")
    out.records[row] = {"run_cpu_s": r["run_cpu_s"], "run_sim_s": r["run_sim_s"], **diff}
    print(
        f"{row}: CPU rtf {rtf:.2f} ({rtf / ref_rtf:.2f}x), pose diff final {diff['final_m']:.3f} m max "
        f"{diff['max_m']:.3f} m, heading max {diff['max_rad']:.3f} rad; wheel odom {odom[0]:.3f} m "
        f"{odom[1]:.3f} rad; EKF heading {ekf[1]:.3f} rad",
        flush=True,
    )


def _barn_row(out: BenchResult, runs: dict, ref: float, step: float, world: int, seed: int) -> None:
    r, row = runs[step], f"BARN world {world} seed {seed}, {step * 1e3:g} ms"
    if "error" in r or "error" in runs[ref]:
        out.add("error", r.get("error") or "the reference run failed", row=row, table="barn")
        print(f"{row}: {r.get('error')}", flush=True)
        return
    rtf = r["run_sim_s"] / r["run_cpu_s"]
    ref_rtf = runs[ref]["run_sim_s"] / runs[ref]["run_cpu_s"]
    deviation = path_distance(runs[ref]["path"], r["path"])
    for key, value, unit in (
        ("run CPU rtf", rtf, "x real time"),
        ("speed-up", rtf / ref_rtf, "x"),
        ("outcome", r["status"], ""),
        ("trial time", r["time"], "s"),
        ("path deviation", deviation, "m"),
    ):
        out.add(key, value, unit, row=row, table="barn")
    out.records[row] = {k: v for k, v in r.items() if k != "path"}
    print(
        f"{row}: CPU rtf {rtf:.2f} ({rtf / ref_rtf:.2f}x), {r['status']} in {r['time']:.2f} s, path "
        f"{deviation:.3f} m from the {ref * 1e3:g} ms run's",
        flush=True,
    )


if __name__ == "__main__":
    sys.exit(main())
