"""`bag play --view`: a bag replayed into the operator's view (rosbag play + rviz).

The view subscribes to the replayed topics exactly as it does in a live run; it is ticked by
the bus (a listener sees every message as it is published, at the bag's time), so drawing keeps
the live run's throttles in bag time. There is no simulation, hence no MeshcatVisualizer: the
robot is a box standing in for it, posed from /tf (world -> base_link_ground_truth when the bag
has the truth, else map -> base_link).
"""

from __future__ import annotations

from pathlib import Path

from ..core.node import Master
from ..view.view_node import ViewNode, ViewOptions
from .play import Player, PlayStats
from .reader import Bag


def play_with_view(
    bag: Path,
    options: ViewOptions,
    rate: float = 1.0,
    start: float = 0.0,
    duration: float | None = None,
    topics: list[str] | None = None,
) -> tuple[ViewNode, PlayStats]:
    """Play `bag` into a new view; returns the view (still open: call view.shutdown()) and the stats."""
    master = Master()
    player = Player(Bag(bag), bus=master.bus, rate=rate, start=start, duration=duration, topics=topics)
    view = ViewNode(master, "view", options=options)
    try:
        view.on_start()
        master.bus.add_listener(lambda topic, msgtype, msg, t: view.tick(t))
        stats = player.run()
        view.flush(master.clock.now())
    except BaseException:
        view.shutdown()
        raise
    return view, stats
