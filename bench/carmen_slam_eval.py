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
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402

from twil_control import PACKAGE_ROOT  # noqa: E402
from twil_control.mapping import carmen, slam_metrics  # noqa: E402
from twil_control.mapping.gmapping import offline  # noqa: E402
from twil_control.mapping.gmapping.filter import ScanGeometry  # noqa: E402
from twil_control.mapping.gmapping.params import GMappingParams  # noqa: E402

DATA = Path("/work/shared/data/carmen")
NOISE = carmen.DEFAULT_NOISE


def evaluate_log(name: str, particles: int, delta: float, seed: int):
    log = carmen.read_log(DATA / f"{name}-corrected.log.gz")
    odom = carmen.synthesise_odometry(log.poses, NOISE, seed)
    values = yaml.safe_load((PACKAGE_ROOT / "config/gmapping.yaml").read_text())
    values.update(particles=particles, delta=delta, maxUrange=25.0, maxRange=log.range_max - 0.01,
                  linearUpdate=0.0, angularUpdate=0.0)
    start = time.perf_counter()
    run = offline.run(log.ranges, odom, log.times, ScanGeometry(log.beam_angles(), log.laser_offset, 0.0),
                      GMappingParams(**values), seed=seed + 1)
    seconds = time.perf_counter() - start
    ref = log.poses[run.scan_index]
    return (log, run, slam_metrics.evaluate(run.poses, ref), slam_metrics.evaluate(odom[run.scan_index], ref),
            seconds, odom)


def row(label: str, r: slam_metrics.SlamReport) -> str:
    c, lp = r.consecutive, r.loops
    return (f"| {label} | {c.trans_mean:.3f} ± {c.trans_std:.3f} | {c.rot_mean:.2f} ± {c.rot_std:.2f} | "
            f"{lp.trans_mean:.3f} ± {lp.trans_std:.3f} | {lp.rot_mean:.2f} ± {lp.rot_std:.2f} | {r.ate_rmse:.3f} |")


def save_map(path: Path, log, run, odom) -> None:
    grid = run.slam.occupancy()
    rows, cols = grid.data.shape
    extent = [grid.origin_x, grid.origin_x + cols * grid.resolution, grid.origin_y, grid.origin_y + rows * grid.resolution]
    image = np.where(grid.data < 0, 0.8, np.where(grid.data == 100, 0.0, 1.0))
    known = np.argwhere(grid.data >= 0)
    (r0, c0), (r1, c1) = known.min(0), known.max(0)
    fig, ax = plt.subplots(figsize=(8, 8))
    ax.imshow(image, origin="lower", cmap="gray", vmin=0, vmax=1, extent=extent, interpolation="nearest")
    # the reference drawn in the SLAM's map frame (best rigid alignment of the reference onto it)
    rot, t = slam_metrics.align_rigid(log.poses[run.scan_index, :2], run.poses[:, :2])
    ref = log.poses[run.scan_index, :2] @ rot.T + t
    ax.plot(ref[:, 0], ref[:, 1], "-", color="tab:green", lw=0.8, label="corrected (reference, aligned)")
    ax.plot(run.poses[:, 0], run.poses[:, 1], "--", color="tab:red", lw=0.8, label="SLAM (best particle)")
    ax.set_xlim(grid.origin_x + c0 * grid.resolution - 0.5, grid.origin_x + c1 * grid.resolution + 0.5)
    ax.set_ylim(grid.origin_y + r0 * grid.resolution - 0.5, grid.origin_y + r1 * grid.resolution + 0.5)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Intel lab, {len(run.scan_index)} scans, gmapping replica "
                 f"({run.slam.p.particles} particles, {grid.resolution} m cells)")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--particles", type=int, default=80)
    parser.add_argument("--delta", type=float, default=0.025)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--logs", nargs="+", default=["intel", "aces"])
    parser.add_argument("--image", default=str(PACKAGE_ROOT / "docs/img/intel_map.png"))
    args = parser.parse_args()
    lines = [f"odometry noise srr srt str stt = {' '.join(map(str, NOISE))} (seed {args.seed}); "
             f"{args.particles} particles, delta {args.delta} m", "",
             "| log, trajectory | consecutive trans (m) | consecutive rot (deg) | loop trans (m) | "
             "loop rot (deg) | ATE RMSE (m) |", "|---|---|---|---|---|---|"]
    for name in args.logs:
        log, run, slam, odo, seconds, odom = evaluate_log(name, args.particles, args.delta, args.seed)
        lines.append(row(f"{name} ({len(run.scan_index)} scans, {slam.loops.pairs} loop pairs), SLAM", slam))
        lines.append(row(f"{name}, odometry alone", odo))
        print(f"{name}: {seconds:.0f} s, median {1e3 * np.median(run.seconds):.0f} ms per scan, "
              f"{run.slam.resample_count} resamplings", flush=True)
        if name == "intel":
            save_map(Path(args.image), log, run, odom)
            print(f"map picture: {args.image}")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
