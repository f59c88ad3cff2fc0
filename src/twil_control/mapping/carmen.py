"""CARMEN laser logs (the Radish "corrected" SLAM benchmarks): the reader, and the synthesised
odometry the bag converter and the SLAM tests use.

The corrected poses are the ground truth; the odometry is their relative motion corrupted with
gmapping's motion noise (seeded). Readings at the log's "no return" value are kept, with
range_max set to it, so a consumer drops them as ROS does (docs/slam.md).
"""

from __future__ import annotations

import gzip
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from twil_control.errors import TwilControlError

from .gmapping.motion import compose, noisy_motion, relative_motion

DEFAULT_NOISE = (0.05, 0.05, 0.05, 0.05)  # srr srt str stt of the synthesised odometry


class CarmenFormatError(TwilControlError, ValueError):
    """A log line that does not follow the CARMEN format (names the file and line)."""


@dataclass
class CarmenLog:
    """The FLASER records of a log: times (s), ranges (n, beams), corrected poses (n, 3)."""

    path: str
    times: np.ndarray
    ranges: np.ndarray
    poses: np.ndarray
    params: dict[str, str] = field(default_factory=dict)
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))  # line of each scan

    @property
    def n_beams(self) -> int:
        return self.ranges.shape[1]

    @property
    def range_max(self) -> float:
        return float(self.ranges.max())

    def beam_angles(self) -> np.ndarray:
        """Beam i at -90 deg + i * 180 deg / n (1 deg apart for 180 beams, the last at +89 deg).

        The logs' README also says "last at +90 deg", which cannot hold with 1 deg spacing; this
        spacing gives sharper maps from the corrected poses (fewer occupied cells on both logs)
        than -90..+90 deg spread over n - 1 gaps."""
        return -math.pi / 2 + np.arange(self.n_beams) * (math.pi / self.n_beams)

    @property
    def laser_offset(self) -> float:
        """The front laser's offset along the robot's x axis (PARAM robot_frontlaser_offset)."""
        return float(self.params.get("robot_frontlaser_offset", 0.0))


def _open(path: Path):
    with open(path, "rb") as fh:
        gz = fh.read(2) == b"\x1f\x8b"
    return gzip.open(path, "rt") if gz else open(path)


def read_log(path: str | Path) -> CarmenLog:
    """Parse FLASER and PARAM lines (ODOM, NEFF, comments and other records are skipped)."""
    path = Path(path)
    if not path.is_file():
        raise CarmenFormatError(f"{path}: no such file")
    times, ranges, poses, lines, params = [], [], [], [], {}
    n_beams = None
    try:
        with _open(path) as fh:
            for number, line in enumerate(fh, start=1):
                words = line.split()
                if not words or words[0].startswith("#"):
                    continue
                where = f"{path}:{number}"
                if words[0] == "PARAM":
                    if len(words) < 3:
                        raise CarmenFormatError(
                            f"{where}: PARAM needs 'PARAM name value ...' (got {len(words) - 1} fields)"
                        )
                    params[words[1]] = words[2]
                elif words[0] == "FLASER":
                    t, r, pose = _flaser(words, where)
                    if n_beams is None:
                        n_beams = len(r)
                    elif len(r) != n_beams:
                        raise CarmenFormatError(
                            f"{where}: FLASER has {len(r)} ranges; earlier scans "
                            f"had {n_beams} (one laser per log)"
                        )
                    times.append(t)
                    ranges.append(r)
                    poses.append(pose)
                    lines.append(number)
    except (OSError, EOFError, UnicodeDecodeError) as error:
        raise CarmenFormatError(f"{path}: cannot read the log ({error})") from None
    if not times:
        raise CarmenFormatError(f"{path}: no FLASER records (is this a CARMEN log?)")
    return CarmenLog(
        str(path), np.array(times), np.array(ranges), np.array(poses), params, np.array(lines, np.int64)
    )


def _flaser(words: list[str], where: str):
    """FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp"""
    try:
        n = int(words[1])
    except (IndexError, ValueError):
        raise CarmenFormatError(
            f"{where}: FLASER must be followed by the number of ranges "
            f"(got {words[1] if len(words) > 1 else 'nothing'!r})"
        ) from None
    if n < 1:
        raise CarmenFormatError(f"{where}: FLASER needs at least one range (got n = {n})")
    expected = 2 + n + 9
    if len(words) < expected:
        raise CarmenFormatError(
            f"{where}: FLASER with {n} ranges needs {expected} fields "
            f"(n ranges, x y theta, odom x y theta, ipc_timestamp hostname "
            f"logger_timestamp); got {len(words)}"
        )
    try:
        values = np.array(words[2 : 2 + n + 6], float)
        t = float(words[2 + n + 6])
    except ValueError as error:
        raise CarmenFormatError(f"{where}: FLASER fields must be numbers ({error})") from None
    if not (np.isfinite(values).all() and math.isfinite(t)):
        raise CarmenFormatError(f"{where}: FLASER holds a non-finite number")
    if (values[:n] < 0).any():
        raise CarmenFormatError(f"{where}: FLASER has a negative range")
    return t, values[:n], values[n : n + 3]


def monotonic_times(times: np.ndarray, min_step: float = 1e-3) -> np.ndarray:
    """The scans' times, each nudged to at least min_step after the previous one. The file order
    is the scan order; a few stamps in the real logs go back by up to 0.9 s (4 in Intel), which
    a bag and a tf buffer cannot take."""
    out = np.array(times, float)
    for k in range(1, len(out)):
        out[k] = max(out[k], out[k - 1] + min_step)
    return out


def synthesise_odometry(poses: np.ndarray, noise=DEFAULT_NOISE, seed: int = 0) -> np.ndarray:
    """Odometry poses: the corrected relative motions with motion-model noise, chained from the
    first corrected pose (so odom and map coincide at the start)."""
    srr, srt, str_, stt = noise
    rng = np.random.default_rng(seed)
    odom = np.empty_like(poses)
    odom[0] = poses[0]
    for k in range(1, len(poses)):
        delta = relative_motion(poses[k], poses[k - 1])
        odom[k] = compose(odom[k - 1], noisy_motion(delta, srr, srt, str_, stt, rng))
    return odom
