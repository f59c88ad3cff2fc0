"""Runs a launch plan: builds the nodes and the Drake diagram, records the bag, advances time.

The order is fixed so runs are reproducible: nodes are built and visited in launch-file order
(core.ros_node) and time advances in fixed simulated slices. Everything that can be checked is
checked before the bag is opened, so bad input never leaves a bag behind; once recording has
started, every way out closes the bag with what it holds. Node failures follow roslaunch's
required/respawn (launch/supervision.py; docs/failures.md).
"""

from __future__ import annotations

import gc
import logging
import math
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from twil_control.errors import TwilControlError

from ..bag.recorder import MIN_SPACE, BagRecorder, RecorderError, check_writable
from ..core.node import Master, check_seed
from ..core.rosout import RosoutHandler
from . import node_types as registry
from .allocator import keep_freed_memory
from .display_nodes import announce as announce_display_nodes
from .interrupt import STOP_SIGNALS
from .plan import LaunchPlan
from .record_check import RecordCheck
from .supervision import RequiredNodeFailed, Supervisor, cause_of, is_bug

if TYPE_CHECKING:  # the view and the bridge are imported only when a run asks for them
    from ..foxglove.bridge import FoxgloveOptions
    from ..view.view_node import ViewOptions

log = logging.getLogger("twil_control.launch")

#: Topics every bag holds, whatever the launch's record list says.
ALWAYS_RECORDED = ("/rosout", "/clock")

#: Simulated seconds between checks for Ctrl-C, node completion and progress output.
SLICE = 0.05

#: Python's GIL switch interval while time runs (s; Python's default is 0.005). The simulation
#: takes the GIL for every Python system's event (the controller manager's, at 1 kHz); while
#: another thread runs Python (slam_gmapping's worker, the view's server), it waits until that
#: thread is made to let go, which Python does after the switch interval: with the default a
#: 0.2 ms step could wait 5 ms. bench/gil_bench.py measures the difference.
SWITCH_INTERVAL = 0.0002


class LaunchRuntimeError(TwilControlError, RuntimeError):
    """A launch that cannot be built (two worlds, a node hook failing before time starts)."""


@dataclass
class RunOptions:
    duration: float | None = None  # simulated seconds; None = until a node is done or Ctrl-C
    bag: Path | None = None  # None = do not record
    realtime: float = 0.0  # target real-time rate; 0 = as fast as possible
    seed: int = 0
    progress: bool = False  # a progress line on the terminal
    view: ViewOptions | None = None  # view.view_node.ViewOptions: the Meshcat view; None = headless
    stop_when_done: bool = True  # end when a node reports its work done (off while a user drives the view)
    foxglove: FoxgloveOptions | None = (
        None  # foxglove.bridge.FoxgloveOptions: serve the bus live; None = no server
    )
    chunk_seconds: float = 1.0  # simulated seconds a bag chunk holds at most (0: 1 MiB chunks)
    min_space: int = MIN_SPACE  # free bytes the bag's disk needs at start (warned below while recording)
    fsync: bool = True  # fdatasync each bag chunk, in a thread (a power loss then loses about one chunk)


@dataclass
class RunResult:
    sim_time: float = 0.0
    wall_time: float = 0.0
    bag: Path | None = None
    messages: int = 0
    interrupted: bool = False
    signal: int = 0  # the signal that ended the run (0: none)
    error: BaseException | None = (
        None  # what stopped the launch early (a required node, a system, the bag's disk)
    )
    failures: list = field(default_factory=list)  # supervision.Failure of every node that failed
    nodes: list = field(default_factory=list)

    @property
    def failed(self) -> bool:
        """The run went wrong: it stopped on an error, or a node failed on the way (exit 1)."""
        return self.error is not None or bool(self.failures)

    @property
    def realtime_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else math.inf


class Launch:
    """A launch plan turned into live nodes and (when a world is simulated) a Drake simulator."""

    def __init__(self, plan: LaunchPlan, seed: int = 0) -> None:
        self.plan = plan
        self.master = Master(plan.params)
        self.master.seed = check_seed(seed)
        unknown = registry.unknown_types(plan.nodes)
        if unknown is not None:
            raise unknown
        self.rosout = RosoutHandler(self.master).attach()  # every node's log lines on /rosout
        try:
            self.nodes = [self._construct(spec) for spec in plan.nodes]
        except BaseException:
            self.rosout.detach()
            raise
        self.supervisor = Supervisor(
            self.master, self.nodes, {spec.fqn: spec for spec in plan.nodes}, self._construct
        )
        self.sim = None
        self.simulator = None

    def _construct(self, spec):
        cls = registry.get(spec.pkg, spec.type)
        node = cls(self.master, spec.name, spec.namespace, spec.remappings, spec.args)
        node.arg_sources = dict(spec.arg_sources)
        return node

    def build(self) -> None:
        """Run the build phases; afterwards the diagram exists and time is 0."""
        makers = [n for n in self.nodes if n.simulates()]
        if len(makers) > 1:
            raise LaunchRuntimeError(
                "a launch simulates one world; these nodes each start one: "
                + ", ".join(n.fqn for n in makers)
            )
        if makers:
            sim = self.sim = makers[0].make_simulation()
            for node in self.nodes:
                node.build_world(sim)
            sim.finalize()
            for node in self.nodes:
                node.build_systems(sim)
        elif users := [n.fqn for n in self.nodes if n.build_hooks()]:
            raise LaunchRuntimeError(
                f"nodes {', '.join(users)} need a simulated world, but the "
                "launch starts none (add a twil_control/drake_world node)"
            )

    def start(self) -> None:
        """Time 0: nodes' on_start hooks, then the timers they created join the simulation.

        A required node failing here on purpose (a TwilControlError, such as its ``fail(reason)``)
        is LaunchRuntimeError: the launch did not start; any other exception is a bug and
        propagates as it was raised."""
        try:
            for node in list(self.nodes):
                self.supervisor.start(node)
        except RequiredNodeFailed as stop:
            if is_bug(stop.failure.error):
                raise cause_of(stop.failure.error) from None
            raise LaunchRuntimeError(f"{stop}; the launch was not started") from stop.failure.error
        if self.sim is not None:
            from ..world.ros_timers import RosTimers  # Drake only when a world is simulated

            self.supervisor.timer_events = False
            if self.master.timers:
                self.supervisor.timer_events = self.sim.add_system(RosTimers(self.master), "ros_timers")
            self.simulator = self.sim.build()
            self.simulator.Initialize()
        # Everything built so far lives until the end: move it out of the collector's reach, so
        # a collection during the 1 kHz loop scans only what the run allocates (a full one would
        # take longer than a control period). It stays frozen: the diagram outlives the run
        # anyway (pydrake 1.51 never frees a diagram holding a Python LeafSystem), and unfrozen,
        # the process's exit would scan the whole heap, long enough that a sweep worker's
        # repeated SIGINT (every 0.5 s) kills the exiting launch.
        gc.collect()
        gc.freeze()

    def between_slices(self) -> None:
        """Between two slices of simulated time (the simulator's context may change here)."""
        for node in self.nodes:
            node.between_slices()

    def is_done(self) -> bool:
        return any(n.is_done() for n in self.nodes)

    def shutdown(self) -> None:
        for node in reversed(self.nodes):
            try:
                node.shutdown()
            except Exception:  # one node's failure must not keep the others (or the bag) open
                log.exception("node %s failed to shut down", node.fqn)
        self.rosout.detach()


def run(plan: LaunchPlan, options: RunOptions, on_master=None) -> RunResult:
    """Build, record and run a launch plan.

    Errors before time starts (bad parameters, unknown types, missing files, a required node
    failing in on_start, such as a spawner whose controller does not load) propagate and no bag
    is written. Afterwards a required node's failure, or an exception in a Drake system, stops
    the run and is returned in RunResult.error; other nodes' failures are logged and returned in
    RunResult.failures while the run goes on. The bag is closed however the run ends, holding
    everything up to its end.
    """
    keep_freed_memory()  # no page faults for memory freed and allocated again at every step
    launch = _make_launch(plan, options, on_master)
    result = RunResult(nodes=launch.nodes)
    _build_and_start(launch)
    bridge = _open_bridge(launch, plan, options)
    # From here on a stop signal only ends time (checked once a slice): the bag is closed.
    stop = {"signal": 0, "continued": False}
    previous = _catch_stop_signals(stop)
    recorder, record_check = _start_recording(launch, plan, options, bridge, previous)
    previous_switch = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL)
    wall0 = time.perf_counter()
    try:
        _run_time(launch, options, stop, wall0, recorder, bridge)
    except RequiredNodeFailed as stop_error:  # report it, keep the bag
        result.error = stop_error
    except Exception as error:  # a Drake system raised (or the bag's disk filled) while time runs: the same
        result.error = error
    finally:
        result.failures = launch.supervisor.failures
        sys.setswitchinterval(previous_switch)
        result.signal = stop["signal"]
        result.interrupted = bool(result.signal)
        result.wall_time = time.perf_counter() - wall0
        result.sim_time = launch.master.clock.now()
        _close_run(result, launch, bridge, recorder, record_check, previous)
    return result


def _make_launch(plan: LaunchPlan, options: RunOptions, on_master) -> Launch:
    """The nodes, constructed (the bag's folder checked first), the view's among them if asked for."""
    if options.bag is not None:
        check_writable(options.bag, min_space=options.min_space)
    launch = Launch(plan, seed=options.seed)
    announce_display_nodes(launch.nodes, plan.nodes, view_served=bool(getattr(options.view, "serve", False)))
    if options.view is not None:  # imported only when asked for: headless runs create no Meshcat
        from ..view.view_node import ViewNode

        launch.nodes.append(ViewNode(launch.master, options=options.view))
    if on_master is not None:  # e.g. the logger stamping records with simulated time
        on_master(launch.master)
    return launch


def _build_and_start(launch: Launch) -> None:
    try:
        launch.build()
        launch.start()
    except BaseException:
        launch.shutdown()
        raise


def _open_bridge(launch: Launch, plan: LaunchPlan, options: RunOptions):
    """The Foxglove bridge if asked for, opened before the bag: a port in use must not leave a
    bag behind."""
    if options.foxglove is None:
        return None
    from ..foxglove.bridge import FoxgloveBridge

    try:
        return FoxgloveBridge(
            launch.master,
            options.foxglove,
            name=f"twil_control {plan.files[0].name if plan.files else ''}".strip(),
        )
    except BaseException:
        launch.shutdown()
        raise


def _catch_stop_signals(stop: dict) -> dict:
    """Route the stop signals and SIGCONT into `stop`; the handlers they replace."""

    def on_stop_signal(signum, frame):
        stop["signal"] = stop["signal"] or signum

    def on_continue(signum, frame):  # SIGCONT: the process had been stopped (SIGSTOP, Ctrl-Z)
        stop["continued"] = True

    previous = {s: signal.signal(s, on_stop_signal) for s in STOP_SIGNALS}
    previous[signal.SIGCONT] = signal.signal(signal.SIGCONT, on_continue)
    return previous


def _start_recording(launch: Launch, plan: LaunchPlan, options: RunOptions, bridge, previous: dict):
    """(recorder, record check), None for both without a bag. Recording starts once everything
    is built, as rosbag record subscribing to a running graph: latched messages sent at start
    (/tf_static) are written first, stamped now."""
    if options.bag is None:
        return None, None
    topics = plan.record_topics
    if topics is not None:  # /rosout and /clock are always recorded, as the log of the run
        topics = topics + [t for t in ALWAYS_RECORDED if t not in topics]
    try:
        recorder = BagRecorder(
            options.bag,
            launch.master.bus,
            topics,
            compression=plan.record_compression,
            chunk_seconds=options.chunk_seconds,
            min_space=options.min_space,
            fsync=options.fsync,
        )
    except BaseException:
        if bridge is not None:
            bridge.close()
        launch.shutdown()
        _restore(previous)
        raise
    launch.rosout.replay(recorder.write)  # the lines logged while the launch was built
    return recorder, RecordCheck(launch.master.bus, plan.record_topics)


def _run_time(launch: Launch, options: RunOptions, stop: dict, wall0: float, recorder, bridge) -> None:
    if launch.simulator is not None:
        launch.simulator.set_target_realtime_rate(options.realtime)
        # pace from now, time 0 of the run: Drake paces from Initialize(), and what happens
        # between (the recorder's set-up) would otherwise be run off faster than real time
        launch.simulator.ResetStatistics()
    end = math.inf if options.duration is None else options.duration
    _advance(launch, end, options, stop, wall0, recorder, bridge)


def _close_run(result: RunResult, launch: Launch, bridge, recorder, record_check, previous: dict) -> None:
    """Shut the nodes down and close the bag whatever fails on the way; the signal handlers
    come back last."""
    try:
        if bridge is not None:
            bridge.close()
        launch.shutdown()
    finally:
        try:
            if recorder is not None:
                result.bag = recorder.close()
                result.messages = recorder.count
                if record_check is not None:
                    record_check.finish()
                if recorder.failure and result.error is None:
                    result.error = RecorderError(recorder.failure)
        finally:
            # only now: a second signal (a sweep's worker repeats SIGINT every 0.5 s until
            # the launch exits) must not break off the nodes' shutdown or the bag's close
            _restore(previous)


def _restore(handlers: dict) -> None:
    for signum, handler in handlers.items():
        signal.signal(signum, handler)


def _advance(
    launch: Launch,
    end: float,
    options: RunOptions,
    stop: dict,
    wall0: float,
    recorder: BagRecorder | None = None,
    bridge=None,
) -> None:
    """Advance time slice by slice: the Drake simulator when a world is simulated, otherwise
    the nodes' timers alone (a launch of pure ROS nodes), paced to `realtime` if asked."""
    simulator = launch.simulator
    progress = _Progress(end) if options.progress else None
    t = launch.master.clock.now()
    pace = _Pace(launch, options.realtime, t)
    while t < end - 1e-12 and not stop["signal"]:
        t = min(t + SLICE, end)
        if simulator is not None:
            # not interruptible: pydrake would take the GIL at every step to look for Ctrl-C, which
            # on_stop_signal and this loop handle (once a slice)
            simulator.AdvanceTo(t, interruptible=False)
        else:
            launch.master.spin_until(t)
        pace.after_slice(t, stop)
        launch.master.clock.set(t)
        launch.between_slices()
        launch.supervisor.respawn_due(t)
        if recorder is not None:
            recorder.flush()
        if bridge is not None:  # after the recorder: the messages' bytes are serialised by then
            bridge.tick()
        if progress:
            progress.show(t, time.perf_counter() - wall0)
        if options.stop_when_done and launch.is_done():
            log.info("a node reported its work done at t = %.3f s", t)
            break
    if progress:
        progress.close()


class _Pace:
    """Real-time pacing that never catches up (as Gazebo paces): Drake's simulator sleeps toward
    its target rate counted from an anchor, and after a stop (SIGSTOP, a suspended laptop, a
    machine too busy for a while) it would run the lost time off unpaced. Once a slice the lag
    is measured; past MAX_LAG the anchor moves to now, so pacing resumes from where it was, and
    a lag from a stop is reported. A launch without a simulator is paced here alone."""

    MAX_LAG = 0.5  # wall seconds behind the schedule that are caught up, no more
    REPORTED = 1.0  # a lag this large in one slice is a pause: said in the log

    def __init__(self, launch: Launch, rate: float, t: float) -> None:
        self._launch, self.rate = launch, rate
        self.pauses: list[tuple[float, float]] = []  # (sim time, wall seconds lost)
        self._anchor(t)

    def _anchor(self, t: float) -> None:
        self.wall0, self.t0 = time.perf_counter(), t
        if self._launch.simulator is not None and self._launch.sim is not None:
            self._launch.simulator.ResetStatistics()  # Drake paces from here on
            self._launch.sim.pace_anchor = (self.wall0, self.t0)

    def after_slice(self, t: float, stop: dict) -> None:
        if self.rate <= 0:
            return
        due = self.wall0 + (t - self.t0) / self.rate
        now = time.perf_counter()
        if self._launch.simulator is None and now < due:
            time.sleep(due - now)
            return
        behind = now - due
        if behind <= self.MAX_LAG:
            return
        continued, stop["continued"] = stop.get("continued"), False
        if continued or behind > self.REPORTED:
            self.pauses.append((t, behind))
            why = (
                "the process was stopped and continued (SIGSTOP or Ctrl-Z, then SIGCONT)"
                if continued
                else "the process was paused or the machine too busy"
            )
            log.warning(
                "paced run: %.1f s of wall time lost at t = %.3f s: %s; pacing resumes from here at "
                "%gx real time, without catching up",
                behind,
                t,
                why,
                self.rate,
            )
        self._anchor(t)


class _Progress:
    """One self-rewriting terminal line: simulated time and real-time factor."""

    def __init__(self, end: float) -> None:
        import sys

        self._out = sys.stderr
        self._end = end
        self._last = 0.0

    def show(self, t: float, wall: float) -> None:
        now = time.perf_counter()
        if now - self._last < 0.2:
            return
        self._last = now
        rtf = t / wall if wall > 0 else 0.0
        total = "" if math.isinf(self._end) else f"/{self._end:.1f}"
        bar = ""
        if not math.isinf(self._end):
            filled = int(30 * t / self._end)
            bar = "[" + "#" * filled + "-" * (30 - filled) + "] "
        self._write(f"\r{bar}sim {t:.2f}{total} s  {rtf:.1f}x real time ")

    def close(self) -> None:
        self._write("\n")

    def _write(self, text: str) -> None:
        if self._out is None:
            return
        try:
            self._out.write(text)
            self._out.flush()
        except OSError:  # the terminal is gone (SIGHUP): the run goes on to close its bag
            self._out = None
