"""The SLAM on the two real CARMEN logs (Intel, ACES), against noisy odometry alone: the
README's accuracy table, and the Intel map picture (docs/img/intel_map.png).

    .venv/bin/python bench/carmen_slam_eval.py [--particles 80] [--delta 0.025] [--seed 0]

Per log: odometry synthesised from the corrected poses with motion-model noise (srr srt str stt
= 0.05 each, seeded), the filter fed every scan in-process (gmapping.offline.run) with the
original launch's parameters except the sensor ranges (maxUrange 25 m, maxRange just below the
log's no-return value) and linearUpdate = angularUpdate = 0 (the corrected logs are already
thinned to one scan every ~0.5 m / 0.3 rad, so every scan is processed). The SLAM trajectory is
the best particle's path at the end. Relation errors (Kummerle et al. 2009) over consecutive
scans and over loop-closing pairs (>= 50 scans apart, within 1 m by the corrected poses), and
the absolute trajectory RMSE after a rigid alignment.

Consistency (no doubled walls): the same processed scans are also traced from the corrected
poses (aligned onto the SLAM's frame) into the SLAM map's grid; the SLAM map's occupied cells
are scored against that reference map within 0.1 m (a doubled wall is an occupied cell far
from any reference wall: precision drops), and the picture shows both maps side by side. The
Intel lab's inner corridor walls are curved in the reference map too: the bow is the log's.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import yaml
from _common import BenchResult
from _result import figure_path

from twil_control import PACKAGE_ROOT
from twil_control.mapping import carmen, slam_metrics
from twil_control.mapping.gmapping import offline
from twil_control.mapping.gmapping.filter import ScanGeometry
from twil_control.mapping.gmapping.gmapping_params import GMappingParams
from twil_control.mapping.gmapping.occupancy import occupancy_from_counts, trace_scan

DATA = PACKAGE_ROOT / "data/carmen"
NOISE = carmen.DEFAULT_NOISE


def evaluate_log(name: str, particles: int, delta: float, seed: int):
    log = carmen.read_log(DATA / f"{name}-corrected.log.gz")
    odom = carmen.synthesise_odometry(log.poses, NOISE, seed)
    values = yaml.safe_load((PACKAGE_ROOT / "config/gmapping.yaml").read_text())
    values.update(
        particles=particles,
        delta=delta,
        maxUrange=25.0,
        maxRange=log.range_max - 0.01,
        linearUpdate=0.0,
        angularUpdate=0.0,
    )
    start = time.perf_counter()
    run = offline.run(
        log.ranges,
        odom,
        log.times,
        ScanGeometry(log.beam_angles(), log.laser_offset, 0.0),
        GMappingParams(**values),
        seed=seed + 1,
    )
    seconds = time.perf_counter() - start
    ref = log.poses[run.scan_index]
    return (
        log,
        run,
        slam_metrics.evaluate(run.poses, ref),
        slam_metrics.evaluate(odom[run.scan_index], ref),
        seconds,
        odom,
    )


def row(label: str, r: slam_metrics.SlamReport) -> str:
    c, lp = r.consecutive, r.loops
    return (
        f"| {label} | {c.trans_mean:.3f} ± {c.trans_std:.3f} | {c.rot_mean:.2f} ± {c.rot_std:.2f} | "
        f"{lp.trans_mean:.3f} ± {lp.trans_std:.3f} | {lp.rot_mean:.2f} ± {lp.rot_std:.2f} | {r.ate_rmse:.3f} |"
    )


def reference_map(log, run) -> np.ndarray:
    """The map the same processed scans make from the corrected poses (rigidly aligned onto the
    SLAM's frame), on the SLAM map's grid: what a consistent SLAM map should look like."""
    slam = run.slam
    rot, t = slam_metrics.align_rigid(log.poses[run.scan_index, :2], run.poses[:, :2])
    turn = np.arctan2(rot[1, 0], rot[0, 0])
    ref = log.poses[run.scan_index]
    xy = ref[:, :2] @ rot.T + t
    rows, cols = slam.maps.shape_cells
    hits, visits = np.zeros((rows, cols), np.int32), np.zeros((rows, cols), np.int32)
    g, m = slam.geometry, slam.maps
    for k, (x, y), th in zip(slam.trajectory()[0], xy, ref[:, 2] + turn):
        ex, ey, is_hit = slam.scans[k]
        trace_scan(hits, visits, m.ox, m.oy, m.delta, x, y, th, g.sensor_x, g.sensor_y, ex, ey, is_hit)
    return occupancy_from_counts(hits, visits, slam.p.occ_thresh)


AGREEMENT_TOLERANCE = 0.10  # m: beyond the few-cm local offsets an ATE of 0.1-0.2 m brings,
# within the 0.3-1 m a doubled wall or corridor is apart


def map_agreement(log, run) -> tuple[slam_metrics.MapScore, np.ndarray, object]:
    """Occupied-cell precision/recall of the SLAM map against the reference-pose map within
    AGREEMENT_TOLERANCE: a wall the SLAM doubled is an occupied cell with no reference wall near
    it (precision drops), a wall it lost one with no SLAM wall near it (recall drops)."""
    grid = run.slam.occupancy()
    ref = reference_map(log, run)
    origin = (grid.origin_x, grid.origin_y)
    cells = max(1, round(AGREEMENT_TOLERANCE / grid.resolution))
    return slam_metrics.map_score(grid.data, origin, ref, origin, grid.resolution, tolerance=cells), ref, grid


def save_map(path: Path, log, run, ref_grid: np.ndarray, grid, score: slam_metrics.MapScore) -> None:
    rows, cols = grid.data.shape
    extent = [
        grid.origin_x,
        grid.origin_x + cols * grid.resolution,
        grid.origin_y,
        grid.origin_y + rows * grid.resolution,
    ]
    known = np.argwhere(grid.data >= 0)
    (r0, c0), (r1, c1) = known.min(0), known.max(0)
    rot, t = slam_metrics.align_rigid(log.poses[run.scan_index, :2], run.poses[:, :2])
    ref = log.poses[run.scan_index, :2] @ rot.T + t
    fig, axes = plt.subplots(1, 2, figsize=(15, 7.8))
    for ax, data, title in (
        (axes[0], ref_grid, "from the corrected poses (reference)"),
        (
            axes[1],
            grid.data,
            f"gmapping replica: {run.slam.p.particles} particles, {grid.resolution} m cells",
        ),
    ):
        image = np.where(data < 0, 0.8, np.where(data == 100, 0.0, 1.0))
        ax.imshow(image, origin="lower", cmap="gray", vmin=0, vmax=1, extent=extent, interpolation="nearest")
        ax.set_xlim(grid.origin_x + c0 * grid.resolution - 0.5, grid.origin_x + c1 * grid.resolution + 0.5)
        ax.set_ylim(grid.origin_y + r0 * grid.resolution - 0.5, grid.origin_y + r1 * grid.resolution + 0.5)
        ax.set_xlabel("x (m)")
        ax.set_title(f"Intel lab, {len(run.scan_index)} scans, {title}", fontsize=10)
    axes[0].set_ylabel("y (m)")
    axes[0].plot(ref[:, 0], ref[:, 1], "-", color="tab:green", lw=0.6, label="corrected poses (aligned)")
    axes[1].plot(run.poses[:, 0], run.poses[:, 1], "-", color="tab:red", lw=0.6, label="SLAM (best particle)")
    axes[1].text(
        0.02,
        0.02,
        f"occupied cells against the reference map (within {AGREEMENT_TOLERANCE} m): precision "
        f"{score.precision:.3f}, recall {score.recall:.3f}",
        transform=axes[1].transAxes,
        fontsize=9,
        bbox=dict(facecolor="white", alpha=0.8),
    )
    for ax in axes:
        ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--particles", type=int, default=80)
    parser.add_argument("--delta", type=float, default=0.025)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--logs", nargs="+", default=["intel", "aces"])
    parser.add_argument(
        "--image",
        help="the Intel map picture (default: docs/img/intel_map.png, beside $BENCH_RESULTS when set)",
    )
    args = parser.parse_args()
    result = BenchResult(
        "carmen_slam_eval",
        "the SLAM on the real Intel and ACES logs (noisy synthesised odometry): "
        "relation errors (Kummerle et al. 2009) and ATE against the corrected poses, and the cost "
        "per processed scan",
    )
    lines = [
        f"odometry noise srr srt str stt = {' '.join(map(str, NOISE))} (seed {args.seed}); "
        f"{args.particles} particles, delta {args.delta} m",
        "",
        "| log, trajectory | consecutive trans (m) | consecutive rot (deg) | loop trans (m) | "
        "loop rot (deg) | ATE RMSE (m) |",
        "|---|---|---|---|---|---|",
    ]
    for name in args.logs:
        log, run, slam, odo, seconds, odom = evaluate_log(name, args.particles, args.delta, args.seed)
        lines.append(row(f"{name} ({len(run.scan_index)} scans, {slam.loops.pairs} loop pairs), SLAM", slam))
        lines.append(row(f"{name}, odometry alone", odo))
        print(
            f"{name}: {seconds:.0f} s, median {1e3 * np.median(run.seconds):.0f} ms per scan, "
            f"{run.slam.resample_count} resamplings",
            flush=True,
        )
        result.add(
            "consecutive trans",
            slam.consecutive.trans_mean,
            "m (mean)",
            row=name,
            headline=f"SLAM on the {name} log: consecutive relations, translation",
        )
        result.add("consecutive rot", slam.consecutive.rot_mean, "deg (mean)", row=name)
        result.add("loop trans", slam.loops.trans_mean, "m (mean)", row=name)
        result.add("loop rot", slam.loops.rot_mean, "deg (mean)", row=name)
        result.add("ATE RMSE", slam.ate_rmse, "m", row=name)
        result.add("odometry ATE RMSE", odo.ate_rmse, "m", row=name)
        result.add("per scan", 1e3 * np.median(run.seconds), "ms wall (median)", row=name)
        score, ref_grid, grid = map_agreement(log, run)
        print(
            f"{name}: SLAM map against the map of the corrected poses (occupied cells, within "
            f"{AGREEMENT_TOLERANCE} m): "
            f"precision {score.precision:.3f}, recall {score.recall:.3f}",
            flush=True,
        )
        if name == "intel":
            picture = Path(args.image) if args.image else figure_path("intel_map.png")
            save_map(picture, log, run, ref_grid, grid, score)
            print(f"map picture: {picture}")
    print("\n".join(lines))
    result.add("particles", args.particles)
    result.write()


if __name__ == "__main__":
    main()
