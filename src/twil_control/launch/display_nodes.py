"""What the launch says about its display nodes (rviz, gazebo_ros/gzclient, rqt_*, image_view,
rostopic echo and the like, nodes/display.py): one info line each, naming the node, its type
and where it is declared. Headless they are not run and the run goes on; with ``--view`` the
browser view shows the run in their place.
"""

from __future__ import annotations

import logging

log = logging.getLogger("twil_control.launch")


def announce(nodes, specs, view_served: bool) -> int:
    """Log one line per display node of ``nodes`` (built from ``specs``, in the same order);
    returns how many there are."""
    count = 0
    for node, spec in zip(nodes, specs):
        if not getattr(node, "displays_only", False):
            continue
        count += 1
        where = f"{spec.pkg}/{spec.type}" + (f", {spec.source}" if spec.source else "")
        if view_served:
            log.info(
                "node %s (%s) only displays: the view (--view) shows the run in its place", node.fqn, where
            )
        else:
            log.info(
                "node %s (%s) only displays: not run headless (--view opens the browser view in its place)",
                node.fqn,
                where,
            )
    return count
