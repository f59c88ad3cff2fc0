"""Gazebo's ROS plugins, loaded into the simulator node (/gazebo) from a spawned URDF's
``<gazebo>`` elements, as gazebo_ros loads them: each plugin's topics and services belong to the
simulator node and resolve in the plugin's ``robotNamespace``.

The simulator node (gazebo/gzserver.py) is the :class:`PluginHost`: spawn_model hands it a
description (:meth:`PluginHost.load_plugins`), and it runs the plugins' build and start hooks
with its own. The plugins: ros_control.py (gazebo_ros_control), drive.py (diff drive, skid
steer), sensors.py (laser, IMU, p3d).
"""

from __future__ import annotations

import logging

from twil_control.errors import InputError

from ...core import names
from ...core.node import Node

__all__ = ["PluginHost", "PluginNode", "host_of", "ros_control_of"]


class PluginNode(Node):
    """A plugin's node handle: names resolve in ``namespace``; what it publishes, subscribes and
    advertises belongs to the host node (rosnode shows /gazebo, as for gazebo_ros plugins)."""

    def __init__(self, host: Node, namespace: str) -> None:  # not registered: the host is the node
        self.master = host.master
        self.name = host.name
        self.namespace = names.canonical(namespace or "/")
        self.fqn = host.fqn
        self.remappings: dict[str, str] = {}
        self.log = host.log
        self._logged_once: set[str] = set()

    def resolve(self, name: str) -> str:
        return names.resolve(name, self.namespace, None, self.remappings)


def host_of(master):
    """The node hosting Gazebo plugins (the simulator node), or an error saying what to add."""
    hosts = [n for n in master.nodes.values() if isinstance(n, PluginHost)]
    if not hosts:
        raise InputError(
            "spawn_model -urdf/-sdf needs the simulator node (gazebo_ros/gzserver or "
            "twil_control/drake_world) in the launch"
        )
    return hosts[0]


def ros_control_of(nodes, namespace: str):
    """The gazebo_ros_control plugin (``.hw``, ``.manager``, ``.system``) running in
    ``namespace`` among ``nodes`` (a launch's nodes): tests and benches reach the controllers so."""
    for node in nodes:
        for plugin in getattr(node, "plugins", []) if isinstance(node, PluginHost) else []:
            if getattr(plugin, "manager", None) is not None and plugin.node.namespace == namespace:
                return plugin
    raise LookupError(f"no gazebo_ros_control plugin in {namespace}")


class PluginHost:
    """Mixin of the simulator node: the plugins of spawned descriptions and their hooks."""

    plugins: list

    def drive_effort_limits(self, description) -> dict[str, float]:
        """Wheel joints the description's drive plugins turn -> the plugin's torque (N m)."""
        from ...description.plugins import configure

        configured = configure(description, description.name)
        return {
            joint: drive.torque
            for drive in configured.drives
            for joint in drive.left_joints + drive.right_joints
        }

    def load_plugins(self, sim, model: str, description, robot_namespace: str | None) -> None:
        """Configure the description's plugins and sensors (spawn_model, before the plant is
        finalized); unsupported ones are warned about once each."""
        from ...description.plugins import configure
        from . import drive, ros_control, sensors

        configured = configure(description, model, robot_namespace)
        for warning in configured.warnings:
            self.log.warning("%s", warning)
        for note in configured.notes:
            self.log.info("%s", note)
        if configured.ros_control and configured.drives:
            joints = sorted({j for d in configured.drives for j in d.left_joints + d.right_joints})
            self.log.warning(
                "model %s has both gazebo_ros_control and a drive plugin; the drive plugin turns %s",
                model,
                ", ".join(joints),
            )
        for config in configured.ros_control:
            self.plugins.append(ros_control.RosControlPlugin(self, sim, model, config, description))
        for config in configured.drives:
            self.plugins.append(drive.DrivePlugin(self, sim, model, config, description))
        for config in configured.lasers:
            self.plugins.append(sensors.LaserPlugin(self, model, config))
        for config in configured.imus:
            kind = sensors.HectorImuPlugin if config.hector is not None else sensors.ImuPlugin
            self.plugins.append(kind(self, model, config))
        for config in configured.p3d:
            self.plugins.append(sensors.P3dPlugin(self, model, config))
        logging.getLogger(__name__).debug("model %s: %d plugins", model, len(self.plugins))

    def plugin_hook(self, hook: str, *args) -> None:
        for plugin in self.plugins:
            fn = getattr(plugin, hook, None)
            if fn is not None:
                fn(*args)
