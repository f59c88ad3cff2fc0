"""The global plan between the planners: why none can exist on a costmap (move_base's reasons
for aborting), and the plan as the local planner takes it (in its frame, from the robot on).

Pure: numpy and the costmap/grid planner of this package.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import costmap as cm
from . import grid_planner


@dataclass
class PlanFailure:
    """Why a goal got no plan; `structural`: no planner can solve it on this costmap."""

    reason: str
    structural: bool = False  # no planner can solve it on this costmap (outside, blocked, disconnected)


def diagnose(m: cm.Costmap, start, goal, allow_unknown: bool) -> PlanFailure | None:
    """Why no planner can connect start and goal on this costmap, or None."""
    h, w = m.shape
    x0, y0 = m.origin
    x1, y1 = x0 + w * m.resolution, y0 + h * m.resolution
    gr, gc = m.world_to_cell(goal[0], goal[1])
    if not m.inside(gr, gc):
        return PlanFailure(
            f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is outside the map "
            f"(x {x0:.2f}..{x1:.2f}, y {y0:.2f}..{y1:.2f})",
            True,
        )
    sr, sc = m.world_to_cell(start[0], start[1])
    if not m.inside(sr, sc):
        return PlanFailure(f"the robot ({start[0]:.2f}, {start[1]:.2f}) is outside the map", True)
    gcost = int(m.costs[gr, gc])
    if gcost == cm.NO_INFORMATION and not allow_unknown:
        return PlanFailure(f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is in unknown space", True)
    if gcost in (cm.LETHAL, cm.INSCRIBED):
        what = "an obstacle" if gcost == cm.LETHAL else "an obstacle's inscribed radius"
        return PlanFailure(f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is in {what} (cost {gcost})", True)
    scost = int(m.costs[sr, sc])
    if scost in (cm.LETHAL, cm.INSCRIBED):
        return PlanFailure(
            f"the robot's cell ({start[0]:.2f}, {start[1]:.2f}) is in an obstacle (cost {scost})", True
        )
    try:
        grid_planner.plan_cells(
            m.costs, (int(sr), int(sc)), (int(gr), int(gc)), 0.0, cm.INSCRIBED, allow_unknown
        )
    except grid_planner.NoPathError:
        return PlanFailure(
            f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is unreachable: no path through free space "
            f"connects it to the robot ({start[0]:.2f}, {start[1]:.2f})",
            True,
        )
    return None


def transform_path(plan: np.ndarray, T) -> np.ndarray:
    """Poses (k, 3) mapped by the 2-D transform T = (x, y, yaw)."""
    c, s = math.cos(T[2]), math.sin(T[2])
    x = T[0] + c * plan[:, 0] - s * plan[:, 1]
    y = T[1] + s * plan[:, 0] + c * plan[:, 1]
    return np.column_stack([x, y, plan[:, 2] + T[2]])


def prune(plan: np.ndarray, pose) -> np.ndarray:
    """The plan from its point closest to the robot onwards (base_local_planner's prune_plan)."""
    d = np.hypot(plan[:, 0] - pose[0], plan[:, 1] - pose[1])
    return plan[int(np.argmin(d)) :]


def blocked_ahead(
    m: cm.Costmap,
    plan: np.ndarray,
    pose,
    clear_radius: float,
    allow_unknown: bool,
    lethal: int = cm.INSCRIBED,
) -> bool:
    """Whether the plan, from its point nearest the robot on and beyond clear_radius of the robot,
    crosses a cell a planner could not plan through: cost at or above `lethal` (the inscribed
    zone or an obstacle), or unknown unless allowed. The points near the robot are left out: a
    robot close to an obstacle starts its plan in the obstacle's inflation."""
    ahead = prune(plan, pose)
    far = np.hypot(ahead[:, 0] - pose[0], ahead[:, 1] - pose[1]) > clear_radius
    r, c = m.world_to_cell(ahead[far, 0], ahead[far, 1])
    inside = m.inside(r, c)
    costs = m.costs[r[inside], c[inside]]
    unknown = costs == cm.NO_INFORMATION
    return bool(np.any((costs >= lethal) & ~unknown) or (not allow_unknown and np.any(unknown)))
