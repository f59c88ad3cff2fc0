"""Nodes that only display: rviz, gazebo_ros/gzclient, the rqt_* plugins, image_view.

A launch file written for a desktop starts viewers beside the simulation. Here they take no
part in the graph: they read no parameter, subscribe to nothing, accept any args (``-d
config.rviz``) and never fail, so a headless run goes on. The runner logs one line for each
(launch/display_nodes.py); with ``--view`` the browser view shows the run in their place.
"""

from __future__ import annotations

from typing import ClassVar

from ..core.ros_node import RosNode


class DisplayNode(RosNode):
    """A viewer or GUI: present in the graph under its name, with nothing to run."""

    displays_only: ClassVar[bool] = True
