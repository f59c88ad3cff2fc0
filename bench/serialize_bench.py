"""Microseconds per message of ROS 1 serialisation: rosbags' serialize_ros1 vs the project's
generated serializers (core/ros1_serializer.py, what messages.serialize uses), in one run.

The messages are the ones a launch records: the launch (default the qbot navigation, 10
simulated s) is run into a temporary bag, which is read back; hot types the run did not
record (nav_msgs/Path before a goal is planned, geometry_msgs/Twist when cmd_vel is not
recorded) get a synthetic message. For each type both serializers are timed over the same
messages (best of 7 interleaved passes, after a warm-up pass that also checks the bytes are
equal), then every recorded message is serialised once each way: the recorder's
serialisation cost for that run.

    .venv/bin/python bench/serialize_bench.py [--launch launch/qbot_navigation.launch.yaml]
        [--duration 10] [--bag EXISTING.bag]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
from rosbags.rosbag1 import Reader

from twil_control import PACKAGE_ROOT
from twil_control.core import messages
from twil_control.core.ros1_serializer import Ros1Serializer
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run

HOT_TYPES = [
    "nav_msgs/msg/Odometry", "tf2_msgs/msg/TFMessage", "sensor_msgs/msg/JointState",
    "std_msgs/msg/UInt8MultiArray", "sensor_msgs/msg/LaserScan", "geometry_msgs/msg/Twist",
    "nav_msgs/msg/OccupancyGrid", "nav_msgs/msg/Path", "actionlib_msgs/msg/GoalStatusArray",
]
SAMPLE = 400  # messages per type timed (the first ones of the bag)


def record(launch_file: str, duration: float, bag: Path) -> float:
    plan = load_launch(PACKAGE_ROOT / launch_file, {})
    result = run(plan, RunOptions(duration=duration, bag=bag))
    if result.error:
        raise result.error
    return result.wall_time


def read_messages(bag: Path) -> dict[str, list]:
    store = messages.typestore()
    out: dict[str, list] = defaultdict(list)
    with Reader(bag) as reader:
        for conn, _, raw in reader.messages():
            out[conn.msgtype].append(store.deserialize_ros1(raw, conn.msgtype))
    return out


def synthetic_path(poses: int = 200):
    """A plan as move_base publishes it: poses along a curve, every header alike."""
    cls = messages.msg_class
    rng = np.random.default_rng(0)
    xy = np.cumsum(rng.normal(0.05, 0.01, (poses, 2)), axis=0)
    hdr = messages.header("map", 12.5)
    return cls("nav_msgs/Path")(header=hdr, poses=[
        cls("geometry_msgs/PoseStamped")(header=hdr, pose=cls("geometry_msgs/Pose")(
            position=cls("geometry_msgs/Point")(x=float(x), y=float(y), z=0.0),
            orientation=cls("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0)))
        for x, y in xy])


def synthetic_twist():
    v3 = messages.msg_class("geometry_msgs/Vector3")
    return messages.msg_class("geometry_msgs/Twist")(linear=v3(x=0.3, y=0.0, z=0.0),
                                                     angular=v3(x=0.0, y=0.0, z=-0.4))


SYNTHETIC = {"nav_msgs/msg/Path": (synthetic_path, "200 poses"),
             "geometry_msgs/msg/Twist": (synthetic_twist, "cmd_vel")}


def per_message_us(serializers: list, msgs: list, passes: int = 7) -> list[float]:
    """Best pass of each serializer, the passes interleaved so that both see the same load
    (the machine's cores are shared)."""
    best = [float("inf")] * len(serializers)
    for _ in range(passes):
        for i, serialize in enumerate(serializers):
            start = time.perf_counter()
            for m in msgs:
                serialize(m)
            best[i] = min(best[i], time.perf_counter() - start)
    return [b / len(msgs) * 1e6 for b in best]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--launch", default="launch/qbot_navigation.launch.yaml")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--bag", type=Path,
                    help="time the messages of this bag instead of running a launch")
    args = ap.parse_args()

    store = messages.typestore()
    with tempfile.TemporaryDirectory() as tmp:
        wall = None
        bag = args.bag
        if bag is None:
            bag = Path(tmp) / "bench.bag"
            wall = record(args.launch, args.duration, bag)
        by_type = read_messages(bag)
    source = {t: "bag" for t in by_type}
    for name, (make, what) in SYNTHETIC.items():
        if name not in by_type:
            by_type[name], source[name] = [make()], f"synthetic, {what}"

    def theirs(m):
        return bytes(store.serialize_ros1(m, m.__msgtype__))

    ours = Ros1Serializer(store)
    start = time.perf_counter()
    for t in by_type:
        ours.function(t)
    generation_ms = (time.perf_counter() - start) * 1e3

    print(f"{'type':38s} {'msgs':>6s} {'bytes':>7s} {'rosbags us':>11s} {'ours us':>8s} "
          f"{'ratio':>6s}")
    order = [t for t in HOT_TYPES if t in by_type] + sorted(set(by_type) - set(HOT_TYPES))
    for t in order:
        msgs = by_type[t][:SAMPLE]
        for m in msgs:  # warm-up pass, and the bytes must be the same
            if ours.serialize(m) != theirs(m):
                raise SystemExit(f"{t}: bytes differ from rosbags'")
        us_theirs, us_ours = per_message_us([theirs, ours.serialize], msgs)
        size = np.mean([len(theirs(m)) for m in msgs])
        note = "" if source[t] == "bag" else f"  ({source[t]})"
        print(f"{t:38s} {len(by_type[t]):6d} {size:7.0f} {us_theirs:11.1f} {us_ours:8.1f} "
              f"{us_theirs / us_ours:5.1f}x{note}")

    recorded = [m for t, ms in by_type.items() if source[t] == "bag" for m in ms]
    totals = {}
    for name, fn in (("rosbags", theirs), ("ours", ours.serialize)):
        start = time.perf_counter()
        for m in recorded:
            fn(m)
        totals[name] = time.perf_counter() - start
    run_note = f" (the run's wall time: {wall:.2f} s)" if wall is not None else ""
    ms_theirs, ms_ours = totals["rosbags"] * 1e3, totals["ours"] * 1e3
    print(f"\nall {len(recorded)} recorded messages once: rosbags {ms_theirs:.0f} ms, "
          f"ours {ms_ours:.0f} ms, {ms_theirs / ms_ours:.1f}x{run_note}")
    print(f"generating the {len(by_type)} types' functions (once per process): "
          f"{generation_ms:.1f} ms")


if __name__ == "__main__":
    main()
