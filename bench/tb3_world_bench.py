"""TurtleBot3's e-manual navigation in turtlebot3_world: a goal tour localised by amcl beside the
same tour under fake_localization, and global localisation from several seeds.

    .venv/bin/python bench/tb3_world_bench.py [--goals 20] [--seeds 10] [--phases tour,fake,global]
                                              [--turtlebot3 DIR] [--out DIR] [--reuse]

The packages are TurtleBot3's noetic branches (the copies vendored for the tests, or checkouts
given with --turtlebot3), run as the e-manual runs them: turtlebot3_gazebo's
turtlebot3_world.launch (the burger spawned at (-2, -0.5)) and turtlebot3_navigation's
turtlebot3_navigation.launch (map_server with the package's maps/map.yaml, amcl.launch,
move_base.launch; open_rviz:=false), each phase one ``python -m twil_control.launch`` process.

1. ``tour``: a 2D Pose Estimate where the burger is (/initialpose, rviz's covariance), then
   --goals goals on /move_base_simple/goal one after another (tests/data/ros1/tryout/
   tb3_world_goals.launch), drawn seeded in the map's free space (at least CLEARANCE from its
   walls and pillars, reachable from the spawn, MIN_SEPARATION apart), each cancelled after
   --goal-timeout s: goals reached, simulated time per goal, and the robot's pose in the map
   (map -> odom -> base_footprint on /tf) against the truth (/gazebo/model_states) at 10 Hz:
   mean, 95th percentile and largest error, and the same over the run in ERROR_WINDOW windows.
2. ``fake``: the same goals with fake_localization in amcl's place (the rest of
   turtlebot3_navigation.launch as it is), its ground truth the diff drive's odometry (the
   plugin's odometrySource world): the navigation without localisation error.
3. ``global``: amcl.launch's filter, told nothing of the pose (its initial pose (0, 0, 0) is
   2 m off), spread over the map by ``rosservice call /global_localization`` when time starts;
   the burger driven open-loop (GLOBAL_DRIVE: turns in place, then east between the pillar
   rows) for --seeds launch seeds: converged when /amcl_pose comes within GLOBAL_RADIUS of the
   truth and stays there to the end of GLOBAL_WITHIN s. turtlebot3_world is nearly symmetric
   about its centre (the map's occupied cells lie within 0.1 m of its own turned by pi in 93 %,
   by pi/2 in 81 %: the square grid of pillars), so runs that settle on the truth turned by such
   an angle (ALIASES) are counted apart. The drive is the one a user would give amcl with
   turtlebot3_teleop_key: spin the burger at its top turning speed, then drive off. With
   amcl.launch's parameters (diff model, odom_alpha 0.1, no recovery particles) the particles
   spread per update by alpha times the square of the motion since the last update
   (docs/localization.md): at 0.6 rad/s an update follows 0.24 rad of turn and moves them by
   about 6 mm and 0.006 rad, so each hypothesis keeps the poses of its first draw and the one
   drawn closest to its own best fit wins, the truth or an alias alike; at 2.84 rad/s every 5 Hz
   scan follows 0.57 rad (3 cm and 0.03 rad per update) and the particles settle into each
   hypothesis's best fit, where the truth's better fit (a scan's likelihood 1.1 to 1.25 times an
   alias's best) decides; the drive east then settles runs in which the truth came out of the
   turns as the lighter cluster. Gazebo's ray sensor takes a scan at one instant: a real LDS-01,
   sweeping for 0.2 s, would see its scan skewed by the 0.57 rad the burger turns meanwhile.
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
import yaml
from _result import BenchResult
from rosbags.highlevel import AnyReader

ROOT = Path(__file__).resolve().parents[1]
VENDOR = ROOT / "tests" / "data" / "ros1" / "vendor"
GOALS_LAUNCH = ROOT / "tests" / "data" / "ros1" / "tryout" / "tb3_world_goals.launch"
SPAWN = (-2.0, -0.5, 0.0)  # turtlebot3_world.launch's x_pos, y_pos
CLEARANCE = 0.35  # m from the map's occupied cells to a goal
MIN_SEPARATION = 1.5  # m between a goal and the one before
ERROR_WINDOW = 30.0  # s of simulated time per window of the error over time
GLOBAL_RADIUS, GLOBAL_WITHIN = 0.3, 30.0  # m, s of driving
#: the world's near-symmetries: the truth turned about the world's centre by these angles
ALIASES = {"by pi": math.pi, "by pi/2": math.pi / 2, "by -pi/2": -math.pi / 2}
#: the global phase's drive from the spawn point: 3.5 turns in place at 2.84 rad/s (the burger's
#: top turning speed, turtlebot3_teleop's BURGER_MAX_ANG_VEL), the last half turn at 0.6 rad/s (an
#: open-loop stop from 2.84 rad/s overshoots by 0.4 rad), then 0.2 m/s east for 8 s between the
#: pillar rows at y = 0 and -1.1, stopping short of the middle column; the run ends at GLOBAL_WITHIN
GLOBAL_DRIVE = {
    "rate": 10,
    "segments": [
        {"time": 0.0, "linear_x": 0.0, "angular_z": 2.84},
        {"time": 7.744, "linear_x": 0.0, "angular_z": 0.6},
        {"time": 12.980, "linear_x": 0.2, "angular_z": 0.0},
        {"time": 20.980, "linear_x": 0.0, "angular_z": 0.0},
    ],
}
#: The global phase's recorded runs (scans, odometry at their stamps, the truth; --seeds 10)
#: replayed through the original C++ amcl (ros-planning/navigation noetic-devel's pf, map and
#: sensors libraries with a replay driver doing what amcl_node's laserReceived does, as
#: bench/amcl_bench.py's anchor; neither is part of this repository) and through this project's
#: filter, each run with filter seeds 0-9 (drand48's, numpy's): runs whose pose in the map (the
#: estimate composed with the odometry at each scan) came within GLOBAL_RADIUS of the truth and
#: stayed there to the end. A filter seed draws the same particles on every run, and the outcome
#: follows the draw far more than the run, so 10 x 10 replays weigh about 10 draws: hence the
#: row of 50 seeds on two runs (launch seeds 0 and 7). "one slow turn": the recorded runs of a
#: drive of one turn at 0.6 rad/s and 16 s east, where both settle on an alias about half the time.
CXX_GLOBAL = {
    "replayed, C++ amcl": {"within 0.3 m in 30 s": "93/100"},
    "replayed, this project": {"within 0.3 m in 30 s": "100/100"},
    "replayed, this project, 50 seeds x 2 runs": {"within 0.3 m in 30 s": "88/100"},
    "replayed one slow turn, C++ amcl": {"within 0.3 m in 30 s": "44/100"},
    "replayed one slow turn, this project": {"within 0.3 m in 30 s": "50/100"},
}
GLOBAL_LAUNCH = """<launch>
  <!-- what a user does beside the e-manual's two launch files to find a lost robot: amcl's
       global_localization service from a terminal, then drive (a timed cmd_vel sequence) -->
  <node pkg="rosservice" type="rosservice" name="global_localization" args="call --wait /global_localization"/>
  <node pkg="twil_control" type="qbot_cmd_sequence" name="teleop">
    <param name="file" value="{drive}"/>
    <param name="topic" value="/cmd_vel"/>
  </node>
</launch>
"""
#: turtlebot3_navigation.launch with fake_localization in amcl.launch's place
FAKE_NAVIGATION = """<launch>
  <arg name="model" default="$(env TURTLEBOT3_MODEL)"/>
  <arg name="map_file" default="$(find turtlebot3_navigation)/maps/map.yaml"/>
  <arg name="open_rviz" default="true"/>
  <include file="$(find turtlebot3_bringup)/launch/turtlebot3_remote.launch">
    <arg name="model" value="$(arg model)"/>
  </include>
  <node pkg="map_server" name="map_server" type="map_server" args="$(arg map_file)"/>
  <node pkg="fake_localization" type="fake_localization" name="fake_localization">
    <param name="base_frame_id" value="base_footprint"/>
    <remap from="base_pose_ground_truth" to="/odom"/>
  </node>
  <include file="$(find turtlebot3_navigation)/launch/move_base.launch">
    <arg name="model" value="$(arg model)"/>
  </include>
</launch>
"""


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def _stamp(h) -> float:
    return h.stamp.sec + h.stamp.nanosec * 1e-9


def draw_goals(map_yaml: Path, n: int, seed: int) -> list[tuple[float, float, float]]:
    """n goals (x, y, yaw) in the map's free space: CLEARANCE from every occupied cell, joined to
    the spawn point through such cells, each MIN_SEPARATION from the one before."""
    from scipy import ndimage

    from twil_control.mapping.map_io import read_map

    m = read_map(map_yaml)
    data = np.asarray(m.data)
    clear = ndimage.distance_transform_edt(data < 65) * m.resolution >= CLEARANCE
    clear &= data == 0
    labels, _ = ndimage.label(clear)
    col, row = (int((v - o) / m.resolution) for v, o in zip(SPAWN[:2], m.origin[:2]))
    cells = np.argwhere(labels == labels[row, col])
    rng = np.random.default_rng(seed)
    goals, prev = [], SPAWN[:2]
    while len(goals) < n:
        r, c = cells[rng.integers(len(cells))]
        x, y = (round(o + (k + 0.5) * m.resolution, 2) for o, k in zip(m.origin[:2], (c, r)))
        if math.dist((x, y), prev) >= MIN_SEPARATION:
            goals.append((x, y, round(float(rng.uniform(-math.pi, math.pi)), 2)))
            prev = (x, y)
    return goals


def run(
    files: list[str],
    args: list[str],
    bag: Path,
    duration: float,
    env: dict,
    seed: int = 0,
    reuse: bool = False,
) -> dict:
    record = bag.with_suffix(".run.json")  # the run's exit, times and last line, beside its bag
    if reuse and bag.exists():  # a finished run of an earlier invocation: read its bag again
        if record.exists():
            return json.loads(record.read_text())
        return {"exit": 0, "wall_s": math.nan, "cpu_s": math.nan, "errors": [], "last_line": "(reused)"}
    bag.unlink(missing_ok=True)
    command = [sys.executable, "-m", "twil_control.launch", *files, *args]
    command += ["--duration", str(duration), "--bag", str(bag), "--seed", str(seed)]
    start, cpu0 = time.perf_counter(), os.times()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    cpu1 = os.times()
    lines = done.stderr.strip().splitlines()
    out = {
        "exit": done.returncode,
        "wall_s": round(time.perf_counter() - start, 1),
        "cpu_s": round(
            cpu1.children_user + cpu1.children_system - cpu0.children_user - cpu0.children_system, 1
        ),
        "errors": [line for line in lines if line.startswith(("[ERROR]", "error:"))],
        "last_line": lines[-1] if lines else "",
    }
    record.write_text(json.dumps(out))
    return out


def read(bag: Path) -> dict:
    """From a run's bag: the truth (t, x, y, yaw), the robot's pose in the map from /tf (t, x, y,
    yaw at every odom -> base_footprint, map -> odom the latest one stamped at or before),
    /amcl_pose (t, x, y, yaw), the goals sent (t, x, y) and move_base's results (t, status)."""
    out = {k: [] for k in ("truth", "odom", "map_odom", "amcl", "goals", "results")}
    with AnyReader([bag]) as reader:
        topics = ("/gazebo/model_states", "/tf", "/amcl_pose", "/move_base_simple/goal", "/move_base/result")
        conns = [c for c in reader.connections if c.topic in topics]
        for conn, t, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/gazebo/model_states":
                p = msg.pose[list(msg.name).index("turtlebot3_burger")]
                out["truth"].append((t * 1e-9, p.position.x, p.position.y, _yaw(p.orientation)))
            elif conn.topic == "/tf":
                for tf in msg.transforms:
                    key = {("odom", "base_footprint"): "odom", ("map", "odom"): "map_odom"}.get(
                        (tf.header.frame_id, tf.child_frame_id)
                    )
                    if key:
                        tr = tf.transform
                        out[key].append(
                            (_stamp(tf.header), tr.translation.x, tr.translation.y, _yaw(tr.rotation))
                        )
            elif conn.topic == "/amcl_pose":
                p = msg.pose.pose
                out["amcl"].append((_stamp(msg.header), p.position.x, p.position.y, _yaw(p.orientation)))
            elif conn.topic == "/move_base_simple/goal":
                out["goals"].append((t * 1e-9, msg.pose.position.x, msg.pose.position.y))
            else:
                out["results"].append((t * 1e-9, msg.status.status))
    out = {k: np.array(v) for k, v in out.items()}
    if len(out["map_odom"]) and len(out["odom"]):
        odom, mo = out["odom"], out["map_odom"]
        odom = odom[odom[:, 0] >= mo[0, 0]]
        k = np.searchsorted(mo[:, 0], odom[:, 0], side="right") - 1
        a, b = mo[k, 1:], odom[:, 1:]
        c, s = np.cos(a[:, 2]), np.sin(a[:, 2])
        pose = np.column_stack(
            [a[:, 0] + c * b[:, 0] - s * b[:, 1], a[:, 1] + s * b[:, 0] + c * b[:, 1], a[:, 2] + b[:, 2]]
        )
        out["in_map"] = np.column_stack([odom[:, 0], pose])
    return out


def errors_against_truth(poses: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(t, position error m, heading error rad) of (t, x, y, yaw) poses, the truth interpolated."""
    inside = (poses[:, 0] >= truth[0, 0]) & (poses[:, 0] <= truth[-1, 0])
    poses = poses[inside]
    x = np.interp(poses[:, 0], truth[:, 0], truth[:, 1])
    y = np.interp(poses[:, 0], truth[:, 0], truth[:, 2])
    yaw = np.interp(poses[:, 0], truth[:, 0], np.unwrap(truth[:, 3]))
    d = np.hypot(poses[:, 1] - x, poses[:, 2] - y)
    a = np.abs(np.remainder(poses[:, 3] - yaw + np.pi, 2 * np.pi) - np.pi)
    return np.column_stack([poses[:, 0], d, a])


def tour_figures(data: dict, n_goals: int) -> dict:
    results = data["results"]
    reached = int(np.sum(results[:, 1] == 3)) if len(results) else 0
    goal_times = []
    for (t_sent, *_), (t_done, status) in zip(data["goals"], results):
        if status == 3:
            goal_times.append(t_done - t_sent)
    out = {
        "reached": reached,
        "of": n_goals,
        "sim_s": float(data["truth"][-1, 0]),
        "mean_goal_s": float(np.mean(goal_times)) if goal_times else math.nan,
    }
    if "in_map" in data:
        # sampled at 10 Hz, whatever rate the odometry's transform comes at, so that the
        # statistics weigh time evenly
        err = errors_against_truth(data["in_map"], data["truth"])
        err = err[np.searchsorted(err[:, 0], np.arange(err[0, 0], err[-1, 0], 0.1))]
        out.update(
            mean_m=float(err[:, 1].mean()),
            p95_m=float(np.percentile(err[:, 1], 95)),
            max_m=float(err[:, 1].max()),
            mean_rad=float(err[:, 2].mean()),
            max_rad=float(err[:, 2].max()),
        )
        edges = np.arange(0.0, err[-1, 0] + ERROR_WINDOW, ERROR_WINDOW)
        out["over_time"] = [
            [float(a), round(float(err[(err[:, 0] >= a) & (err[:, 0] < b), 1].mean()), 4)]
            for a, b in zip(edges, edges[1:])
            if ((err[:, 0] >= a) & (err[:, 0] < b)).any()
        ]
    return out


def converged_after(data: dict, turn: float = 0.0) -> float:
    """Seconds until /amcl_pose came within GLOBAL_RADIUS of the truth (or of the truth turned by
    `turn` about the world's centre, an alias of it) to stay (nan: never)."""
    if not len(data["amcl"]):
        return math.nan
    truth = data["truth"]
    if turn:
        c, s = math.cos(turn), math.sin(turn)
        x, y = truth[:, 1], truth[:, 2]
        truth = np.column_stack([truth[:, 0], c * x - s * y, s * x + c * y, truth[:, 3] + turn])
    err = errors_against_truth(data["amcl"], truth)
    outside = np.nonzero(err[:, 1] >= GLOBAL_RADIUS)[0]
    if len(outside) == 0:
        return float(err[0, 0])
    if outside[-1] == len(err) - 1:
        return math.nan
    return float(err[outside[-1] + 1, 0])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--goals", type=int, default=20)
    parser.add_argument("--goal-seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, default=10, help="launch seeds of the global phase")
    parser.add_argument(
        "--goal-timeout", type=float, default=60.0, help="simulated s before a goal is cancelled"
    )
    parser.add_argument("--phases", default="tour,fake,global")
    parser.add_argument("--reuse", action="store_true", help="read the bags in --out again, not running")
    parser.add_argument("--turtlebot3", type=Path, help="folder holding the turtlebot3 packages (noetic)")
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "tb3_world_bench")
    opts = parser.parse_args()
    opts.out.mkdir(parents=True, exist_ok=True)
    paths = [str(p.resolve()) for p in (opts.turtlebot3,) if p] + [str(VENDOR)]
    env = dict(
        os.environ,
        ROS_PACKAGE_PATH=os.pathsep.join(paths),
        TURTLEBOT3_MODEL="burger",
        PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]),
    )
    from twil_control.core import packages

    gazebo, navigation = (packages.find(name, env) for name in ("turtlebot3_gazebo", "turtlebot3_navigation"))
    world = str(gazebo / "launch" / "turtlebot3_world.launch")
    nav = str(navigation / "launch" / "turtlebot3_navigation.launch")
    result = BenchResult(
        "tb3_world_bench",
        "TurtleBot3's e-manual navigation in turtlebot3_world (its own launch files, map and amcl, "
        "move_base parameters): a goal tour under amcl and under fake_localization, and amcl's "
        "global localisation from several seeds",
    )
    phases = opts.phases.split(",")
    goals = draw_goals(navigation / "maps" / "map.yaml", opts.goals, opts.goal_seed)
    goal_arg = "goals:=" + "; ".join(f"{x} {y} {yaw}" for x, y, yaw in goals)
    duration = (opts.goal_timeout + 5.0) * len(goals) + 5.0
    for phase in [p for p in phases if p in ("tour", "fake")]:
        navigation_launch = nav if phase == "tour" else str(_write(opts.out / "fake.launch", FAKE_NAVIGATION))
        bag = opts.out / f"{phase}.bag"
        args = ["open_rviz:=false", goal_arg, f"goal_timeout:={opts.goal_timeout}"]
        r = run([world, navigation_launch, str(GOALS_LAUNCH)], args, bag, duration, env, reuse=opts.reuse)
        figures = tour_figures(read(bag), len(goals))
        row = "amcl" if phase == "tour" else "fake_localization"
        print(f"== {phase}: exit {r['exit']}, {r['wall_s']} s wall, {r['cpu_s']} s CPU; {r['last_line']}")
        print(f"   {figures}")
        result.add(
            "goals reached",
            f"{figures['reached']}/{figures['of']}",
            row=row,
            headline=f"turtlebot3_world tour, {row}: goals reached",
        )
        result.add("simulated", figures["sim_s"], "s", row=row)
        result.add("mean time to a goal", figures["mean_goal_s"], "s", row=row)
        result.add("CPU per simulated s", r["cpu_s"] / figures["sim_s"], "s", row=row)
        for key, label, unit in (
            ("mean_m", "pose error mean", "m"),
            ("p95_m", "pose error p95", "m"),
            ("max_m", "pose error max", "m"),
            ("max_rad", "heading error max", "rad"),
        ):
            if key in figures:
                result.add(label, figures[key], unit, row=row)
        result.records[phase] = {**r, **figures, "goals": goals}
    if "global" in phases:
        drive = _write(opts.out / "global_drive.yaml", yaml.safe_dump(GLOBAL_DRIVE))
        launch = _write(opts.out / "global.launch", GLOBAL_LAUNCH.format(drive=drive))
        times, on_alias = [], dict.fromkeys(ALIASES, 0)
        for seed in range(opts.seeds):
            bag = opts.out / f"global_seed{seed}.bag"
            r = run(
                [world, nav, str(launch)], ["open_rviz:=false"], bag, GLOBAL_WITHIN, env, seed, opts.reuse
            )
            data = read(bag)
            after = converged_after(data)
            aliases = {name: converged_after(data, turn) for name, turn in ALIASES.items()}
            times.append(after)
            for name, t in aliases.items():
                on_alias[name] += int(t <= GLOBAL_WITHIN)
            print(
                f"== global seed {seed}: exit {r['exit']}, {r['wall_s']} s wall; converged after {after:.1f} s;"
                f" on the truth turned about the centre after {aliases}"
            )
            result.records[f"global_seed{seed}"] = {**r, "converged_s": after, "aliases_s": aliases}
        ok = [t for t in times if t <= GLOBAL_WITHIN]
        result.add(
            f"within {GLOBAL_RADIUS} m in {GLOBAL_WITHIN:.0f} s",
            f"{len(ok)}/{len(times)}",
            row="global localisation",
            headline="turtlebot3_world: amcl global localisation, runs converged within 30 s",
        )
        result.add(
            "median time to converge",
            float(np.median(ok)) if ok else math.nan,
            "s",
            row="global localisation",
        )
        result.add("slowest that converged", max(ok) if ok else math.nan, "s", row="global localisation")
        for name, count in on_alias.items():
            result.add(
                f"settled on the truth turned {name}", f"{count}/{len(times)}", row="global localisation"
            )
        for row, figures in CXX_GLOBAL.items():
            for label, value in figures.items():
                result.add(label, value, row=row)
    result.write()
    return 0


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


if __name__ == "__main__":
    sys.exit(main())
