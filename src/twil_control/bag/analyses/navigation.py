"""A navigation run (move_base's role), from its ROS interfaces.

Per actionlib goal id: target, outcome, time to its first terminal status, path driven, final
distance, least clearance from the map and collision samples (docs/analyze.md). A simple goal is
matched to the first goal id that appears after it; map and ground truth are taken to share the
world frame (a simulated run on a given map).
"""

from __future__ import annotations

import numpy as np

from ...core.actionlib import TERMINAL, status_name
from ..reader import Bag
from ..signals import interp_poses, path_length
from .common import Figure, Result, find_ground_truth, grid_of, odometry_poses
from .map_quality import distance_field, sample

NAME = "navigation"


def detect(bag: Bag) -> dict | None:
    status = bag.topics_of_type("actionlib_msgs/GoalStatusArray")
    if not status:
        return None
    st = "/move_base/status" if "/move_base/status" in status else status[0]
    ns = st.rsplit("/", 1)[0]
    simple = [
        t for t in bag.topics_of_type("geometry_msgs/PoseStamped") if t.endswith("move_base_simple/goal")
    ]
    return {
        "status": st,
        "action_goal": ns + "/goal" if ns + "/goal" in bag.topics else None,
        "simple_goal": simple[0] if simple else None,
        "ground_truth": find_ground_truth(bag),
        "map": "/map" if "/map" in bag.topics else None,
        "collisions": [t for t in bag.topics_of_type("std_msgs/String") if t.endswith("/collisions")],
    }


def _pose2(p) -> tuple[float, float]:
    return float(p.position.x), float(p.position.y)


def _goals_from_status(bag: Bag, status_topic: str) -> tuple[dict[str, dict], list[str]]:
    """Every goal id in the status, in order of appearance, with its first terminal status."""
    goals: dict[str, dict] = {}
    order: list[str] = []
    for t_ns, msg in bag.messages(status_topic):
        t = t_ns * 1e-9
        for s in msg.status_list:
            gid = s.goal_id.id
            g = goals.get(gid)
            if g is None:
                stamp = s.goal_id.stamp.sec + 1e-9 * s.goal_id.stamp.nanosec
                g = goals[gid] = {"first_seen": t, "stamp": stamp, "status": s.status, "end": None}
                order.append(gid)
            if g["end"] is None:  # the first terminal status is the goal's outcome
                g["status"] = s.status
                if s.status in TERMINAL:
                    g["end"] = t
    return goals, order


def _attach_action_goals(bag: Bag, topic: str, goals: dict[str, dict]) -> None:
    for t_ns, msg in bag.messages(topic):
        gid = getattr(getattr(msg, "goal_id", None), "id", None)
        if gid in goals:
            goals[gid]["target"] = _pose2(msg.goal.target_pose.pose)
            goals[gid]["published"] = t_ns * 1e-9


def _attach_simple_goals(bag: Bag, topic: str, goals: dict[str, dict], order: list[str]) -> None:
    simple = [(t * 1e-9, _pose2(m.pose)) for t, m in bag.messages(topic)]
    unmatched = [g for g in order if "target" not in goals[g]]
    for ts, target in simple:  # each simple goal -> the first new goal id after it
        for gid in unmatched:
            if goals[gid]["first_seen"] >= ts - 1e-9:
                goals[gid]["target"], goals[gid]["published"] = target, ts
                unmatched.remove(gid)
                break


def _clearance_field(bag: Bag, topics: dict, options: dict):
    """(distance field, resolution, origin) of the reference map, else of the bag's last /map."""
    if options.get("ground_truth_map"):
        from .mapping import load_reference_map

        gt = load_reference_map(options["ground_truth_map"])
        return distance_field(gt.data, gt.resolution), gt.resolution, gt.origin
    if topics.get("map"):
        data, res, origin = grid_of(bag.messages(topics["map"])[-1][1])
        return distance_field(data, res), res, origin
    return None


def _driven_metrics(g: dict, start: float, stop: float, tg, pg, field) -> dict:
    """Start and end pose, path length, final distance and least clearance over [start, stop]."""
    row = {}
    sel = (tg >= start) & (tg <= stop)
    p_start = interp_poses([start], tg, pg)[0]
    row["start_x_m"], row["start_y_m"] = float(p_start[0]), float(p_start[1])
    row["path_length_m"] = path_length(pg[sel, 0], pg[sel, 1])
    p_end = interp_poses([stop], tg, pg)[0]
    row["end_x_m"], row["end_y_m"] = float(p_end[0]), float(p_end[1])
    if "target" in g:
        row["final_distance_m"] = float(np.hypot(p_end[0] - g["target"][0], p_end[1] - g["target"][1]))
    if field is not None and sel.any():
        d = sample(field[0], field[1], field[2], pg[sel, :2])
        row["min_clearance_m"] = float(np.nanmin(d)) if np.isfinite(d).any() else None
    return row


def _goal_row(bag: Bag, i: int, gid: str, g: dict, topics: dict, tg, pg, field, contact_t) -> dict:
    start = g.get("published") or (g["stamp"] if g["stamp"] > 0 else g["first_seen"])
    end = g["end"]
    row = {
        "goal": i,
        "id": gid,
        "status": status_name(g["status"]),
        "target_x_m": g.get("target", (None, None))[0],
        "target_y_m": g.get("target", (None, None))[1],
        "time_s": None if end is None else float(end - start),
    }
    stop = end if end is not None else (tg[-1] if pg is not None else bag_end(bag))
    if topics.get("collisions"):
        row["collision_samples"] = int(np.count_nonzero((contact_t >= start) & (contact_t <= stop)))
    if pg is not None:
        row.update(_driven_metrics(g, start, stop, tg, pg, field))
    return row


def analyze(bag: Bag, topics: dict, options: dict) -> Result:
    goals, order = _goals_from_status(bag, topics["status"])
    if topics.get("action_goal"):
        _attach_action_goals(bag, topics["action_goal"], goals)
    if topics.get("simple_goal"):
        _attach_simple_goals(bag, topics["simple_goal"], goals, order)
    tg = pg = None
    if topics.get("ground_truth"):
        tg, pg = odometry_poses(bag, topics["ground_truth"])
    field = _clearance_field(bag, topics, options)
    # the contact monitor's samples (one message per 10 ms with a robot-world contact)
    contact_t = np.array(
        [t * 1e-9 for topic in topics.get("collisions") or [] for t, msg in bag.messages(topic) if msg.data]
    )
    rows = [
        _goal_row(bag, i, gid, goals[gid], topics, tg, pg, field, contact_t) for i, gid in enumerate(order)
    ]
    m = {"goals": len(rows), "succeeded": sum(r["status"] == "SUCCEEDED" for r in rows)}
    if topics.get("collisions"):
        m["collision_samples"] = int(len(contact_t))
    m["per_goal"] = rows
    figures = []
    if pg is not None:
        figures.append(
            Figure(
                "navigation_path", "Driven path (ground truth) and goals", lambda fig: _draw(fig, pg, rows)
            )
        )
    return Result(m, figures)


def bag_end(bag: Bag) -> float:
    return max(t for topic in bag.topics for t, _ in bag.messages(topic)[-1:]) * 1e-9


def _draw(fig, pg, rows) -> None:
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(pg[:, 0], pg[:, 1], lw=1.4, label="ground truth")
    for r in rows:
        if r["target_x_m"] is not None:
            ax.plot(r["target_x_m"], r["target_y_m"], "*", ms=11)
            ax.annotate(f"{r['goal']}: {r['status']}", (r["target_x_m"], r["target_y_m"]), fontsize=7)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
