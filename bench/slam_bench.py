"""SLAM cost per processed scan: the gmapping filter with the original launch's parameters
(config/gmapping.yaml: 80 particles, delta 0.025) on 640-beam scans at 30 Hz in a house-like
scene (segments ray-cast in numpy: walls, doors, furniture boxes), and on the Intel log's
180-beam scans.

    .venv/bin/python bench/slam_bench.py [--scans N] [--intel-scans N] [--laser-scans N] [--launch-seconds S] [--launch-rounds N]

Prints, per run, the median and p95 of the wall time and of the thread CPU time of each
processed scan (the first two are left out: they compile the numba code), with particles matched
serially and in numba threads (prange over particles), the position error of the best particle
against the truth, the memory held by the particles' maps, and the split of the wall time
between the filter's phases (scan matching, registration into the particles' maps, resampling,
the rest); then, in the same run, the laser's scans per second (bench/laser_bench.py's numba
caster, 640 beams, house world) and the real-time factor of launch/qbot_gmapping.launch.yaml
over its first S simulated seconds (wall and process CPU: the machine is shared, so CPU time is
the steadier figure).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import yaml
from _common import BenchResult

from twil_control import PACKAGE_ROOT
from twil_control.mapping import carmen, raycast
from twil_control.mapping.gmapping.filter import GMapping, ScanGeometry
from twil_control.mapping.gmapping.gmapping_params import GMappingParams
from twil_control.mapping.gmapping.motion import compose, noisy_motion, relative_motion

INTEL = PACKAGE_ROOT / "data/carmen/intel-corrected.log.gz"
ANGLES = np.linspace(-2.26889, 2.26889, 640)  # the qbot's Hokuyo
PHASES = ("match", "register", "resample", "other")  # GMapping.last_phase_seconds


def _box(cx, cy, w, h):
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def house_segments() -> np.ndarray:
    """12 x 9 m, three rooms joined by doors, four pieces of furniture."""
    s = _box(0, 0, 12, 9)
    s += [[-1, -4.5, -1, -1], [-1, 0.2, -1, 4.5], [-6, 1, -3, 1], [-2, 1, -1, 1]]
    s += [[2.5, -4.5, 2.5, -1.5], [2.5, 0, 2.5, 4.5]]
    s += (
        _box(-5.2, -2.5, 1.0, 0.6) + _box(5.3, 3.8, 0.8, 0.8) + _box(0, 3.6, 0.5, 1.2) + _box(4, -3, 1.5, 0.5)
    )
    return np.array(s, float)


def house_path(rate=30.0, speed=0.5, turn_rate=1.5) -> np.ndarray:
    way = [
        (-4, -3),
        (-4, -0.4),
        (1.0, -0.4),
        (1.0, 3.0),
        (1.0, -0.6),
        (4.2, -0.6),
        (4.2, 3.0),
        (4.2, -2.0),
        (4.2, -0.6),
        (1.0, -0.6),
        (-4, -0.6),
        (-4, -3),
    ]
    out, th = [], math.atan2(way[1][1] - way[0][1], way[1][0] - way[0][0])
    for a, b in zip(way[:-1], way[1:]):
        a, b = np.array(a, float), np.array(b, float)
        goal = math.atan2(b[1] - a[1], b[0] - a[0])
        turn = (goal - th + math.pi) % (2 * math.pi) - math.pi
        n_turn = int(abs(turn) / (turn_rate / rate))
        out += [[a[0], a[1], th + turn * (k + 1) / max(n_turn, 1)] for k in range(n_turn)]
        th = goal
        n = int(np.linalg.norm(b - a) / (speed / rate))
        out += [[*(a + s * (b - a)), th] for s in np.arange(n) / n]
    return np.array(out)


def cast(segs, pose, angles, max_range=10.0):
    """Ranges of beams from `pose` at robot-frame `angles` (inf beyond max_range)."""
    r = raycast.cast(*pose, angles[0], angles[1] - angles[0], len(angles), segs, np.empty((0, 3)))
    return np.where(r <= max_range, r, np.inf)


def original_params(**override) -> GMappingParams:
    values = yaml.safe_load((PACKAGE_ROOT / "config/gmapping.yaml").read_text())
    values.update(override)
    return GMappingParams(**values)


def measure(slam: GMapping, scans, odom, times, truth=None) -> dict:
    wall, cpu, proc, err, phases = [], [], [], [], []
    for k in range(len(scans)):
        w0, c0, p0 = time.perf_counter(), time.thread_time(), time.process_time()
        if slam.process(odom[k], scans[k], times[k]):
            wall.append(time.perf_counter() - w0)
            cpu.append(time.thread_time() - c0)
            proc.append(time.process_time() - p0)
            phases.append([slam.last_phase_seconds[key] for key in PHASES])
            if truth is not None:
                err.append(math.hypot(*(slam.best_pose()[:2] - truth[k][:2])))
    if len(wall) < 3:  # the first two compile numba's code and are left out
        raise SystemExit(
            f"slam_bench: only {len(wall)} of {len(scans)} scans were processed (linearUpdate / "
            f"angularUpdate gate them); statistics need at least 3: run more scans (--scans)"
        )
    wall, cpu, proc = np.array(wall[2:]) * 1e3, np.array(cpu[2:]) * 1e3, np.array(proc[2:]) * 1e3
    phases = np.array(phases[2:]) * 1e3
    return dict(
        n=len(wall),
        wall=(np.median(wall), np.percentile(wall, 95)),
        split={key: (np.median(phases[:, j]), phases[:, j].mean()) for j, key in enumerate(PHASES)},
        cpu=(np.median(cpu), np.percentile(cpu, 95)),
        proc=(np.median(proc), np.percentile(proc, 95)),
        err=max(err) if err else float("nan"),
        mem=slam.maps.memory_bytes() / 1e6,
        resamples=slam.resample_count,
    )


def report(label: str, r: dict) -> None:
    print(
        f"{label:<44} {r['n']:>4} scans  wall median {r['wall'][0]:7.1f} ms  p95 {r['wall'][1]:7.1f}  "
        f"thread cpu median {r['cpu'][0]:7.1f} ms  p95 {r['cpu'][1]:7.1f}  process cpu median {r['proc'][0]:7.1f}  max pos err {r['err']:.3f} m  "
        f"maps {r['mem']:.0f} MB  resamples {r['resamples']}"
    )
    split = r["split"]
    total = sum(mean for _, mean in split.values())
    print(
        f"{'':<44} wall per phase, median (mean, share of the mean total): "
        + ",  ".join(
            f"{key} {median:.1f} ms ({mean:.1f}, {100 * mean / total:.0f}%)"
            for key, (median, mean) in split.items()
        )
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scans", type=int, default=0, help="house scans to run (default: the whole path)")
    parser.add_argument("--intel-scans", type=int, default=300)
    parser.add_argument("--laser-scans", type=int, default=3000)
    parser.add_argument("--launch-seconds", type=float, default=20.0)
    parser.add_argument("--launch-rounds", type=int, default=3, help="mapping launch runs (median)")
    args = parser.parse_args()
    result = BenchResult(
        "slam_bench",
        "the gmapping filter's cost per processed scan (80 particles, delta 0.025, "
        "serial and with the particles in numba threads) on a house-like scene and on the Intel "
        "log, the laser's scans per second, and the mapping launch's real-time factor",
    )

    segs, truth = house_segments(), house_path()
    if args.scans:
        truth = truth[: args.scans]
    rng = np.random.default_rng(1)
    odom = [truth[0]]
    for k in range(1, len(truth)):  # wheel odometry with gmapping's default noise per 30 Hz step
        odom.append(
            compose(odom[-1], noisy_motion(relative_motion(truth[k], truth[k - 1]), 0.1, 0.2, 0.1, 0.2, rng))
        )
    scans = [cast(segs, p, ANGLES) + rng.normal(0, 0.01, len(ANGLES)) for p in truth]
    times = np.arange(len(truth)) / 30.0
    params = original_params()
    print(
        f"house-like scene: {len(truth)} scans of 640 beams at 30 Hz, {params.particles} particles, "
        f"delta {params.delta}, linearUpdate {params.linearUpdate}, angularUpdate {params.angularUpdate}"
    )
    for parallel in (False, True):
        slam = GMapping(params, ScanGeometry(ANGLES), np.random.default_rng(0), parallel=parallel)
        r = measure(slam, scans, odom, times, truth)
        report(f"house, {'numba threads' if parallel else 'serial'}", r)
        record(result, f"house {'threads' if parallel else 'serial'}", r)

    if args.laser_scans > 0:
        import laser_bench

        numba_rate = laser_bench.cast_rates(args.laser_scans)[0]
        print(
            f"laser (640 beams, house world, numba caster): {numba_rate[0]:.0f} scans/s wall, "
            f"{numba_rate[1]:.0f} scans/s thread CPU (target >= 2000)"
        )
        result.add("laser_scans_per_s", numba_rate[1], "scans/s (thread CPU)")
    if args.launch_seconds > 0:
        from nav_bench import timed_launch

        runs = [
            timed_launch("launch/qbot_gmapping.launch.yaml", {}, args.launch_seconds)
            for _ in range(args.launch_rounds)
        ]  # medians: the shared machine's speed drifts
        sim, wall, build, cpu, _, steal = np.median(np.array(runs), axis=0)
        rtfs = [r[0] / r[1] for r in runs]
        print(
            f"mapping launch (qbot_gmapping, house, bag; median of {len(runs)}): {sim:.0f} s simulated in "
            f"{wall:.1f} s wall ({sim / wall:.2f}x real time, runs {min(rtfs):.2f}-{max(rtfs):.2f}x; build "
            f"{build:.1f} s more), {cpu:.1f} s process CPU ({sim / cpu:.2f}x), host steal {100 * steal:.0f}% of both "
            f"cores (target >= 2x)"
        )
        result.add(
            "mapping_launch_rtf",
            sim / wall,
            f"x real time (median of {len(runs)})",
            target=">= 2",
            headline="qbot_gmapping launch, real-time factor",
        )
    if args.intel_scans <= 0:
        result.write()
        return
    log = carmen.read_log(INTEL)
    n = min(args.intel_scans, len(log.times))
    odom = carmen.synthesise_odometry(log.poses, carmen.DEFAULT_NOISE, 0)
    geometry = ScanGeometry(log.beam_angles(), log.laser_offset, 0.0)
    # 30 and 80 particles serially: the cases the original C++ gmapping was run on (docs/performance.md)
    for particles, parallel in ((30, False), (80, False), (80, True)):
        params = original_params(
            maxUrange=25.0, maxRange=81.0, linearUpdate=0.0, angularUpdate=0.0, particles=particles
        )
        slam = GMapping(params, geometry, np.random.default_rng(0), parallel=parallel)
        r = measure(slam, log.ranges[:n], odom[:n], log.times[:n], log.poses[:n])
        how = "numba threads" if parallel else "serial"
        report(f"Intel first {n} scans (180 beams), {particles} particles, {how}", r)
        record(result, f"intel {particles} particles {'threads' if parallel else 'serial'}", r)
    result.write()


def record(result: BenchResult, label: str, r: dict) -> None:
    """A row of the table: per processed scan, wall time and the process's CPU time (the
    serial Intel rows are the ones the original C++ gmapping was measured on)."""
    result.add("wall median", r["wall"][0], "ms", row=label)
    result.add("wall p95", r["wall"][1], "ms", row=label)
    result.add(
        "CPU median",
        r["proc"][0],
        "ms",
        row=label,
        headline=label.endswith("serial") and label.startswith("intel") and f"SLAM, {label}: CPU per scan",
    )


if __name__ == "__main__":
    main()
