"""A mapping run (gmapping's role): trajectory error and map quality.

The estimate is map -> odom composed with odom -> base_link; the map frame is put into the world
so that the first estimate is the true pose, since gmapping starts its map at the robot's first
pose. With a ground-truth map the last /map is compared cell by cell (analyses.map_quality).
The metrics: docs/analyze.md.
"""

from __future__ import annotations

import math

import numpy as np

from ...mapping.map_io import read_map
from ..bag_errors import BagError
from ..reader import Bag
from ..signals import align_start, compose, interp_poses, rms, wrap
from .common import AnalysisSkipped, Figure, Result, find_ground_truth, grid_of, odometry_poses, tf_series
from .map_quality import compare_grids

NAME = "mapping"


def detect(bag: Bag) -> dict | None:
    grids = bag.topics_of_type("nav_msgs/OccupancyGrid")
    if not grids or "/tf" not in bag.topics:
        return None
    return {
        "map": "/map" if "/map" in grids else grids[0],
        "tf": "/tf",
        "ground_truth": find_ground_truth(bag),
    }


def load_reference_map(path):
    """A map_server YAML + image pair (mapping.map_io.read_map); errors name the file."""
    try:
        return read_map(path)
    except FileNotFoundError as error:
        raise BagError(f"ground-truth map {path}: no such file ({error.filename})") from None
    except ValueError as error:
        raise BagError(f"ground-truth map {path}: {error}") from None


def analyze(bag: Bag, topics: dict, options: dict) -> Result:
    base = options.get("base_frame", "base_link")
    tf = tf_series(bag, topics["tf"])
    odom_frame = options.get("odom_frame", "odom")
    map_frame = options.get("map_frame", "map")
    if (map_frame, odom_frame) not in tf:
        raise AnalysisSkipped(
            f"/tf has no {map_frame} -> {odom_frame} transform (frames: "
            f"{', '.join(f'{p}->{c}' for p, c in tf)})"
        )
    if (odom_frame, base) not in tf:
        raise AnalysisSkipped(f"/tf has no {odom_frame} -> {base} transform")
    t_mo, p_mo = tf[(map_frame, odom_frame)]
    t_ob, p_ob = tf[(odom_frame, base)]
    keep = t_ob >= t_mo[0]
    t_est = t_ob[keep]
    p_est = compose(interp_poses(t_est, t_mo, p_mo), p_ob[keep])
    m: dict = {"map_updates": bag.topics[topics["map"]].count}
    figures = []
    T = np.zeros(3)
    if topics["ground_truth"] and len(t_est):
        tg, pg = odometry_poses(bag, topics["ground_truth"])
        T = align_start(t_est, p_est, tg, pg)
        inside = (t_est >= tg[0]) & (t_est <= tg[-1])
        pw = compose(T, p_est[inside])
        gi = interp_poses(t_est[inside], tg, pg)
        err = np.hypot(pw[:, 0] - gi[:, 0], pw[:, 1] - gi[:, 1])
        m["trajectory_rmse_m"] = float(rms(err))
        m["trajectory_max_error_m"] = float(err.max())
        m["trajectory_final_error_m"] = float(err[-1])
        m["yaw_rmse_deg"] = float(math.degrees(rms(wrap(pw[:, 2] - gi[:, 2]))))
        figures.append(
            Figure(
                "mapping_trajectory",
                "map -> base_link (aligned at the start) and ground truth",
                lambda fig: _draw_traj(fig, pg, pw),
            )
        )
    msgs = bag.messages(topics["map"])
    data, res, origin = grid_of(msgs[-1][1])
    m["map_width"], m["map_height"], m["map_resolution_m"] = data.shape[1], data.shape[0], res
    ref = options.get("ground_truth_map")
    if ref:
        gt = load_reference_map(ref)
        q = compare_grids(data, res, origin, gt.data, gt.resolution, gt.origin, T_ref_map=T)
        m.update({k if k.startswith("map_") else f"map_{k}": v for k, v in q.items()})
        figures.append(
            Figure(
                "mapping_map",
                "Last /map (grey) and ground-truth occupied cells (red)",
                lambda fig: _draw_map(fig, data, res, origin, T, gt),
            )
        )
    return Result(m, figures)


def _draw_traj(fig, pg, pw) -> None:
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(pg[:, 0], pg[:, 1], lw=1.4, label="ground truth")
    ax.plot(pw[:, 0], pw[:, 1], lw=1.2, ls="--", label="map -> base_link")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)


def _draw_map(fig, data, res, origin, T, gt) -> None:
    from .map_quality import cell_centres

    ax = fig.add_subplot(1, 1, 1)
    o = compose(T, np.asarray(origin, float))
    img = np.where(data < 0, 0.5, 1.0 - data / 100.0)
    ax.imshow(
        img,
        origin="lower",
        cmap="gray",
        vmin=0,
        vmax=1,
        extent=(o[0], o[0] + data.shape[1] * res, o[1], o[1] + data.shape[0] * res),
    )
    pts = cell_centres(np.asarray(gt.data) >= 65, gt.resolution, gt.origin)
    ax.plot(pts[:, 0], pts[:, 1], ",", color="red")
    ax.set_aspect("equal")
