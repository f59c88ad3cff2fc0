"""Third-party ROS 1 robots tried as a new user would: TurtleBot3 burger and Husky, from their own
packages' launch and parameter files (roslaunch XML, through ROS_PACKAGE_PATH), in the house world.

By default the packages are the copies vendored for the tests (tests/data/ros1/vendor: the
files the tests read, unchanged) with empty stand-ins for the accessory packages Husky's
description includes (tests/data/ros1/stubs); that runs tb3_drive, tb3_nav and husky_drive. The
other phases need files not vendored: point the script at checkouts (folders holding
turtlebot3_description, turtlebot3_bringup, turtlebot3_slam, turtlebot3_navigation; and
husky_description, husky_control, husky_navigation; optionally lms1xx, Husky's laser), searched
before the vendored copies::

    .venv/bin/python bench/tryout_robots.py [--goals 3] [--phases tb3_drive,tb3_nav,husky_drive]
    .venv/bin/python bench/tryout_robots.py --turtlebot3 ~/src/turtlebot3 --husky ~/src/husky \\
        --lms1xx ~/src/LMS1xx --phases tb3_nav_trajectory,husky_control,husky_nav

Each phase writes a top-level roslaunch XML file (what a user would write: the simulator in the
place of gazebo_ros's empty_world.launch with the house world, spawn_model, then the packages'
own launch files included unchanged) and runs it as its own process with
``python -m twil_control.launch``. Goals are drawn as bench/nav_goals.py draws them (free cells
of the house reachable from the spawn point, 2 m apart, seeded; for husky_nav free for the
footprint and inflation of husky_navigation's costmap_common.yaml) and sent one after another by
twil_control/move_base_goals, each cancelled after --goal-timeout simulated seconds. It prints
what happened and writes a row per phase to bench/results/ (goals reached of those sent, the
largest distance of the true pose from a reached goal; every phase's warnings, goals, topic
counts and tf frames in the result's records).

Phases:
1. ``tb3_drive``: turtlebot3_remote.launch (its description and robot_state_publisher), spawned
   from the xacro, a cmd_vel sequence.
2. ``tb3_nav``: turtlebot3_slam.launch (gmapping with its gmapping_params.yaml) and
   turtlebot3_navigation's move_base.launch, as they are (DWAPlannerROS with
   dwa_local_planner_params_burger.yaml), and the goals.
3. ``tb3_nav_trajectory``: the same move_base files but TurtleBot3's base_local_planner_params.yaml
   (TrajectoryPlannerROS) as the local planner.
4. ``husky_control``: husky_control's control.launch as it is: its nodes this project does not
   provide (robot_localization's EKF, twist_mux, the interactive marker server) named in one error.
5. ``husky_drive``: what control.launch does without those nodes (its description, control.yaml,
   the spawner of husky_joint_publisher and husky_velocity_controller, robot_state_publisher),
   spawned as spawn_husky.launch does, a cmd_vel sequence.
6. ``seed_drive`` (needs ``--qbot``: a checkout, or a git directory, of qbot's original package,
   zwilling/4-wheeled-ros-robot, which has no licence and is never copied into this repository):
   its README's set-up (catkin_ws/src/qbot, GAZEBO_MODEL_PATH and GAZEBO_RESOURCE_PATH at its
   gazebo/ folders) and its gazebo.launch as it is (its world includes its qbot model.sdf, which
   includes the hokuyo-ros laser model), driven by ``rostopic pub -r 10 /qbot/cmd_vel``: the
   skid-steer plugin's odometry and the laser's 640-beam scans on /qbot/laser/scan.
7. ``husky_nav``: husky_drive's bring-up with the LMS1xx laser (HUSKY_LMS1XX_ENABLED=1, needs
   --lms1xx) and husky_navigation's gmapping_demo.launch as it is (gmapping, move_base with
   planner.yaml and the costmap files), and the goals; what control.launch's missing nodes do
   for navigation done otherwise: odom -> base_link from the velocity controller's wheel
   odometry (enable_odom_tf true: robot_localization's EKF publishes it on the robot), and
   move_base's cmd_vel remapped to the velocity controller (twist_mux's job).
"""

from __future__ import annotations

import argparse
import math
import os
import re
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
sys.path.insert(0, str(ROOT / "bench"))
HOUSE = ROOT / "sim" / "worlds" / "house.sdf"

VENDOR = ROOT / "tests" / "data" / "ros1" / "vendor"
STUBS = ROOT / "tests" / "data" / "ros1" / "stubs"

# Out of the spawn point (0, 0) facing +x: north up the hall, back, a turn (house.sdf's layout,
# see config/qbot_explore_house.yaml).
CMD_SEQUENCE = """rate: 10
segments:
  - {time: 0.0, linear_x: 0.0, angular_z: 0.8}
  - {time: 1.96, linear_x: 0.15, angular_z: 0.0}
  - {time: 9.96, linear_x: 0.0, angular_z: -0.8}
  - {time: 13.9, linear_x: 0.15, angular_z: 0.0}
  - {time: 17.9, linear_x: 0.0, angular_z: 0.0}
"""

ARGS = """  <arg name="cmd_sequence" default=""/>
  <arg name="goals_file" default=""/>
  <arg name="goal_timeout" default="0.0"/>
"""
# the simulator in the place of gazebo_ros's empty_world.launch with a world
WORLD = f"""  <node pkg="gazebo_ros" type="gzserver" name="gazebo" args="-e ode {HOUSE}"/>
"""
TELEOP = """  <node pkg="twil_control" type="qbot_cmd_sequence" name="teleop">
    <param name="file" value="$(arg cmd_sequence)"/><param name="topic" value="{topic}"/>
  </node>
"""
GOALS = """  <node pkg="twil_control" type="move_base_goals" name="goals">
    <param name="file" value="$(arg goals_file)"/><param name="start_delay" value="2.0"/>
    <param name="timeout" value="$(arg goal_timeout)"/>
  </node>
"""
TB3_SPAWN = """  <node pkg="gazebo_ros" type="spawn_model" name="spawn_urdf"
        args="-urdf -model turtlebot3 -x 0.0 -y 0.0 -z 0.0 -param robot_description"/>
"""
TB3_SLAM = """  <include file="$(find turtlebot3_slam)/launch/turtlebot3_slam.launch">
    <arg name="model" value="burger"/><arg name="open_rviz" value="false"/>
  </include>
"""
# turtlebot3_navigation's move_base.launch with another local planner file
TB3_MOVE_BASE = """  <node pkg="move_base" type="move_base" name="move_base" output="screen">
    <param name="base_local_planner" value="{planner}"/>
    <rosparam file="$(find turtlebot3_navigation)/param/costmap_common_params_burger.yaml" command="load" ns="global_costmap"/>
    <rosparam file="$(find turtlebot3_navigation)/param/costmap_common_params_burger.yaml" command="load" ns="local_costmap"/>
    <rosparam file="$(find turtlebot3_navigation)/param/local_costmap_params.yaml" command="load"/>
    <rosparam file="$(find turtlebot3_navigation)/param/global_costmap_params.yaml" command="load"/>
    <rosparam file="$(find turtlebot3_navigation)/param/move_base_params.yaml" command="load"/>
    <rosparam file="{file}" command="load"/>
    <remap from="cmd_vel" to="/cmd_vel"/>
  </node>
"""
HUSKY_BRINGUP = """  <include file="$(find husky_description)/launch/description.launch"/>
  <rosparam command="load" file="$(find husky_control)/config/control.yaml"/>
  <node name="base_controller_spawner" pkg="controller_manager" type="spawner"
        args="husky_joint_publisher husky_velocity_controller"/>
  <node name="robot_state_publisher" pkg="robot_state_publisher" type="robot_state_publisher"/>
  <node name="spawn_husky_model" pkg="gazebo_ros" type="spawn_model"
        args="-x 0.0 -y 0.0 -z 0.0 -Y 0.0 -unpause -urdf -param robot_description -model husky -robot_namespace /"/>
"""


def tb3_launch(phase: str) -> str:
    body = WORLD
    if phase == "tb3_drive":
        body += (
            """  <include file="$(find turtlebot3_bringup)/launch/turtlebot3_remote.launch">
    <arg name="model" value="burger"/>
  </include>
"""
            + TB3_SPAWN
            + TELEOP.format(topic="/cmd_vel")
        )
    else:
        body += TB3_SLAM + TB3_SPAWN + GOALS
        if phase == "tb3_nav":
            body += """  <include file="$(find turtlebot3_navigation)/launch/move_base.launch">
    <arg name="model" value="burger"/>
  </include>
"""
        else:
            body += TB3_MOVE_BASE.format(
                planner="base_local_planner/TrajectoryPlannerROS",
                file="$(find turtlebot3_navigation)/param/base_local_planner_params.yaml",
            )
    return f"<launch>\n{ARGS}{body}</launch>\n"


def husky_launch(phase: str) -> str:
    if phase == "husky_control":
        return f"""<launch>\n{ARGS}{WORLD}  <include file="$(find husky_control)/launch/control.launch"/>\n</launch>\n"""
    body = WORLD + HUSKY_BRINGUP
    if phase == "husky_drive":
        body += TELEOP.format(topic="/husky_velocity_controller/cmd_vel")
    else:
        body += (
            """  <!-- robot_localization's job in husky_control (its EKF publishes odom -> base_link, so
       control.yaml turns the controller's own transform off): the wheel odometry's transform -->
  <param name="husky_velocity_controller/enable_odom_tf" value="true"/>
  <group>
    <!-- twist_mux's job in husky_control: move_base's commands to the velocity controller -->
    <remap from="cmd_vel" to="/husky_velocity_controller/cmd_vel"/>
    <include file="$(find husky_navigation)/launch/gmapping_demo.launch"/>
  </group>
"""
            + GOALS
        )
    return f"<launch>\n{ARGS}{body}</launch>\n"


def run_launch(launch: Path, bag: Path, duration: float, env: dict, args: list[str]) -> dict:
    command = [
        sys.executable,
        "-m",
        "twil_control.launch",
        str(launch),
        *args,
        "--duration",
        str(duration),
        "--bag",
        str(bag),
    ]
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    lines = done.stderr.strip().splitlines()
    problems = [line for line in lines if line.startswith(("[WARNING]", "[ERROR]", "error:"))]
    if done.returncode == 2:  # the one error of a launch that could not start, with its lines
        problems = lines
    return {
        "exit": done.returncode,
        "wall_s": round(wall, 1),
        "warnings": problems,
        "goal_lines": [line for line in lines if "/goals: goal" in line],
        "last_line": lines[-1] if lines else "",
    }


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def analyse(bag: Path, model: str) -> dict:
    """Figures of a run's bag: the model's true path, tf frames, move_base's results, and per goal
    where the robot truly was when its result came."""
    out: dict = {}
    if not bag.exists():
        return out
    with AnyReader([bag]) as reader:
        out["topics"] = {c.topic: c.msgcount for c in reader.connections}
        frames, path, results = set(), [], []
        conns = [
            c
            for c in reader.connections
            if c.topic in ("/tf", "/tf_static", "/gazebo/model_states", "/move_base/result")
        ]
        for conn, t, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic in ("/tf", "/tf_static"):
                frames.update(f for tf in msg.transforms for f in (tf.header.frame_id, tf.child_frame_id))
            elif conn.topic == "/gazebo/model_states" and model in msg.name:
                pose = msg.pose[list(msg.name).index(model)]
                path.append(
                    (t * 1e-9, pose.position.x, pose.position.y, pose.position.z, _yaw(pose.orientation))
                )
            elif conn.topic == "/move_base/result":
                results.append((round(t * 1e-9, 2), msg.status.status, msg.status.text))
    if path:
        travelled = sum(math.dist(a[1:3], b[1:3]) for a, b in zip(path, path[1:]))
        out["true_path"] = {
            "travelled_m": round(travelled, 3),
            "end": [round(v, 3) for v in path[-1][1:]],
            "min_z": round(min(p[3] for p in path), 4),
            "max_z": round(max(p[3] for p in path), 4),
        }
        times = np.array([p[0] for p in path])
        for i, (t, status, text) in enumerate(results):
            k = int(np.clip(np.searchsorted(times, t), 0, len(path) - 1))
            results[i] = (t, status, text, [round(v, 3) for v in path[k][1:3]])
    out["tf_frames"] = sorted(frames)
    out["move_base_results"] = results
    return out


def draw_goals(n: int, seed: int, tmp: Path, common: Path | None = None) -> list[tuple[float, float, float]]:
    """bench/nav_goals.py's goals: free cells of the house reachable from the spawn point, for
    qbot's footprint and inflation, or those of a robot's costmap_common file (`common`: its
    footprint, footprint_padding and inflation radius, either style)."""
    from nav_goals import house_map

    from twil_control.mapping.map_io import read_map
    from twil_control.navigation import evaluation as ev
    from twil_control.navigation.footprint import FootprintCells, parse_footprint

    map_yaml, m, cells = house_map(tmp)
    if common is not None:
        p = yaml.safe_load(common.read_text())
        occ = read_map(map_yaml)
        inflation = p.get("inflation", {}).get("inflation_radius", p.get("inflation_radius", 0.55))
        scaling = p.get("inflation", {}).get("cost_scaling_factor", p.get("cost_scaling_factor", 10.0))
        cells = FootprintCells(
            parse_footprint(p["footprint"], p.get("footprint_padding", 0.0)), occ.resolution
        )
        m = ev.costmap_from_occupancy(occ.data, occ.resolution, occ.origin, cells, inflation, scaling)
    return ev.sample_goals(m, cells, (0.0, 0.0, 0.0), n, np.random.default_rng(seed))


def score(results: list, goals: list, tolerance: float) -> dict:
    """Per goal its result and how far from it the robot truly stopped (gmapping's map frame is
    the spawn pose's, so the goals are in both); reached: SUCCEEDED."""
    rows = []
    names = {2: "PREEMPTED", 3: "SUCCEEDED", 4: "ABORTED", 5: "REJECTED"}
    for goal, result in zip(goals, [r for r in results if r[1] in names]):
        t, status, text, at = result if len(result) == 4 else (*result, None)
        err = round(math.dist(goal[:2], at), 3) if at else None
        rows.append(
            {
                "goal": list(goal),
                "status": names[status],
                "at_s": t,
                "true_xy": at,
                "true_error_m": err,
                "text": text,
            }
        )
    reached = [r for r in rows if r["status"] == "SUCCEEDED"]
    errors = [r["true_error_m"] for r in reached if r["true_error_m"] is not None]
    return {
        "reached": len(reached),
        "of": len(goals),
        "xy_goal_tolerance_m": tolerance,
        "max_true_error_m": max(errors) if errors else None,
        "per_goal": rows,
    }


SUMMARY_LINE = re.compile(r"simulated ([\d.]+) s in ([\d.]+) s .*with (\d+) messages")


def record(out: BenchResult, phase: str, run: dict) -> None:
    """A phase as one row: exit code, simulated time and real-time factor, messages, the robot's
    true travel, goals reached and how far from them, how many warnings, the first error."""
    out.add("exit", run["exit"], row=phase)
    m = SUMMARY_LINE.search(run.get("last_line", ""))
    if m:
        out.add("simulated", float(m.group(1)), "s", row=phase)
        out.add("rtf", float(m.group(1)) / float(m.group(2)), "x real time", row=phase)
        out.add("messages", int(m.group(3)), row=phase)
    if "true_path" in run:
        out.add("travelled", run["true_path"]["travelled_m"], "m", row=phase)
    if "goals" in run:
        goals = run["goals"]
        out.add("goals reached", f"{goals['reached']}/{goals['of']}", row=phase, headline=phase == "tb3_nav")
        if goals["max_true_error_m"] is not None:
            out.add("largest true distance from a reached goal", goals["max_true_error_m"], "m", row=phase)
        last = goals["per_goal"][-1]["text"] if goals["per_goal"] else "no result"
        out.add("last result", last[:160], row=phase)
    out.add("warnings", sum(line.startswith("[WARNING]") for line in run["warnings"]), row=phase)
    errors = [line for line in run["warnings"] if not line.startswith("[WARNING]")]
    if errors:
        out.add("error", errors[0][:160] + ("..." if len(errors[0]) > 160 else ""), row=phase)
    out.records[phase] = run


SEED_DRIVE = """<launch>
  <node pkg="rostopic" type="rostopic" name="drive"
        args="pub -r 10 /qbot/cmd_vel geometry_msgs/Twist '{linear: {x: 0.2}, angular: {z: 0.1}}'"/>
</launch>
"""


def seed_drive(source: Path, out: Path, env: dict) -> dict:
    """qbot's original package set up as its README says, its gazebo.launch and a rostopic pub."""
    import shutil

    package = out / "catkin_ws" / "src" / "qbot"
    shutil.rmtree(package, ignore_errors=True)
    package.mkdir(parents=True)
    if (source / "HEAD").is_file() and not (source / ".git").exists():  # a git directory
        archive = subprocess.run(
            ["git", "-C", str(source), "archive", "HEAD"], capture_output=True, check=True
        )
        subprocess.run(["tar", "-x", "-C", str(package)], input=archive.stdout, check=True)
    else:
        shutil.copytree(source, package, dirs_exist_ok=True, ignore=shutil.ignore_patterns(".git"))
    drive = out / "seed_drive.launch"
    drive.write_text(SEED_DRIVE)
    bag = out / "seed_drive.bag"
    bag.unlink(missing_ok=True)
    env = dict(
        env,
        ROS_PACKAGE_PATH=str(package.parent),
        GAZEBO_MODEL_PATH=str(package / "gazebo" / "models"),
        GAZEBO_RESOURCE_PATH=str(package / "gazebo" / "world"),
    )
    command = [sys.executable, "-m", "twil_control.launch", "launch/gazebo.launch", str(drive)]
    start = time.perf_counter()
    done = subprocess.run(
        [*command, "--duration", "5", "--bag", str(bag)], cwd=package, env=env, capture_output=True, text=True
    )
    lines = done.stderr.strip().splitlines()
    run = {
        "exit": done.returncode,
        "wall_s": round(time.perf_counter() - start, 1),
        "warnings": [line for line in lines if line.startswith(("[WARNING]", "[ERROR]", "error:"))],
        "last_line": lines[-1] if lines else "",
    }
    run.update(analyse(bag, "qbot"))
    if bag.exists():
        with AnyReader([bag]) as reader:
            conns = [c for c in reader.connections if c.topic == "/qbot/laser/scan"]
            beams = [
                len(reader.deserialize(raw, c.msgtype).ranges)
                for c, _, raw in reader.messages(connections=conns)
            ]
        run["scans"] = {"count": len(beams), "beams": sorted(set(beams))}
    return run


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--turtlebot3", type=Path, help="folder holding the turtlebot3 packages")
    parser.add_argument("--husky", type=Path, help="folder holding the husky packages")
    parser.add_argument("--lms1xx", type=Path, help="folder holding the lms1xx package (Husky's laser)")
    parser.add_argument("--qbot", type=Path, help="qbot's original package: a checkout or a git directory")
    parser.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "tryout_robots")
    parser.add_argument("--drive-duration", type=float, default=20.0)
    parser.add_argument("--goals", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--goal-timeout", type=float, default=90.0, help="simulated s before a goal is cancelled"
    )
    parser.add_argument(
        "--phases",
        default="tb3_drive,tb3_nav,husky_drive",
        help="also tb3_nav_trajectory, husky_control, husky_nav, seed_drive (need checkouts)",
    )
    opts = parser.parse_args()
    opts.out.mkdir(parents=True, exist_ok=True)
    # checkouts first (the first package of a name found wins), then the vendored copies and stand-ins
    paths = [str(p.resolve()) for p in (opts.turtlebot3, opts.husky, opts.lms1xx) if p] + [
        str(VENDOR),
        str(STUBS),
    ]
    base_env = dict(
        os.environ,
        ROS_PACKAGE_PATH=os.pathsep.join(paths),
        TURTLEBOT3_MODEL="burger",
        PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]),
    )
    sequence = opts.out / "cmd_sequence.yaml"
    sequence.write_text(CMD_SEQUENCE)
    goals = draw_goals(opts.goals, opts.seed, opts.out)
    goals_file = opts.out / "goals.yaml"
    goals_file.write_text(yaml.safe_dump([{"x": x, "y": y, "yaw": yaw} for x, y, yaw in goals]))
    drawn = {"qbot footprint": goals}
    # what each phase needs: its launch, robot, xy goal tolerance (the local planner file's)
    tolerance = {"tb3_nav": 0.05, "tb3_nav_trajectory": 0.10, "husky_nav": 0.2}
    result = BenchResult(
        "tryout_robots",
        "TurtleBot3 and Husky from their own packages (xacro, meshes, Gazebo "
        "plugins, control and navigation files) driven and navigated in the house world",
    )
    for name in opts.phases.split(","):
        if name == "seed_drive":
            if not opts.qbot:
                print("== seed_drive: skipped (qbot's original package: --qbot)")
                continue
            run = seed_drive(opts.qbot, opts.out, base_env)
            record(result, name, run)
            print(f"== {name}: exit {run['exit']}, {run['wall_s']} s wall; {run['last_line']}")
            print(f"   true_path: {run.get('true_path')}; scans: {run.get('scans')}")
            continue
        robot = "turtlebot3" if name.startswith("tb3") else "husky"
        env = dict(base_env)
        if name == "husky_nav":
            if not opts.lms1xx:
                print("== husky_nav: skipped (Husky's laser needs the lms1xx package: --lms1xx)")
                continue
            env["HUSKY_LMS1XX_ENABLED"] = "1"
        goals, goals_file = drawn["qbot footprint"], opts.out / "goals.yaml"
        if name == "husky_nav":
            # Husky is 1 x 0.66 m: goals its own costmap can hold
            from twil_control.core import packages

            common = packages.find("husky_navigation", env) / "config" / "costmap_common.yaml"
            goals = drawn.setdefault(
                "husky_navigation costmap", draw_goals(opts.goals, opts.seed, opts.out, common)
            )
            goals_file = opts.out / "goals_husky.yaml"
            goals_file.write_text(yaml.safe_dump([{"x": x, "y": y, "yaw": yaw} for x, y, yaw in goals]))
        launch = opts.out / f"{name}.launch"
        launch.write_text(tb3_launch(name) if robot == "turtlebot3" else husky_launch(name))
        bag = opts.out / f"{name}.bag"
        bag.unlink(missing_ok=True)
        nav = name in tolerance
        args = (
            [f"goals_file:={goals_file}", f"goal_timeout:={opts.goal_timeout}"]
            if nav
            else [f"cmd_sequence:={sequence}"]
        )
        duration = (opts.goal_timeout + 5.0) * len(goals) if nav else opts.drive_duration
        run = run_launch(launch, bag, duration, env, args)
        run.update(analyse(bag, robot))
        if nav:
            run["goals"] = score(run.get("move_base_results", []), goals, tolerance[name])
            run["goals_drawn"] = goals
        record(result, name, {**run, "seed": opts.seed, "goal_timeout_s": opts.goal_timeout})
        print(f"== {name}: exit {run['exit']}, {run['wall_s']} s wall; {run['last_line']}")
        for line in run["warnings"]:
            print(f"   {line[:300]}")
        for key in ("true_path", "move_base_results"):
            if key in run:
                print(f"   {key}: {run[key]}")
        if nav:
            g = run["goals"]
            print(
                f"   goals reached: {g['reached']}/{g['of']} SUCCEEDED (xy_goal_tolerance {g['xy_goal_tolerance_m']} m; "
                f"largest distance of the true pose from a reached goal {g['max_true_error_m']} m)"
            )
    result.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
