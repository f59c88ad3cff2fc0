"""One run, as a Dask worker executes it: the launch in a subprocess, then the bag's metrics.

A process of its own keeps Drake's state, a crash or a leak there, and lets a run past its timeout
be stopped as a person would (SIGINT: the launch closes its bag), then killed after a grace
period. It runs in a session of its own, so a Ctrl-C on the sweep's terminal reaches only the
sweep, which stops each run through a Dask Event; with setpriv, the launch also dies with its
worker. Each finished run is written at once, atomically, as RUN.json: that makes a rerun skip it.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .metrics import MetricsUnavailable, metrics_of

#: Seconds a run gets to close its bag after SIGINT before it is killed.
STOP_GRACE = 15.0
#: How often a running launch is checked for its timeout and the sweep's stop request (each
#: check of the stop request is a round trip to the scheduler).
POLL = 1.0
#: Characters of the launch's output kept at most as a failed run's error text.
ERROR_TAIL = 1500

OK, FAILED, TIMEOUT, CANCELLED = "ok", "failed", "timeout", "cancelled"


@dataclass(frozen=True)
class RunTask:
    """Everything a worker needs for one run (plain data: it travels to remote workers)."""

    run_id: str
    index: int
    launch: str
    argv: list[str]  # name:=value ..., --duration, --seed
    run_dir: str  # where RUN.bag, RUN.json, RUN.log go (shared filesystem)
    timeout: float
    metrics_options: dict[str, Any] = field(default_factory=dict)
    stop_event: str | None = None  # name of a distributed.Event that asks runs to stop
    metrics_only: bool = False  # the bag exists: (re)compute its metrics only
    record: dict[str, Any] | None = None  # the earlier record, for metrics_only
    # the command run: ``python -m MODULE [LAUNCH] ARGV... [--bag RUN.bag] --quiet``; other
    # modules (twil_control.barn) take their own argv, and with record_bag False no bag or metrics
    module: str = "twil_control.launch"
    record_bag: bool = True

    def path(self, suffix: str) -> Path:
        return Path(self.run_dir) / f"run_{self.run_id}{suffix}"


def execute_run(task: RunTask) -> dict[str, Any]:
    """Run one task and return its record (also written as RUN.json unless cancelled)."""
    stop_requested = _stop_check(task.stop_event)
    if task.metrics_only:
        record = dict(task.record or {})
        had_metrics_error = record.get("metrics_error") is not None
        record.update(_metrics_fields(task, task.path(".bag")))
        if record["metrics_error"] is not None:
            record["status"], record["error"] = FAILED, record["metrics_error"]
        elif had_metrics_error:  # the launch itself had ended well
            record["status"], record["error"] = OK, None
        write_record(task.path(".json"), record)
        return record
    start = time.monotonic()
    outcome = _launch(task, stop_requested)
    record = {
        "run_id": task.run_id,
        "index": task.index,
        "status": outcome.status,
        "error": outcome.error,
        "returncode": outcome.returncode,
        "wall_time": time.monotonic() - start,
        "cpu_time": outcome.cpu_time,
        "bag": None,
        "log": str(task.path(".log")),
        "host": socket.gethostname(),
        "finished": time.time(),
        "command": outcome.command,
        "metrics": None,
        "metrics_error": None,
        "metrics_options": task.metrics_options,
    }
    if outcome.status == CANCELLED:
        _remove(task.path(".bag"), task.path(".bag.active"))
        return record
    bag = task.path(".bag")
    if bag.exists():
        record["bag"] = str(bag)
    if outcome.status == OK and task.record_bag:
        record.update(_metrics_fields(task, bag))
        if record["metrics_error"] is not None:
            record["status"], record["error"] = FAILED, record["metrics_error"]
    write_record(task.path(".json"), record)
    return record


@dataclass
class _Outcome:
    status: str
    error: str | None
    returncode: int | None
    command: list[str]
    cpu_time: float | None = None  # user + system seconds of the launch process


def _launch(task: RunTask, stop_requested: Callable[[], bool]) -> _Outcome:
    bag, log_path = task.path(".bag"), task.path(".log")
    Path(task.run_dir).mkdir(parents=True, exist_ok=True)
    _remove(bag, task.path(".bag.active"))  # what an interrupted earlier attempt left
    command = [
        sys.executable,
        "-m",
        task.module,
        *([task.launch] if task.launch else []),
        *task.argv,
        *(["--bag", str(bag)] if task.record_bag else []),
        "--quiet",
    ]
    if stop_requested():  # Ctrl-C came before this run started
        return _Outcome(CANCELLED, "stopped by the sweep (Ctrl-C)", None, command)
    wrapper = _parent_death_wrapper()
    children_before = _children_cpu()
    with open(log_path, "w", encoding="utf-8") as log:
        proc = subprocess.Popen(
            wrapper + command,
            stdout=log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            cwd=task.run_dir,
            start_new_session=True,
            env=_child_env(),
        )
        deadline = time.monotonic() + task.timeout
        reason = None
        while proc.poll() is None:
            if time.monotonic() > deadline:
                reason = TIMEOUT
            elif stop_requested():
                reason = CANCELLED
            if reason:
                _stop(proc)
                break
            try:
                proc.wait(timeout=POLL)
            except subprocess.TimeoutExpired:
                pass
    code = proc.returncode
    cpu = _children_cpu() - children_before  # one run at a time per worker process (one thread)
    if reason == TIMEOUT:
        # the launch writes its bag once time starts: stopped before, it leaves none
        what = (
            "stopped"
            if not task.record_bag
            else "stopped; the bag holds what ran"
            if bag.exists()
            else "stopped while starting up, before its time started; no bag was written"
        )
        return _Outcome(TIMEOUT, f"timed out after {task.timeout:g} s wall time ({what})", code, command, cpu)
    if reason == CANCELLED:
        return _Outcome(CANCELLED, "stopped by the sweep (Ctrl-C)", code, command)
    if code != 0:
        reason = _verdict(log_path)
        return _Outcome(
            FAILED, f"exit code {code}: {reason}" if reason else f"exit code {code}", code, command, cpu
        )
    return _Outcome(OK, None, code, command, cpu)


def _children_cpu() -> float:
    """User + system CPU seconds of this process's waited-for children so far."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _stop(proc: subprocess.Popen) -> None:
    """SIGINT (the launch closes its bag and exits), SIGKILL after the grace period.

    SIGINT is sent again every half second: a launch still starting up may not listen yet
    (the launch installs its handler when time starts; the local cluster's workers, and so
    their children, ignore SIGINT until then, see execute._sigint_ignored_in_children)."""
    deadline = time.monotonic() + STOP_GRACE
    try:
        while proc.poll() is None and time.monotonic() < deadline:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                proc.wait(timeout=0.5)
            except subprocess.TimeoutExpired:
                pass
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def _parent_death_wrapper() -> list[str]:
    setpriv = shutil.which("setpriv") if sys.platform.startswith("linux") else None
    return [setpriv, "--pdeathsig", "KILL", "--"] if setpriv else []


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONUNBUFFERED"] = "1"  # the log holds everything up to a kill
    return env


def _stop_check(event_name: str | None) -> Callable[[], bool]:
    if not event_name:
        return lambda: False
    from distributed import Event  # only inside a Dask worker

    event = Event(event_name)

    def requested() -> bool:
        try:
            return event.is_set()
        except Exception:  # the scheduler is gone: the sweep is over
            return True

    return requested


def _metrics_fields(task: RunTask, bag: Path) -> dict[str, Any]:
    fields: dict[str, Any] = {"metrics": None, "metrics_error": None, "metrics_options": task.metrics_options}
    try:
        fields["metrics"] = to_plain(metrics_of(bag, task.metrics_options))
    except MetricsUnavailable:
        pass  # recorded without metrics; a later rerun computes them from the bag
    except Exception as exc:  # one bad bag must not stop the sweep
        fields["metrics_error"] = f"metrics: {type(exc).__name__}: {exc}"
    return fields


def to_plain(value: Any) -> Any:
    """numpy scalars/arrays and tuples as JSON-friendly Python values."""
    if isinstance(value, dict):
        return {str(k): to_plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_plain(value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    return value


def write_record(path: Path, record: dict[str, Any]) -> None:
    """Write RUN.json atomically: a crash leaves the old file or the new one, never half."""
    tmp = path.with_name(path.name + f".tmp{os.getpid()}")
    tmp.write_text(json.dumps(record, indent=1, allow_nan=True), encoding="utf-8")
    os.replace(tmp, path)


def read_record(path: Path) -> dict[str, Any] | None:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (FileNotFoundError, json.JSONDecodeError):
        return None


def _verdict(path: Path) -> str:
    """Why the launch failed, from its log: its last verdict line (exit 2's ``error: ...``, or the
    ``... failed at t = ...`` of a node failure), else the log's tail."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace").strip()
    except FileNotFoundError:
        return ""
    for line in reversed(text.splitlines()):
        if line.startswith("error: ") or " failed at t = " in line:
            return line[-ERROR_TAIL:]
    return text[-ERROR_TAIL:]


def _remove(*paths: Path) -> None:
    for p in paths:
        p.unlink(missing_ok=True)
