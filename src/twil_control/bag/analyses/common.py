"""What the analyses share: their result type, topic lookup and typed series of a bag."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..reader import Bag
from ..signals import yaw_from_quaternion


class AnalysisSkipped(Exception):
    """The analysis applies by its topics but cannot run (the reason goes into the report)."""


@dataclass
class Figure:
    name: str  # file stem
    title: str
    draw: Callable  # draw(fig) fills a matplotlib Figure


@dataclass
class Result:
    metrics: dict
    figures: list[Figure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def seconds(bag: Bag, t_ns) -> np.ndarray:
    """Bag times (ns) as seconds of simulated time (the recorder stamps sim time)."""
    return np.asarray(t_ns, dtype=np.int64) * 1e-9


ODOMETRY_FIELDS = [
    "pose.pose.position.x",
    "pose.pose.position.y",
    "pose.pose.orientation.x",
    "pose.pose.orientation.y",
    "pose.pose.orientation.z",
    "pose.pose.orientation.w",
]


def odometry_poses(bag: Bag, topic: str) -> tuple[np.ndarray, np.ndarray]:
    """(t seconds, (N, 3) planar poses) of a nav_msgs/Odometry topic."""
    names = ODOMETRY_FIELDS
    t, c = bag.columns(topic, names)
    yaw = yaw_from_quaternion(c[names[2]], c[names[3]], c[names[4]], c[names[5]])
    return seconds(bag, t), np.stack([c[names[0]], c[names[1]], yaw], axis=-1)


def joint_fields(bag: Bag, topic: str, joints: list[str]) -> tuple[list[int], list[str], bool]:
    """(indices of the joints, the position/velocity fields to read, whether velocities are
    recorded) in a JointState topic (names from its first message: the joint order of
    /joint_states does not change during a run)."""
    first = bag.first_message(topic)
    names = list(first.name)
    missing = [j for j in joints if j not in names]
    if missing:
        raise AnalysisSkipped(f"{topic} has no joints {', '.join(missing)} (it has {', '.join(names)})")
    idx = [names.index(j) for j in joints]
    fields = [f"position[{i}]" for i in idx]
    has_vel = len(first.velocity) == len(names)
    if has_vel:
        fields += [f"velocity[{i}]" for i in idx]
    return idx, fields, has_vel


def joint_states(bag: Bag, topic: str, joints: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, positions (N, J), velocities (N, J)) of the named joints."""
    idx, fields, has_vel = joint_fields(bag, topic, joints)
    t, c = bag.columns(topic, fields)
    q = np.stack([c[f"position[{i}]"] for i in idx], axis=-1)
    qd = (
        np.stack([c[f"velocity[{i}]"] for i in idx], axis=-1)
        if has_vel
        else np.gradient(q, seconds(bag, t), axis=0)
    )
    return seconds(bag, t), q, qd


def find_ground_truth(bag: Bag, near: str = "") -> str | None:
    """The nav_msgs/Odometry topic with 'ground_truth' in its name (the one sharing the longest
    namespace prefix with `near` if several)."""
    cands = [t for t in bag.topics_of_type("nav_msgs/Odometry") if "ground_truth" in t]
    if not cands:
        return None
    return max(cands, key=lambda c: (_common_prefix(c, near), -len(c)))


def find_odometry(bag: Bag, near: str = "") -> str | None:
    """The nav_msgs/Odometry topic that is not ground truth (the wheel odometry), the one
    sharing the longest namespace prefix with `near` if several."""
    cands = [t for t in bag.topics_of_type("nav_msgs/Odometry") if "ground_truth" not in t]
    if not cands:
        return None
    return max(cands, key=lambda c: (_common_prefix(c, near), -len(c)))


def _common_prefix(a: str, b: str) -> int:
    n = 0
    for x, y in zip(a.split("/"), b.split("/")):
        if x != y:
            break
        n += 1
    return n


def arm_joint_names(names: list[str], count: int, requested: list[str] | None) -> list[str]:
    """The joints a reference of `count` values refers to: as requested, or all joint_states
    joints when their number matches, or those named like the WAM's (wam_joint_N)."""
    if requested:
        if len(requested) != count:
            raise AnalysisSkipped(f"{len(requested)} joints given for references of {count} values")
        return list(requested)
    if len(names) == count:
        return list(names)
    wam = [n for n in names if n.startswith("wam_joint_")]
    if len(wam) == count:
        return wam
    raise AnalysisSkipped(
        f"cannot tell which of the joints {', '.join(names)} the {count} reference "
        "values are for: pass arm_joints"
    )


def draw_lines(ax, t, series: dict, ylabel: str, logy: bool = False) -> None:
    for label, v in series.items():
        ax.plot(t, v, lw=1.1, label=label)
    if logy:
        ax.set_yscale("log")
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.3)
    if len(series) > 1:
        ax.legend(fontsize=7, loc="best", ncol=2)


def tf_series(bag: Bag, topic: str = "/tf") -> dict[tuple[str, str], tuple[np.ndarray, np.ndarray]]:
    """{(parent, child): (t seconds from header stamps, (N, 3) planar poses)} of a tf topic."""
    acc: dict[tuple[str, str], list] = {}
    if topic not in bag.topics:
        return {}
    for _, msg in bag.messages(topic):
        for tr in msg.transforms:
            q, p = tr.transform.rotation, tr.transform.translation
            key = (tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/"))
            acc.setdefault(key, []).append(
                (
                    tr.header.stamp.sec + 1e-9 * tr.header.stamp.nanosec,
                    p.x,
                    p.y,
                    float(yaw_from_quaternion(q.x, q.y, q.z, q.w)),
                )
            )
    out = {}
    for key, rows in acc.items():
        a = np.array(rows)
        order = np.argsort(a[:, 0], kind="stable")
        out[key] = (a[order, 0], a[order, 1:])
    return out


def grid_of(msg) -> tuple[np.ndarray, float, tuple[float, float, float]]:
    """(data (H, W) int8 with row 0 at the origin, resolution, origin (x, y, yaw)) of a
    nav_msgs/OccupancyGrid."""
    info = msg.info
    o = info.origin
    yaw = float(yaw_from_quaternion(o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w))
    data = np.asarray(msg.data, dtype=np.int8).reshape(info.height, info.width)
    return data, float(info.resolution), (o.position.x, o.position.y, yaw)
