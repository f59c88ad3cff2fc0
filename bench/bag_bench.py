"""How long `info` and `analyze` take on a bag of a million messages.

Writes (once, with rosbags' Writer, LZ4 like the recorder) a 1000 s run of the cart
controller: its status at 1 kHz (1,000,000 twil_control/CartLinearizingStatus), ground truth
and /joint_states at 100 Hz and two commands; then times, in this process, ``bag_info``
(index only) and ``analyze_bag`` (the cart analysis reads the status, ground truth, joint
states and commands) and, as a user runs them, the two commands in a fresh process (Python
start-up and imports included). The messages are serialised once and their numeric fields
written into the stacked bytes with numpy (bag.layout), so writing costs the Writer's time only.

    .venv/bin/python bench/bag_bench.py [--seconds 1000] [--keep PATH]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import BenchResult
from rosbags.rosbag1 import Writer

from twil_control.bag.analyze import analyze_bag
from twil_control.bag.info import bag_info
from twil_control.bag.layout import layout
from twil_control.core import messages

STATUS = "/twil/ros_control/cart_linearizing_controller/status"
COMMAND = "/twil/ros_control/cart_linearizing_controller/command"


def _rows(template, n: int, values: dict[str, np.ndarray]) -> np.ndarray:
    """n copies of the template message's bytes with the named numeric fields set."""
    data = messages.serialize(template)
    lay = layout(messages.typestore(), template.__msgtype__, data)
    rows = np.tile(np.frombuffer(data, np.uint8), (n, 1))
    for name, v in values.items():
        off, dtype = lay.leaves[name]
        size = np.dtype(dtype).itemsize
        rows[:, off : off + size] = (
            np.ascontiguousarray(np.asarray(v, dtype=dtype)).view(np.uint8).reshape(n, size)
        )
    return rows


def write_bench_bag(path: Path, seconds: float) -> int:
    cls = messages.msg_class
    n_s = int(round(seconds * 1000))
    t_s = np.arange(n_s) * 1e-3
    decay = np.exp(-t_s / 3.0)
    status = _rows(
        cls("twil_control/CartLinearizingStatus")(
            header=messages.header("", 0.0),
            e=0.0,
            psi=0.0,
            alpha=0.0,
            e1=0.0,
            e2=0.0,
            V1=0.0,
            V1_dot_predicted=0.0,
            u1=0.0,
            u2=0.0,
            tau_right=0.0,
            tau_left=0.0,
            torque_scale=1.0,
            arm_torques=np.zeros(7),
            x=0.0,
            y=0.0,
            theta=0.0,
        ),
        n_s,
        {
            "V1": 13.0 * decay,
            "tau_right": 6.0 * decay * np.cos(t_s),
            "tau_left": 6.0 * decay * np.sin(t_s),
            "e": 2.2 * decay,
            "x": 2.0 * (1 - decay),
            "y": 1.0 - decay,
            "theta": 1.57 * (1 - decay),
            "header.stamp.sec": np.floor(t_s),
            "header.stamp.nanosec": np.round((t_s % 1) * 1e9),
        },
    )
    n_g = n_s // 10
    t_g = np.arange(n_g) * 1e-2
    dg = np.exp(-t_g / 3.0)
    yaw = 1.5707963267948966 * (1 - dg)
    odom = cls("nav_msgs/Odometry")(
        header=messages.header("world", 0.0),
        child_frame_id="base_link_ground_truth",
        pose=cls("geometry_msgs/PoseWithCovariance")(
            pose=cls("geometry_msgs/Pose")(
                position=cls("geometry_msgs/Point")(x=0.0, y=0.0, z=0.0),
                orientation=cls("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
            covariance=np.zeros(36),
        ),
        twist=cls("geometry_msgs/TwistWithCovariance")(
            twist=cls("geometry_msgs/Twist")(
                linear=cls("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.0),
                angular=cls("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.0),
            ),
            covariance=np.zeros(36),
        ),
    )
    gt = _rows(
        odom,
        n_g,
        {
            "pose.pose.position.x": 2.0 * (1 - dg),
            "pose.pose.position.y": 1.0 - dg,
            "pose.pose.orientation.z": np.sin(yaw / 2),
            "pose.pose.orientation.w": np.cos(yaw / 2),
        },
    )
    names = ["left_wheel_joint", "right_wheel_joint"] + [f"wam_joint_{i}" for i in range(1, 8)]
    js = cls("sensor_msgs/JointState")(
        header=messages.header("", 0.0),
        name=names,
        position=np.zeros(9),
        velocity=np.zeros(9),
        effort=np.zeros(9),
    )
    home = np.array([0.0, -1.95, 0.0, 3.05, 0.0, 0.0, 0.0])
    q = home[None, :] * (1 - (1 + 5 * t_g[:, None]) * np.exp(-5 * t_g[:, None]))
    joints = _rows(js, n_g, {f"position[{i + 2}]": q[:, i] for i in range(7)})
    cmd = cls("twil_control/CartLinearizingCommand")(
        header=messages.header("", 0.0),
        platform_pose=cls("geometry_msgs/Pose2D")(x=2.0, y=1.0, theta=1.5707963267948966),
        arm_positions=home,
        arm_velocities=np.zeros(0),
        arm_accelerations=np.zeros(0),
    )
    writer = Writer(path)
    writer.set_compression(Writer.CompressionFormat.LZ4)
    writer.open()
    conns = {}
    for topic, typ in (
        (STATUS, "twil_control/CartLinearizingStatus"),
        ("/twil/ground_truth/odom", "nav_msgs/Odometry"),
        ("/joint_states", "sensor_msgs/JointState"),
        (COMMAND, "twil_control/CartLinearizingCommand"),
    ):
        msgdef, md5 = messages.definition(typ)
        conns[topic] = writer.add_connection(topic, messages.full_type_name(typ), msgdef=msgdef, md5sum=md5)
    writer.write(conns[COMMAND], 0, messages.serialize(cmd))
    count = 1
    for i in range(n_s):
        ns = i * 1_000_000
        writer.write(conns[STATUS], ns, status[i].tobytes())
        if i % 10 == 0:
            writer.write(conns["/twil/ground_truth/odom"], ns, gt[i // 10].tobytes())
            writer.write(conns["/joint_states"], ns, joints[i // 10].tobytes())
            count += 2
    writer.close()
    return count + n_s


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, default=1000.0, help="bag duration (1 kHz status: 1000 messages/s)"
    )
    parser.add_argument(
        "--keep", type=Path, help="write the bag here and keep it (default: a temporary folder)"
    )
    args = parser.parse_args()
    result = BenchResult(
        "bag_bench",
        "bag info and bag analyze on a bag of a million messages (1,000 s of a 1 kHz "
        "controller status plus 100 Hz topics), in process and as fresh commands",
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = args.keep or Path(tmp) / "bench.bag"
        if not path.exists():
            (count, t_write) = _timed(lambda: write_bench_bag(path, args.seconds))
            print(
                f"wrote {path}: {count:,} messages, {path.stat().st_size / 2**20:.1f} MiB in {t_write:.1f} s"
            )
        info, t_info = _timed(lambda: bag_info(path))
        metrics, t_an = _timed(lambda: analyze_bag(path))
        cart = metrics["cart_controller"]
        print(f"bag: {info['messages']:,} messages, {info['duration']:.0f} s, {info['chunks']} chunks")
        print(f"  info (in process, index only):         {t_info:6.2f} s")
        print(
            f"  analyze (in process, cart controller): {t_an:6.2f} s   "
            f"(V1 max rise {cart['V1_max_rise']:.3g}, peak tau_right {cart['peak_tau_right_Nm']:.3g} N m, "
            f"final error {cart['final_position_error_m']:.2e} m)"
        )
        for cmd in ("info", "analyze"):
            t0 = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "twil_control.bag", cmd, str(path)],
                check=True,
                stdout=subprocess.DEVNULL,
            )
            elapsed = time.perf_counter() - t0
            print(f"  python -m twil_control.bag {cmd:8s}        {elapsed:6.2f} s (fresh process)")
            result.add(f"{cmd}_command_s", elapsed, "s (fresh process, imports included)")
        print(f"  analyze throughput: {info['messages'] / t_an / 1e6:.2f} M messages/s (in process)")
    result.add("messages", info["messages"])
    result.add("info_s", t_info, "s (in process)", headline="bag info, 1.2 M messages")
    result.add("analyze_s", t_an, "s (in process)", headline="bag analyze, 1.2 M messages")
    result.write()


if __name__ == "__main__":
    main()
