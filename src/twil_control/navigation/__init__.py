"""Navigation algorithms (move_base's roles), pure: numpy, OpenCV, SciPy, numba, OMPL.

costmap        costmap_2d: the cost grid, static / obstacle / inflation layers, rolling window
footprint      robot footprint polygon, its radii and the grid cells it covers per heading
grid_planner   navfn's role: cost-aware 8-connected Dijkstra / A* on the costmap
ompl_planner   global planning with OMPL on the costmap (R^2 or SE(2))
local_planner  base_local_planner's TrajectoryPlanner: sampled (v, w) rollouts, scoring
plans          why no plan can exist (move_base's abort reasons); a plan in the local frame, pruned
goals          goal poses refused before planning (non-finite, unnormalised quaternion)
"""
