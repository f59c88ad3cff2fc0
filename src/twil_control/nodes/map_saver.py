"""map_saver's role: writes the map it receives on ``map`` as a map_server pair.

Args as the original's: ``[-f BASENAME] [--occ 65] [--free 25]`` (BASENAME default "map", a
relative one taken from the working directory, as map_saver and --bag do). Cells in
0..free are written free, occ..100 occupied, the rest unknown (mapping.map_io).

When: the first map that arrives is written at once (the original saved that one and exited);
every later map is kept and the latest is written again when the launch ends, so a SLAM run
leaves its final map behind however it ends.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from ..core.ros_node import NodeArgsError, RosNode
from ..mapping.map_io import write_map
from .map_msg import map_from_msg


class MapSaver(RosNode):
    def __init__(self, *a, **kw) -> None:
        super().__init__(*a, **kw)
        parser = argparse.ArgumentParser(add_help=False)
        parser.add_argument("-f", dest="basename", default="map")
        parser.add_argument("--occ", type=int, default=65)
        parser.add_argument("--free", type=int, default=25)
        opts = self.parse_args(parser)
        if not 0 <= opts.free < opts.occ <= 100:
            raise NodeArgsError(
                f"node {self.fqn}: need 0 <= --free < --occ <= 100 (got --free {opts.free}, --occ {opts.occ})"
            )
        self.basename, self.occ, self.free = Path(opts.basename), opts.occ, opts.free
        self.saved = 0  # maps written so far
        self._latest = None  # the last map received
        self._latest_written = True
        self.create_subscription("map", "nav_msgs/OccupancyGrid", self._on_map)

    def _write(self) -> None:
        grid = map_from_msg(self._latest)
        self.basename.parent.mkdir(parents=True, exist_ok=True)
        yml, pgm = write_map(grid, self.basename, self.occ, self.free)
        self.saved += 1
        self._latest_written = True
        self.log.info(
            "wrote a %d x %d map @ %.3f m/cell to %s and %s",
            grid.width,
            grid.height,
            grid.resolution,
            yml,
            pgm,
        )

    def _on_map(self, msg) -> None:
        self._latest, self._latest_written = msg, False
        if self.saved == 0:
            self._write()

    def shutdown(self) -> None:
        if self._latest is not None and not self._latest_written:
            self._write()
