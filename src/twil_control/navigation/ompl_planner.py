"""Global planning with OMPL on a costmap (the role of a move_base global planner plugin).

R^2 or SE(2) states, valid when the footprint clears the inflated costmap, motions checked by
one numpy gather per segment (OMPL's default validator would call into Python once per sample).
Objectives `length` (all in C++) or `length_and_cost`, which keeps paths away from inflated
obstacles. What the Python binding needs (bool validity, no module-level OMPL objects, PRM*
refused with a Python objective because it deadlocks): docs/navigation.md.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from twil_control.errors import TwilControlError

from . import costmap as cm
from .collision import GridChecker
from .footprint import FootprintCells

PLANNERS = ("RRTConnect", "RRT", "RRTstar", "InformedRRTstar", "BITstar", "PRMstar", "SORRTstar", "AORRTC")
OPTIMISING = {"RRTstar", "InformedRRTstar", "BITstar", "PRMstar", "SORRTstar", "AORRTC"}
STATE_SPACES = ("R2", "SE2")
OBJECTIVES = ("length", "length_and_cost")
# planners that sample informed when the objective has a cost-to-go heuristic; the Python cost
# objective has none (see _make_cost_objective), so they sample uniformly with it
INFORMED = {"InformedRRTstar", "BITstar", "SORRTstar", "AORRTC"}

log = logging.getLogger(__name__)
_uninformed_warned: set[str] = set()  # planner names warned about, once per process


class OmplPlannerError(TwilControlError, ValueError):
    """A bad planner configuration."""


@dataclass
class OmplSettings:
    planner: str = "RRTConnect"
    state_space: str = "R2"
    objective: str = "length_and_cost"
    cost_factor: float = 1.0
    planning_time: float = 1.0  # s: the budget (optimising planners use all of it)
    stop_at_first_solution: bool = False  # optimising planners return their first solution
    simplify: bool = True
    interpolation_resolution: float = 0.05  # m between the published path's poses
    allow_unknown: bool = False
    range: float = 0.0  # planner range (m); 0 lets OMPL choose
    # > 0: also stop after this many planner iterations (calls of the termination condition), so a
    # seeded run does the same work whatever the machine's speed: deterministic. Not for PRMstar,
    # whose roadmap grows in a second thread that cannot call back into Python.
    max_iterations: int = 0

    def __post_init__(self) -> None:
        if self.planner not in PLANNERS:
            raise OmplPlannerError(
                f"planner {self.planner!r} is not supported; allowed: {', '.join(PLANNERS)}"
            )
        if self.state_space not in STATE_SPACES:
            raise OmplPlannerError(f"state_space {self.state_space!r} is not supported; allowed: R2, SE2")
        if self.objective not in OBJECTIVES:
            raise OmplPlannerError(
                f"objective {self.objective!r} is not supported; allowed: {', '.join(OBJECTIVES)}"
            )
        if self.planner == "PRMstar" and self.objective != "length":
            raise OmplPlannerError(
                "planner PRMstar needs objective 'length': OMPL's PRM* checks for solutions in "
                "a second thread, which cannot call the Python cost objective"
            )
        if not (self.planning_time > 0 and math.isfinite(self.planning_time)):
            raise OmplPlannerError(
                f"planning_time must be a positive number of seconds (got {self.planning_time})"
            )
        if not self.cost_factor >= 0:
            raise OmplPlannerError(f"cost_factor must be >= 0 (got {self.cost_factor})")
        if self.max_iterations < 0:
            raise OmplPlannerError(f"max_iterations must be >= 0 (got {self.max_iterations})")
        if self.max_iterations and self.planner == "PRMstar":
            raise OmplPlannerError(
                "planner PRMstar cannot use max_iterations (its second thread cannot call the "
                "Python termination condition); use planning_time"
            )
        if not self.interpolation_resolution > 0:
            raise OmplPlannerError(
                f"interpolation_resolution must be > 0 m (got {self.interpolation_resolution})"
            )


@dataclass
class PlanResult:
    poses: np.ndarray | None  # (k, 3) x, y, yaw, or None when no exact solution was found
    status: str  # OMPL's status text ("Exact solution", "Timeout", ...)
    solve_time: float  # s spent in solve()
    length: float  # xy length of the path (m), inf without a path


class Planner:
    """One planning problem set-up on one costmap snapshot; holds every OMPL object it makes."""

    def __init__(
        self, costmap: cm.Costmap, cells: FootprintCells, settings: OmplSettings, seed: int | None = None
    ) -> None:
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ou

        if seed is not None:
            seed_ompl(seed)
        ou.setLogLevel(ou.LOG_WARN)
        self.ob, self.og, self.ou = ob, og, ou
        self.settings = settings
        self.checker = GridChecker(costmap, cells, settings.allow_unknown)
        self.checker.warm_up()  # compile before solve(), whose time budget would pay for it
        self.se2 = settings.state_space == "SE2"
        h, w = costmap.shape
        lo, hi = costmap.origin, costmap.origin + np.array([w, h]) * costmap.resolution
        bounds = ob.RealVectorBounds(2)
        bounds.setLow(0, float(lo[0]))
        bounds.setHigh(0, float(hi[0]))
        bounds.setLow(1, float(lo[1]))
        bounds.setHigh(1, float(hi[1]))
        self.space = ob.SE2StateSpace() if self.se2 else ob.RealVectorStateSpace(2)
        self.space.setBounds(bounds)
        self.si = ob.SpaceInformation(self.space)
        calls = _Callbacks(self.checker, self.se2, settings.cost_factor)
        self.xyyaw = calls.xyyaw
        self.si.setStateValidityChecker(calls.state_valid)
        self.validator = _make_motion_validator(ob, calls)(self.si)
        self.si.setMotionValidator(self.validator)
        self.si.setup()
        if settings.objective == "length":
            self.objective = ob.PathLengthOptimizationObjective(self.si)
        else:
            self.objective = _make_cost_objective(ob, calls)(self.si)

    # -- solving ----------------------------------------------------------------------------
    def _state(self, pose):
        st = self.si.allocState()
        if self.se2:
            st.setX(float(pose[0]))
            st.setY(float(pose[1]))
            st.setYaw(float(pose[2]))
        else:
            st[0] = float(pose[0])
            st[1] = float(pose[1])
        return st

    def solve(self, start, goal) -> PlanResult:
        ob, og, cfg = self.ob, self.og, self.settings
        pdef = ob.ProblemDefinition(self.si)
        pdef.setStartAndGoalStates(self._state(start), self._state(goal))
        if cfg.stop_at_first_solution or cfg.planner not in OPTIMISING:
            self.objective.setCostThreshold(ob.Cost(math.inf))  # any solution satisfies it
        pdef.setOptimizationObjective(self.objective)
        planner = getattr(og, cfg.planner)(self.si)
        if cfg.range > 0 and hasattr(planner, "setRange"):
            planner.setRange(cfg.range)
        planner.setProblemDefinition(pdef)
        quiet = cfg.planner in INFORMED and cfg.objective != "length"
        if quiet and cfg.planner not in _uninformed_warned:
            _uninformed_warned.add(cfg.planner)
            log.warning(
                "%s samples uniformly with objective %r: OMPL's Python binding cannot take its "
                "cost-to-go heuristic (objective 'length' samples informed)",
                cfg.planner,
                cfg.objective,
            )
        level = self.ou.getLogLevel()
        if quiet:  # OMPL would repeat that twice per plan on stderr; a failed plan is the caller's to report
            self.ou.setLogLevel(self.ou.LOG_ERROR)
        try:
            return self._solve(planner, pdef)
        finally:
            self.ou.setLogLevel(level)

    def _solve(self, planner, pdef) -> PlanResult:
        ob, og, cfg = self.ob, self.og, self.settings
        planner.setup()
        ptc = ob.timedPlannerTerminationCondition(cfg.planning_time)
        if cfg.max_iterations:
            calls = [0]

            def iterations_done() -> bool:
                calls[0] += 1
                return calls[0] > cfg.max_iterations

            ptc = ob.plannerOrTerminationCondition(ptc, ob.PlannerTerminationCondition(iterations_done))
        t0 = time.perf_counter()
        status = planner.solve(ptc)
        dt = time.perf_counter() - t0
        if not pdef.hasExactSolution():
            return PlanResult(None, str(status), dt, math.inf)
        path = pdef.getSolutionPath()
        if cfg.simplify:
            og.PathSimplifier(self.si, None, self.objective).simplifyMax(path)
        poses = self._densify(path)
        return PlanResult(poses, str(status), dt, float(np.sum(np.hypot(*np.diff(poses[:, :2], axis=0).T))))

    def _densify(self, path) -> np.ndarray:
        """The path's vertices joined by straight segments sampled every interpolation_resolution,
        yaw along each segment (R^2) or interpolated (SE(2)); the last pose keeps the goal's yaw."""
        pts = [self.xyyaw(s) for s in path.getStates()]
        out = []
        for (xa, ya, yawa), (xb, yb, yawb) in zip(pts, pts[1:]):
            d = math.hypot(xb - xa, yb - ya)
            n = max(1, int(math.ceil(d / self.settings.interpolation_resolution)))
            s = np.arange(n) / n
            heading = math.atan2(yb - ya, xb - xa) if d > 1e-9 else (yawa or 0.0)
            yaw = (
                heading * np.ones(n) if yawa is None else yawa + s * math.remainder(yawb - yawa, 2 * math.pi)
            )
            out.append(np.column_stack([xa + s * (xb - xa), ya + s * (yb - ya), yaw]))
        last = pts[-1]
        out.append(
            np.array([[last[0], last[1], last[2] if last[2] is not None else out[-1][-1, 2] if out else 0.0]])
        )
        return np.vstack(out)


def seed_ompl(seed: int) -> None:
    """Seed OMPL's random numbers: every RNG made afterwards (a planner's, a sampler's) takes its
    seed from a generator seeded here, so a planner built after this call samples the same way
    on every run. OMPL logs an error when this is called after the first RNG was made (it still
    reseeds the generator, which is what re-planning needs), so logging is off for the call."""
    from ompl import util as ou

    level = ou.getLogLevel()
    ou.setLogLevel(ou.LOG_NONE)
    try:
        ou.RNG.setSeed(int(seed) % (2**32 - 1) + 1)  # OMPL ignores 0
    finally:
        ou.setLogLevel(level)


class _Callbacks:
    """What OMPL calls back (must return Python bool / float). It holds no OMPL object, and the
    OMPL objects hold it, not the Planner: SpaceInformation keeps the validity checker and the
    motion validator in C++, where Python's garbage collector does not see them, so a callback
    that led back to the Planner (and so to the SpaceInformation) made a cycle it could never
    free. Every planning call then leaked its Planner with its costmap snapshot, and nanobind
    listed the survivors at exit."""

    def __init__(self, checker: GridChecker, se2: bool, cost_factor: float) -> None:
        self.checker, self.se2, self.cost_factor = checker, se2, cost_factor

    def xyyaw(self, s) -> tuple[float, float, float | None]:
        if self.se2:
            return s.getX(), s.getY(), s.getYaw()
        return s[0], s[1], None

    def state_valid(self, s) -> bool:
        # R^2 states test the inscribed disc; their footprints are checked along motions
        return self.checker.pose_free(*self.xyyaw(s))

    def motion_valid(self, a, b) -> bool:
        xa, ya, yawa = self.xyyaw(a)
        xb, yb, yawb = self.xyyaw(b)
        return self.checker.segment_free((xa, ya), (xb, yb), yawa, yawb)

    def motion_cost(self, a, b) -> float:
        xa, ya, _ = self.xyyaw(a)
        xb, yb, _ = self.xyyaw(b)
        length = math.hypot(xb - xa, yb - ya)
        if length == 0.0:
            return 0.0
        n = max(2, int(length / self.checker.costmap.resolution) + 1)
        mean = self.checker.segment_mean_cost(xa, ya, xb, yb, n)
        return length * (1.0 + self.cost_factor * mean / 252.0)


def _make_motion_validator(ob, calls: _Callbacks):
    class GridMotionValidator(ob.MotionValidator):
        def __init__(self, si) -> None:
            super().__init__(si)

        def checkMotion(self, a, b, *last) -> bool:
            return calls.motion_valid(a, b)

    return GridMotionValidator


def _make_cost_objective(ob, calls: _Callbacks):
    class LengthAndCostObjective(ob.OptimizationObjective):
        """length x (1 + cost_factor x mean cost / 252); the length alone is an admissible
        heuristic since the factor is >= 1. It has no cost-to-go heuristic, so the INFORMED
        planners sample uniformly (solve() says so once): the binding refuses a Python one
        (setCostToGoHeuristic), and deriving from OMPL's path-length objective instead, which
        brings one, made BIT* segfault (a broken parent chain in bestPathFromGoalToStart,
        seeded house runs)."""

        def __init__(self, si) -> None:
            super().__init__(si)

        def stateCost(self, s):
            return self.identityCost()

        def motionCost(self, a, b):
            return ob.Cost(calls.motion_cost(a, b))

        def motionCostHeuristic(self, a, b):
            xa, ya, _ = calls.xyyaw(a)
            xb, yb, _ = calls.xyyaw(b)
            return ob.Cost(math.hypot(xb - xa, yb - ya))

    return LengthAndCostObjective


def plan(
    costmap: cm.Costmap, cells: FootprintCells, start, goal, settings: OmplSettings, seed: int | None = None
) -> PlanResult:
    """Plan from start to goal poses (x, y, yaw) on one costmap snapshot (seeded: see seed_ompl)."""
    return Planner(costmap, cells, settings, seed).solve(start, goal)
