"""Command line: a CARMEN log (mapping.carmen) as a ROS 1 bag.

    python -m twil_control.tools.carmen_to_bag LOG(.gz) -o out.bag [--noise SRR SRT STR STT] [--seed N]

The odometry is synthesised from the corrected poses (seeded), the corrected poses are the ground
truth; the topics and frames: docs/slam.md, "Real laser logs".
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from ..bag.recorder import BagRecorder
from ..control.transforms import quat_from_yaw
from ..core.bus import Bus
from ..core.clock import SimClock
from ..core.messages import header, msg_class
from ..core.odometry_msg import odometry_msg
from ..core.tf import TF_TYPE, transform_stamped
from ..errors import exit_on_error
from ..mapping.carmen import (
    DEFAULT_NOISE,
    CarmenLog,
    monotonic_times,
    read_log,
    synthesise_odometry,
)


def write_bag(log: CarmenLog, out: str | Path, noise=DEFAULT_NOISE, seed: int = 0) -> int:
    """Write the bag (its topics: docs/slam.md); returns the number of scans written."""
    odom = synthesise_odometry(log.poses, noise, seed)
    clock = SimClock(0.0)
    bus = Bus(clock)
    pubs = {
        "scan": bus.advertise("/scan", "sensor_msgs/LaserScan", node="/carmen"),
        "odom": bus.advertise("/odom", "nav_msgs/Odometry", node="/carmen"),
        "truth": bus.advertise("/ground_truth/odom", "nav_msgs/Odometry", node="/carmen"),
        "tf": bus.advertise("/tf", TF_TYPE, node="/carmen"),
        "tf_static": bus.advertise("/tf_static", TF_TYPE, node="/carmen", latch=True),
    }
    recorder = BagRecorder(out, bus)
    try:
        angles = log.beam_angles()
        times = monotonic_times(log.times)
        t0 = float(times[0])
        clock.set(t0)
        tf_msg = msg_class(TF_TYPE)
        pubs["tf_static"].publish(
            tf_msg(
                transforms=[
                    transform_stamped(
                        "base_link", "base_laser", t0, (log.laser_offset, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0)
                    )
                ]
            )
        )
        zero_cov = np.zeros(36)
        scan_cls = msg_class("sensor_msgs/LaserScan")
        for k, t in enumerate(times):
            t = float(t)
            clock.set(t)
            o, g = odom[k], log.poses[k]
            q = quat_from_yaw(o[2])
            pubs["tf"].publish(
                tf_msg(transforms=[transform_stamped("odom", "base_link", t, (o[0], o[1], 0.0), q)])
            )
            pubs["odom"].publish(
                odometry_msg(
                    t, "odom", "base_link", (o[0], o[1], 0.0), q, (0, 0, 0), (0, 0, 0), zero_cov, zero_cov
                )
            )
            pubs["truth"].publish(
                odometry_msg(
                    t,
                    "map",
                    "base_link_ground_truth",
                    (g[0], g[1], 0.0),
                    quat_from_yaw(g[2]),
                    (0, 0, 0),
                    (0, 0, 0),
                    zero_cov,
                    zero_cov,
                )
            )
            dt = float(times[k + 1] - t) if k + 1 < len(times) else 0.0
            pubs["scan"].publish(
                scan_cls(
                    header=header("base_laser", t, seq=k),
                    angle_min=float(angles[0]),
                    angle_max=float(angles[-1]),
                    angle_increment=float(angles[1] - angles[0]),
                    time_increment=0.0,
                    scan_time=dt,
                    range_min=0.0,
                    range_max=log.range_max,
                    ranges=log.ranges[k].astype(np.float32),
                    intensities=np.zeros(0, np.float32),
                )
            )
            recorder.flush()
    finally:
        recorder.close()
    return len(log.times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m twil_control.tools.carmen_to_bag",
        description="Convert a CARMEN log into a ROS 1 bag with synthesised "
        "noisy odometry and ground-truth poses.",
    )
    parser.add_argument("log", help="CARMEN log (.log or .log.gz)")
    parser.add_argument("-o", "--output", required=True, help="bag to write (must not exist)")
    parser.add_argument(
        "--noise",
        nargs=4,
        type=float,
        metavar=("SRR", "SRT", "STR", "STT"),
        default=list(DEFAULT_NOISE),
        help=f"odometry noise of the motion model (default {' '.join(map(str, DEFAULT_NOISE))})",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the odometry noise (default 0)")
    args = parser.parse_args(argv)
    if any(not (math.isfinite(v) and v >= 0) for v in args.noise):
        parser.error(f"--noise values must be finite and >= 0 (got {args.noise})")
    return exit_on_error(lambda: _convert(args))


def _convert(args: argparse.Namespace) -> int:
    log = read_log(args.log)
    n = write_bag(log, args.output, tuple(args.noise), args.seed)
    print(
        f"{args.output}: {n} scans of {log.n_beams} beams, odometry noise "
        f"srr {args.noise[0]} srt {args.noise[1]} str {args.noise[2]} stt {args.noise[3]}, seed {args.seed}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
