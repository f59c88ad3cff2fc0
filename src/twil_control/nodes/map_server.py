"""map_server's role: serves a map file as a latched nav_msgs/OccupancyGrid.

Args as ``rosrun map_server map_server MAP.yaml``: the map's YAML file (a relative path is looked
up as every input path is: the working directory, then the package root; core.paths). Private param ``frame_id`` (default
"map"). Publishes, latched, at t = 0: ``map`` (nav_msgs/OccupancyGrid) and ``map_metadata``
(nav_msgs/MapMetaData), relative names as map_server's (so /map in the root namespace), and
offers the ``static_map`` service (nav_msgs/GetMap's role: called with no arguments, it returns
the OccupancyGrid). File format and thresholds: mapping.map_io.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import ClassVar

from ..core.paths import InputPathError, find_file
from ..core.ros_node import NodeArgsError, RosNode
from ..mapping.map_io import MapFileError, read_map
from .map_msg import map_metadata_msg, occupancy_grid_msg


@dataclass
class MapServerParams:
    ros_package: ClassVar[str] = "map_server"
    frame_id: str = "map"


class MapServer(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        parser = argparse.ArgumentParser(add_help=False)
        parser.add_argument("map_yaml", help="map file (YAML)")
        map_yaml = self.parse_args(parser).map_yaml
        self.params = self.typed_params(MapServerParams)
        try:
            self.path = find_file(map_yaml, "map file")
            self.map = read_map(self.path)
        except (InputPathError, MapFileError) as error:
            raise NodeArgsError(f"node {self.fqn}: {error}") from None
        self._map_pub = self.create_publisher("map", "nav_msgs/OccupancyGrid", latch=True)
        self._meta_pub = self.create_publisher("map_metadata", "nav_msgs/MapMetaData", latch=True)
        self._msg = None
        self.master.advertise_service(self.resolve("static_map"), self.fqn, self._static_map)

    def on_start(self) -> None:
        t = self.now()
        self._msg = occupancy_grid_msg(self.map, self.params.frame_id, t)
        self._meta_pub.publish(map_metadata_msg(self.map, t))
        self._map_pub.publish(self._msg)
        self.log.info(
            "read a %d x %d map @ %.3f m/cell from %s",
            self.map.width,
            self.map.height,
            self.map.resolution,
            self.path,
        )

    def _static_map(self):
        if self._msg is None:
            self._msg = occupancy_grid_msg(self.map, self.params.frame_id, self.now())
        return self._msg
