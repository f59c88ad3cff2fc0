"""The tf tree: broadcasters publishing on /tf and /tf_static, and a buffer that looks up
transforms between any two frames at a time (tf2_ros's Buffer and TransformListener roles).

A lookup walks both frames up to their common ancestor, interpolating each dynamic edge
between the two stamps around the query time (linear in translation, slerp in rotation).
Static edges hold at every time. As in tf2, lookup_transform(target, source) gives the pose of
`source` in `target` (it maps points in source coordinates to target coordinates); time None
means "the latest time every edge on the path has" (tf2's Time(0)).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from twil_control.errors import TwilControlError

from ..control import transforms as tr
from .messages import header, msg_class, to_sec

TF_TYPE = "tf2_msgs/TFMessage"


class TfError(TwilControlError, LookupError):
    """No path between two frames, or a time outside the buffer (tf2's exceptions)."""


@dataclass
class _Edge:
    parent: str
    static: bool
    times: list[float] = field(default_factory=list)
    # ((x, y, z), (qx, qy, qz, qw)) as plain floats: lookups compose them with
    # control.transforms' float functions (a numpy array per value cost more than the math)
    values: list[tuple[tuple, tuple]] = field(default_factory=list)


def transform_stamped(parent: str, child: str, t: float, translation, quaternion):
    """A geometry_msgs/TransformStamped; quaternion in (x, y, z, w) order."""
    vec = msg_class("geometry_msgs/Vector3")
    quat = msg_class("geometry_msgs/Quaternion")
    return msg_class("geometry_msgs/TransformStamped")(
        header=header(parent, t),
        child_frame_id=child,
        transform=msg_class("geometry_msgs/Transform")(
            translation=vec(x=float(translation[0]), y=float(translation[1]), z=float(translation[2])),
            rotation=quat(
                x=float(quaternion[0]), y=float(quaternion[1]), z=float(quaternion[2]), w=float(quaternion[3])
            ),
        ),
    )


class TfBroadcaster:
    """Publishes dynamic transforms on /tf."""

    def __init__(self, node) -> None:
        self._pub = node.create_publisher("/tf", TF_TYPE)

    def send(self, *transforms) -> None:
        self._pub.publish(msg_class(TF_TYPE)(transforms=list(transforms)))


class StaticTfBroadcaster:
    """Publishes static transforms, latched, on /tf_static; each send re-publishes them all."""

    def __init__(self, node) -> None:
        self._pub = node.create_publisher("/tf_static", TF_TYPE, latch=True)
        self._all: dict[str, Any] = {}

    def send(self, *transforms) -> None:
        for tf in transforms:
            self._all[tf.child_frame_id] = tf
        self._pub.publish(msg_class(TF_TYPE)(transforms=list(self._all.values())))


class TfBuffer:
    """Keeps `cache_time` seconds of /tf and all of /tf_static and answers lookups."""

    def __init__(self, node, cache_time: float = 10.0) -> None:
        self.cache_time = cache_time
        self._edges: dict[str, _Edge] = {}
        self._paths: dict[tuple[str, str], tuple[list[str], list[str]]] = {}  # cleared on re-parenting
        node.create_subscription("/tf", TF_TYPE, lambda m: self._add(m, static=False))
        node.create_subscription("/tf_static", TF_TYPE, lambda m: self._add(m, static=True))

    def _add(self, msg, static: bool) -> None:
        for tf in msg.transforms:
            stamp = tf.header.stamp
            tr_ = tf.transform.translation
            q = tf.transform.rotation
            self._set(
                tf.header.frame_id,
                tf.child_frame_id,
                to_sec(stamp),
                ((tr_.x, tr_.y, tr_.z), (q.x, q.y, q.z, q.w)),
                static,
            )

    def set_transform(self, parent: str, child: str, t: float, value, static: bool = False) -> None:
        """Store child's pose in parent at time t: value = (translation xyz, quaternion xyzw)."""
        translation, quaternion = value
        self._set(
            parent,
            child,
            t,
            (tuple(float(x) for x in translation), tuple(float(x) for x in quaternion)),
            static,
        )

    def _set(self, parent: str, child: str, t: float, value: tuple, static: bool) -> None:
        edge = self._edges.get(child)
        if edge is None or edge.parent != parent or edge.static != static:
            edge = self._edges[child] = _Edge(parent, static)  # re-parenting restarts the history
            self._paths.clear()
        if static:
            edge.times, edge.values = [t], [value]
            return
        times = edge.times
        if not times or t > times[-1]:  # the usual case: a newer stamp
            times.append(t)
            edge.values.append(value)
        else:
            i = bisect.bisect_right(times, t)
            if i > 0 and times[i - 1] == t:
                edge.values[i - 1] = value
            else:
                times.insert(i, t)
                edge.values.insert(i, value)
        if times[0] < times[-1] - self.cache_time:
            cut = bisect.bisect_left(times, times[-1] - self.cache_time)
            del times[:cut], edge.values[:cut]

    def frames(self) -> list[str]:
        return sorted(set(self._edges) | {e.parent for e in self._edges.values()})

    def _chain(self, frame: str) -> list[str]:
        chain = [frame]
        while chain[-1] in self._edges:
            chain.append(self._edges[chain[-1]].parent)
            if len(chain) > 1000:
                raise TfError(f"tf tree has a loop through frame '{frame}'")
        return chain

    def _path(self, target: str, source: str) -> tuple[list[str], list[str]]:
        path = self._paths.get((target, source))
        if path is not None:
            return path
        up_source, up_target = self._chain(source), self._chain(target)
        common = next((f for f in up_source if f in set(up_target)), None)
        if common is None:
            known = ", ".join(self.frames()) or "none"
            raise TfError(
                f"no transform from '{source}' to '{target}': the frames are not "
                f"connected (known frames: {known})"
            )
        path = self._paths[(target, source)] = (
            up_source[: up_source.index(common)],
            up_target[: up_target.index(common)],
        )
        return path

    def _edge_value(self, child: str, t: float):
        edge = self._edges[child]
        if edge.static:
            return edge.values[0]
        times = edge.times
        if t < times[0] - 1e-9 or t > times[-1] + 1e-9:
            raise TfError(
                f"transform {edge.parent} -> {child} is known for "
                f"[{times[0]:.3f}, {times[-1]:.3f}] s, not at {t:.3f} s (extrapolation)"
            )
        i = bisect.bisect_left(times, t)
        if i < len(times) and abs(times[i] - t) <= 1e-9:
            return edge.values[i]
        if i == 0:
            return edge.values[0]
        t0, t1 = times[i - 1], times[i]
        (p0, q0), (p1, q1) = edge.values[i - 1], edge.values[i]
        s = (t - t0) / (t1 - t0)
        return (tuple(a + s * (b - a) for a, b in zip(p0, p1)), tr.slerp_floats(q0, q1, s))

    def _latest(self, up: list[str], down: list[str]) -> float:
        ends = [self._edges[f].times[-1] for f in up + down if not self._edges[f].static]
        return min(ends) if ends else 0.0

    def latest_common_time(self, target: str, source: str) -> float:
        return self._latest(*self._path(target, source))

    def lookup_transform(self, target: str, source: str, t: float | None = None):
        """(translation, quaternion xyzw) of frame `source` expressed in frame `target`."""
        up, down = self._path(target, source)
        if t is None:
            t = self._latest(up, down)
        # X_common_source: compose from the common ancestor down to the source.
        p, q = _ORIGIN, _IDENTITY
        for child in reversed(up):
            p, q = tr.compose_floats(p, q, *self._edge_value(child, t))
        pt, qt = _ORIGIN, _IDENTITY
        for child in reversed(down):
            pt, qt = tr.compose_floats(pt, qt, *self._edge_value(child, t))
        p, q = tr.compose_floats(*tr.inverse_floats(pt, qt), p, q)
        return np.array(p), np.array(q)

    def can_transform(self, target: str, source: str, t: float | None = None) -> bool:
        try:
            self.lookup_transform(target, source, t)
            return True
        except TfError:
            return False


_ORIGIN = (0.0, 0.0, 0.0)
_IDENTITY = (0.0, 0.0, 0.0, 1.0)
