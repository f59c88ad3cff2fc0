"""A replay drawn in the view (rosbag play + rviz): the view subscribes to the replayed topics as
in a live run and is ticked by the bus, so its throttles hold in bag time. There is no
simulation, hence no MeshcatVisualizer: the robot is a box posed from /tf (world ->
base_link_ground_truth when the bag has the truth, else map -> base_link). The replay is the
caller's (bag/'s player on the master's bus, built and checked before the view opens): the view
holds no bag code."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from ..core.node import Master
from .view_node import ViewNode, ViewOptions

Stats = TypeVar("Stats")


def replay_into_view(
    master: Master, options: ViewOptions, play: Callable[[], Stats]
) -> tuple[ViewNode, Stats]:
    """Run `play` (which publishes on master.bus) with a view on the graph; returns the view
    (still open: call view.shutdown()) and what `play` returned."""
    view = ViewNode(master, "view", options=options)
    try:
        view.on_start()
        master.bus.add_listener(lambda topic, msgtype, msg, t: view.tick(t))
        stats = play()
        view.flush(master.clock.now())
    except BaseException:
        view.shutdown()
        raise
    return view, stats
