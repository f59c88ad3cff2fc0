"""Third-party ROS 1 robot descriptions tried as a new user would: TurtleBot3 burger (xacro, STL
meshes, diff-drive + laser + IMU Gazebo plugins) and Husky (xacro, DAE meshes, gazebo_ros_control
with diff_drive_controller from its own control YAML), in the house world.

The descriptions are not part of this repository: point the script at checkouts of the public
packages (folders holding turtlebot3_description, turtlebot3_slam, turtlebot3_navigation, and
husky_description, husky_control)::

    .venv/bin/python bench/tryout_robots.py --turtlebot3 ~/src/turtlebot3 --husky ~/src/husky

Husky's description includes accessory xacro files from packages that are not in its repository
(fath_pivot_mount_description, flir_camera_description, velodyne_description, lms1xx); with the
accessories off (their environment variables' defaults) only the includes need to exist, so the
script writes empty stand-ins for them (``--husky-stubs``, default on), as a user without those
packages would. Each phase writes its launch file (YAML mirroring the packages' roslaunch files:
the same parameter files, loaded as they are) and runs it as its own process; it prints what
happened and writes a row per phase to bench/results/ (every phase's warnings, topic counts and
tf frames in the result's records).

Phases:
1. ``tb3_drive``: TurtleBot3 spawned from its xacro, robot_state_publisher, a cmd_vel sequence.
2. ``tb3_nav_as_loaded``: + gmapping (turtlebot3_slam's gmapping_params.yaml) + move_base with
   turtlebot3_navigation's move_base.launch files as loaded (DWAPlannerROS).
3. ``tb3_nav``: the same with TurtleBot3's own base_local_planner_params.yaml
   (TrajectoryPlannerROS) in place of the DWA planner's file, a goal to reach.
4. ``tb3_nav_qbot_planner``: the same with this project's qbot TrajectoryPlannerROS file
   (config/base_local_planner_params.yaml) instead of TurtleBot3's: separates the description
   and plugins from the local planner's tuning.
5. ``husky_drive``: Husky spawned from its xacro, husky_control's control.yaml, the spawner of
   husky_joint_publisher and husky_velocity_controller, the same kind of cmd_vel sequence.
"""
from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from rosbags.highlevel import AnyReader

from _result import BenchResult

ROOT = Path(__file__).resolve().parents[1]
HOUSE = ROOT / "sim" / "worlds" / "house.sdf"

HUSKY_STUBS = {
    "fath_pivot_mount_description": "urdf/lockmount.urdf.xacro",
    "flir_camera_description": "urdf/flir_blackflys.urdf.xacro",
    "velodyne_description": "urdf/VLP-16.urdf.xacro",
    "lms1xx": "urdf/sick_lms1xx.urdf.xacro",
}

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


def write_stubs(folder: Path) -> None:
    for package, include in HUSKY_STUBS.items():
        path = folder / package / include
        path.parent.mkdir(parents=True, exist_ok=True)
        (folder / package / "package.xml").write_text(
            f"<package format='2'><name>{package}</name><version>0.0.0</version>"
            f"<description>empty stand-in for the tryout</description></package>\n")
        path.write_text('<robot xmlns:xacro="http://ros.org/wiki/xacro"/>\n')


def tb3_launch(nav: str) -> str:
    """TurtleBot3 in the house: turtlebot3_house.launch + turtlebot3_remote.launch (+ SLAM and
    move_base for nav "as_loaded" / "trajectory")."""
    text = f"""launch:
  - arg: {{name: cmd_sequence, default: ""}}
  - param: {{name: robot_description,
            command: "$(find xacro)/xacro --inorder $(find turtlebot3_description)/urdf/turtlebot3_burger.urdf.xacro"}}
  - node: {{pkg: gazebo_ros, type: gzserver, name: gazebo, args: "-e ode {HOUSE}"}}
  - node: {{pkg: gazebo_ros, type: spawn_model, name: spawn_urdf,
           args: "-urdf -model turtlebot3 -x 0.0 -y 0.0 -z 0.0 -param robot_description"}}
  - node: {{pkg: robot_state_publisher, type: robot_state_publisher, name: robot_state_publisher,
           params: {{publish_frequency: 50.0}}}}
"""
    if not nav:
        return text + """  - node: {pkg: twil_control, type: qbot_cmd_sequence, name: teleop,
           params: {file: "$(arg cmd_sequence)", topic: /cmd_vel}}
"""
    local = {"as_loaded": "$(find turtlebot3_navigation)/param/dwa_local_planner_params_burger.yaml",
             "trajectory": "$(find turtlebot3_navigation)/param/base_local_planner_params.yaml",
             "qbot_planner": "$(find twil_control)/config/base_local_planner_params.yaml"}[nav]
    planner = "dwa_local_planner/DWAPlannerROS" if nav == "as_loaded" else "base_local_planner/TrajectoryPlannerROS"
    return text + f"""  - node:
      pkg: gmapping
      type: slam_gmapping
      name: turtlebot3_slam_gmapping
      params: {{base_frame: base_footprint, odom_frame: odom, map_frame: map}}
      rosparam: [{{file: "$(find turtlebot3_slam)/config/gmapping_params.yaml"}}]
  - node:
      pkg: move_base
      type: move_base
      name: move_base
      params: {{base_local_planner: {planner}}}
      rosparam:
        - {{file: "$(find turtlebot3_navigation)/param/costmap_common_params_burger.yaml", ns: global_costmap}}
        - {{file: "$(find turtlebot3_navigation)/param/costmap_common_params_burger.yaml", ns: local_costmap}}
        - {{file: "$(find turtlebot3_navigation)/param/local_costmap_params.yaml"}}
        - {{file: "$(find turtlebot3_navigation)/param/global_costmap_params.yaml"}}
        - {{file: "$(find turtlebot3_navigation)/param/move_base_params.yaml"}}
        - {{file: "{local}"}}
      remap: {{cmd_vel: /cmd_vel, odom: odom}}
  - node: {{pkg: twil_control, type: move_base_goals, name: goals, params: {{goals: "0.0 1.2 1.5708", start_delay: 2.0}}}}
"""


def husky_launch() -> str:
    """Husky: spawn_husky.launch (control.launch's description, control YAML and spawner), with
    the robot namespace "/" of its defaults."""
    return f"""launch:
  - arg: {{name: cmd_sequence, default: ""}}
  - param: {{name: robot_description,
            command: "$(find xacro)/xacro $(find husky_description)/urdf/husky.urdf.xacro robot_namespace:=/"}}
  - node: {{pkg: gazebo_ros, type: gzserver, name: gazebo, args: "-e ode {HOUSE}"}}
  - rosparam: {{file: "$(find husky_control)/config/control.yaml"}}
  - node: {{pkg: controller_manager, type: spawner, name: base_controller_spawner,
           args: "husky_joint_publisher husky_velocity_controller"}}
  - node: {{pkg: robot_state_publisher, type: robot_state_publisher, name: robot_state_publisher}}
  - node: {{pkg: gazebo_ros, type: spawn_model, name: spawn_husky_model,
           args: "-x 0.0 -y 0.0 -z 0.0 -Y 0.0 -unpause -urdf -param robot_description -model husky -robot_namespace /"}}
  - node: {{pkg: twil_control, type: qbot_cmd_sequence, name: teleop,
           params: {{file: "$(arg cmd_sequence)", topic: /husky_velocity_controller/cmd_vel}}}}
"""


def run_launch(launch: Path, bag: Path, duration: float, env: dict, args: list[str]) -> dict:
    command = [sys.executable, "-m", "twil_control.launch", str(launch), *args, "--duration", str(duration),
               "--bag", str(bag)]
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    lines = done.stderr.strip().splitlines()
    return {"exit": done.returncode, "wall_s": round(wall, 1),
            "warnings": [line for line in lines if line.startswith(("[WARNING]", "[ERROR]", "error:"))],
            "last_line": lines[-1] if lines else ""}


def _yaw(q) -> float:
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def analyse(bag: Path, model: str, urdf_links: list[str]) -> dict:
    """Figures of a run's bag: the model's true path, scans, tf frames, clock and log counts."""
    out: dict = {}
    if not bag.exists():
        return out
    with AnyReader([bag]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        out["topics"] = counts
        frames, path, statuses = set(), [], []
        conns = [c for c in reader.connections
                 if c.topic in ("/tf", "/tf_static", "/gazebo/model_states", "/move_base/result")]
        for conn, t, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic in ("/tf", "/tf_static"):
                frames.update(f for tf in msg.transforms for f in (tf.header.frame_id, tf.child_frame_id))
            elif conn.topic == "/gazebo/model_states" and model in msg.name:
                pose = msg.pose[list(msg.name).index(model)]
                path.append((t * 1e-9, pose.position.x, pose.position.y, pose.position.z, _yaw(pose.orientation)))
            else:
                statuses.append((round(t * 1e-9, 2), msg.status.status, msg.status.text))
    if path:
        travelled = sum(math.dist(a[1:3], b[1:3]) for a, b in zip(path, path[1:]))
        out["true_path"] = {"travelled_m": round(travelled, 3), "end": [round(v, 3) for v in path[-1][1:]],
                            "min_z": round(min(p[3] for p in path), 4), "max_z": round(max(p[3] for p in path), 4)}
    out["tf_frames"] = sorted(frames)
    out["urdf_links_without_tf"] = sorted(set(urdf_links) - frames)
    out["move_base_results"] = statuses
    return out


def urdf_links(env: dict, package: str, xacro: str, *args: str) -> list[str]:
    code = ("import sys; from twil_control.core import packages; "
            "from twil_control.description.xacro_command import run_xacro; "
            "from twil_control.description.urdf import parse_urdf; "
            f"print(' '.join(parse_urdf(run_xacro([str(packages.find({package!r})) + {xacro!r}, *sys.argv[1:]])).links))")
    done = subprocess.run([sys.executable, "-c", code, *args], env=env, capture_output=True, text=True)
    return done.stdout.split()


SUMMARY_LINE = re.compile(r"simulated ([\d.]+) s in ([\d.]+) s .*with (\d+) messages")


def record(out: BenchResult, phase: str, run: dict) -> None:
    """A phase as one row: exit code, simulated time and real-time factor, messages, the robot's
    true travel, move_base's results, how many warnings, the URDF links without tf, the error."""
    out.add("exit", run["exit"], row=phase)
    m = SUMMARY_LINE.search(run.get("last_line", ""))
    if m:
        out.add("simulated", float(m.group(1)), "s", row=phase)
        out.add("rtf", float(m.group(1)) / float(m.group(2)), "x real time", row=phase)
        out.add("messages", int(m.group(3)), row=phase)
    if "true_path" in run:
        out.add("travelled", run["true_path"]["travelled_m"], "m", row=phase)
    if phase.startswith("tb3_nav") and run["exit"] == 0:
        results = run.get("move_base_results") or []
        out.add("move_base", "; ".join(f"{text} at {t:g} s" for t, _, text in results) or "no result", row=phase)
    out.add("warnings", sum(line.startswith("[WARNING]") for line in run["warnings"]), row=phase)
    if "urdf_links_without_tf" in run:
        out.add("links without tf", ", ".join(run["urdf_links_without_tf"]) or "none", row=phase)
    errors = [line for line in run["warnings"] if not line.startswith("[WARNING]")]
    if errors:
        out.add("error", errors[0][:160] + ("..." if len(errors[0]) > 160 else ""), row=phase)
    out.records[phase] = run


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--turtlebot3", type=Path, help="folder holding the turtlebot3 packages")
    parser.add_argument("--husky", type=Path, help="folder holding the husky packages")
    parser.add_argument("--out", type=Path, default=Path("/tmp/tryout_robots"))
    parser.add_argument("--no-husky-stubs", action="store_true")
    parser.add_argument("--drive-duration", type=float, default=20.0)
    parser.add_argument("--nav-duration", type=float, default=60.0)
    parser.add_argument("--phases", default="tb3_drive,tb3_nav_as_loaded,tb3_nav,tb3_nav_qbot_planner,husky_drive")
    opts = parser.parse_args()
    result = BenchResult("tryout_robots", "TurtleBot3 and Husky from their own packages (xacro, meshes, Gazebo "
                         "plugins, control and navigation files) driven and navigated in the house world")
    opts.out.mkdir(parents=True, exist_ok=True)
    paths = [str(p) for p in (opts.turtlebot3, opts.husky) if p]
    if opts.husky and not opts.no_husky_stubs:
        write_stubs(opts.out / "stubs")
        paths.append(str(opts.out / "stubs"))
    env = dict(os.environ, ROS_PACKAGE_PATH=os.pathsep.join(paths), PYTHONPATH=os.pathsep.join(
        [str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    sequence = opts.out / "cmd_sequence.yaml"
    sequence.write_text(CMD_SEQUENCE)
    phases = {
        "tb3_drive": (lambda: tb3_launch(""), opts.drive_duration, "turtlebot3"),
        "tb3_nav_as_loaded": (lambda: tb3_launch("as_loaded"), opts.nav_duration, "turtlebot3"),
        "tb3_nav": (lambda: tb3_launch("trajectory"), opts.nav_duration, "turtlebot3"),
        "tb3_nav_qbot_planner": (lambda: tb3_launch("qbot_planner"), opts.nav_duration, "turtlebot3"),
        "husky_drive": (husky_launch, opts.drive_duration, "husky"),
    }
    for name in opts.phases.split(","):
        make, duration, model = phases[name]
        if (model == "turtlebot3" and not opts.turtlebot3) or (model == "husky" and not opts.husky):
            continue
        launch = opts.out / f"{name}.launch.yaml"
        launch.write_text(make())
        bag = opts.out / f"{name}.bag"
        bag.unlink(missing_ok=True)
        args = [f"cmd_sequence:={sequence}"] if "drive" in name else []
        run = run_launch(launch, bag, duration, env, args)
        links = (urdf_links(env, "turtlebot3_description", "/urdf/turtlebot3_burger.urdf.xacro")
                 if model == "turtlebot3" else urdf_links(env, "husky_description", "/urdf/husky.urdf.xacro"))
        run.update(analyse(bag, model, links))
        record(result, name, run)
        print(f"== {name}: exit {run['exit']}, {run['wall_s']} s wall; {run['last_line']}")
        for line in run["warnings"]:
            print(f"   {line[:300]}")
        for key in ("true_path", "urdf_links_without_tf", "move_base_results"):
            if key in run:
                print(f"   {key}: {run[key]}")
        if "topics" in run:
            print(f"   topics: {run['topics']}")
    result.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
