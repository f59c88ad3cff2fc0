"""nav_msgs/OccupancyGrid and MapMetaData from a mapping.map_io.OccupancyMap, and back."""

from __future__ import annotations

import numpy as np

from ..control.transforms import quat_from_yaw, yaw_from_quat
from ..core.messages import header, msg_class, time_msg
from ..core.odometry_msg import pose_msg
from ..mapping.map_io import OccupancyMap


def map_metadata_msg(grid: OccupancyMap, load_time: float):
    x, y, yaw = grid.origin
    return msg_class("nav_msgs/MapMetaData")(
        map_load_time=time_msg(load_time),
        resolution=float(grid.resolution),
        width=grid.width,
        height=grid.height,
        origin=pose_msg((x, y, 0.0), quat_from_yaw(yaw)),
    )


def occupancy_grid_msg(
    grid: OccupancyMap, frame_id: str, t: float, load_time: float | None = None, seq: int = 0
):
    """The grid as OccupancyGrid: data row-major from cell (0, 0) (row 0 at the origin)."""
    return msg_class("nav_msgs/OccupancyGrid")(
        header=header(frame_id, t, seq),
        info=map_metadata_msg(grid, t if load_time is None else load_time),
        data=np.ascontiguousarray(grid.data, dtype=np.int8).ravel(),
    )


def map_from_msg(msg) -> OccupancyMap:
    info = msg.info
    o = info.origin
    yaw = yaw_from_quat([o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w])
    data = np.asarray(msg.data, dtype=np.int8).reshape(info.height, info.width)
    return OccupancyMap(data.copy(), float(info.resolution), (o.position.x, o.position.y, yaw))
