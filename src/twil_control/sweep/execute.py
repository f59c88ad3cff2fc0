"""Runs a sweep on Dask: a local cluster of worker processes, or an existing scheduler.

The table is built from the per-run records on disk, so it always holds everything that
finished, whatever stopped the sweep; a finished run is not run again, and a run whose bag has no
metrics yet gets them from its bag without running again. With a scheduler, the workers must see
the same checkout and output directory at the same paths (docs/sweeps.md).
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
import time
import uuid
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .metrics import analyzer_available
from .progress import ProgressLine, progress_wanted
from .results import plot, plotted_metrics, summary, table, write_table
from .runs import Run, runs_of
from .spec import Sweep
from .worker import FAILED, RunTask, execute_run, read_record, write_record

#: Seconds to wait, after Ctrl-C, for running launches to close their bags and return.
STOP_WAIT = 30.0
#: Seconds between looks at the futures (and progress updates).
POLL = 0.25


@dataclass
class SweepOutcome:
    frame: pd.DataFrame
    metric_names: list[str]
    summary: str
    csv: Path
    parquet: Path
    plots: list[Path] = field(default_factory=list)
    executed: int = 0  # tasks executed by this invocation (runs + metrics-only)
    interrupted: bool = False

    @property
    def all_ok(self) -> bool:
        return bool((self.frame["status"] == "ok").all())


def run_dir(out_dir: Path) -> Path:
    return out_dir / "runs"


def plan(
    sweep: Sweep, out_dir: Path, retry_failed: bool = False, metrics_available: bool | None = None
) -> tuple[list[Run], dict[str, dict], list[RunTask]]:
    """(runs, records already on disk, tasks still to do).

    A run with no record is run. A run whose launch ended well (ok, or failed only in its
    metrics) gets its metrics computed again from its bag when they are missing or were
    computed with other options. Failed and timed-out runs are run again only on request."""
    runs, _ = runs_of(sweep)
    if metrics_available is None:
        metrics_available = analyzer_available()
    records, tasks = {}, []
    directory = str(run_dir(out_dir).absolute())
    for run in runs:
        record = read_record(run_dir(out_dir) / f"{run.name}.json")
        common = dict(
            run_id=run.run_id,
            index=run.index,
            launch=run.launch,
            argv=run.launch_argv(),
            run_dir=directory,
            timeout=sweep.timeout,
            metrics_options=sweep.metrics,
        )
        analysed = record is not None and (
            record.get("status") == "ok" or record.get("metrics_error") is not None
        )
        if record is None or (retry_failed and not analysed):
            tasks.append(RunTask(**common))
            continue
        record["index"] = run.index  # the same run may sit elsewhere in an edited sweep
        records[run.run_id] = record
        never_analysed = record.get("metrics") is None and record.get("metrics_error") is None
        stale = (never_analysed and metrics_available) or record.get("metrics_options") != sweep.metrics
        if analysed and record.get("bag") and (stale or (retry_failed and record["status"] != "ok")):
            tasks.append(RunTask(**common, metrics_only=True, record=record))
    return runs, records, tasks


def run_sweep(
    sweep: Sweep,
    out_dir: Path,
    scheduler: str | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: bool | None = None,
    echo=None,
) -> SweepOutcome:
    """Run what is left of ``sweep`` into ``out_dir``; write and return its table."""
    echo = echo or (lambda text: print(text, file=sys.stderr, flush=True))
    out_dir = Path(out_dir).absolute()
    run_dir(out_dir).mkdir(parents=True, exist_ok=True)
    metrics_available = analyzer_available()
    runs, records, tasks = plan(sweep, out_dir, retry_failed, metrics_available)
    _, duplicates = runs_of(sweep)
    if duplicates:
        echo(f"note: {duplicates} duplicate run(s) in the sweep are run once")
    if not metrics_available:
        echo(
            "note: twil_control.bag.analyze is not available: runs are recorded without "
            "metrics (a rerun computes them from the bags once it is)"
        )
    todo = sum(not t.metrics_only for t in tasks)
    echo(
        f"sweep {sweep.name}: {len(runs)} runs, {len(runs) - todo} already done, "
        f"{todo} to run"
        + (f", {len(tasks) - todo} to (re)analyse" if len(tasks) > todo else "")
        + f"; output {out_dir}"
    )
    interrupted = False
    if tasks:
        interrupted = execute_tasks(
            tasks, scheduler, workers, len(runs), progress_wanted() if progress is None else progress, echo
        )
    return finish(sweep, runs, out_dir, executed=len(tasks), interrupted=interrupted)


def finish(
    sweep: Sweep, runs: list[Run], out_dir: Path, executed: int = 0, interrupted: bool = False
) -> SweepOutcome:
    """Table, plots and summary from the records on disk."""
    records = {}
    for run in runs:
        record = read_record(run_dir(out_dir) / f"{run.name}.json")
        if record is not None:
            records[run.run_id] = record
    frame, metric_names = table(runs, records)
    csv, parquet = write_table(frame, out_dir)
    varied = list(sweep.varied_names)
    shown = plotted_metrics(frame, metric_names, sweep.plots)
    plots = plot(frame, shown, varied, out_dir / "plots")
    text = summary(frame, metric_names, varied, sweep.objective, shown)
    return SweepOutcome(frame, metric_names, text, csv, parquet, plots, executed, interrupted)


def execute_tasks(
    tasks: list[RunTask], scheduler: str | None, workers: int | None, total: int, show_progress: bool, echo
) -> bool:
    """Run the tasks on a cluster; True when stopped by Ctrl-C (a Ctrl-C during the local
    cluster's start-up, a few seconds, is ignored: see _sigint_ignored_in_children)."""
    from distributed import Event

    stop_name = f"twil-sweep-stop-{uuid.uuid4().hex[:8]}"
    tasks = [RunTask(**{**t.__dict__, "stop_event": stop_name}) for t in tasks]
    already = total - sum(not t.metrics_only for t in tasks)
    line = ProgressLine(total, already, show_progress)
    with _cluster(scheduler, workers, len(tasks), echo) as client:
        event = Event(stop_name, client=client)
        token = uuid.uuid4().hex[:8]
        futures = {
            client.submit(execute_run, task, key=f"twil-sweep-{task.run_id}-{token}", pure=False): task
            for task in tasks
        }
        pending, done, failed = set(futures), 0, 0
        try:
            while pending:
                finished = {f for f in pending if f.done()}
                pending -= finished
                for future in finished:
                    record = _record_of(future, futures[future])
                    done += 0 if futures[future].metrics_only else 1
                    failed += record.get("status") != "ok"
                if line.enabled:
                    line.update(done, failed, _running(client, pending))
                if pending and not finished:
                    time.sleep(POLL)
            line.close()
            return False
        except KeyboardInterrupt:
            line.close()
            echo(
                "interrupted: stopping the running launches (their runs are not recorded "
                "and run again next time); finished runs are kept"
            )
            try:
                event.set()
                deadline = time.monotonic() + STOP_WAIT
                while any(not f.done() for f in pending) and time.monotonic() < deadline:
                    time.sleep(POLL)
            except KeyboardInterrupt:
                echo("interrupted again: not waiting for the launches to close their bags")
            client.cancel(list(pending))
            return True


def _record_of(future, task: RunTask) -> dict:
    """The task's record; a task that raised (or whose worker died) is recorded as failed."""
    try:
        return future.result()
    except Exception as exc:
        record = {
            "run_id": task.run_id,
            "index": task.index,
            "status": FAILED,
            "error": f"worker: {type(exc).__name__}: {exc}",
            "wall_time": None,
            "bag": None,
            "metrics": None,
            "metrics_options": task.metrics_options,
            "finished": time.time(),
        }
        if task.metrics_only and task.record:
            record = {**task.record, "status": FAILED, "error": record["error"]}
        write_record(Path(task.run_dir) / f"run_{task.run_id}.json", record)
        return record


def _running(client, pending) -> int:
    """Runs executing now: a worker may hold more tasks than threads (Dask queues a few
    ahead), so each worker counts at most its thread count."""
    try:
        processing, threads = client.processing(), client.nthreads()
    except Exception:
        return 0
    keys = {f.key for f in pending}
    return sum(
        min(sum(key in keys for key in tasks), threads.get(worker, 1)) for worker, tasks in processing.items()
    )


@contextmanager
def _cluster(scheduler: str | None, workers: int | None, ntasks: int, echo):
    """A Client on the given scheduler, or on a LocalCluster closed on the way out."""
    from distributed import Client, LocalCluster

    if scheduler:
        client = Client(scheduler_file=scheduler) if Path(scheduler).is_file() else Client(scheduler)
        try:
            echo(
                f"scheduler {client.scheduler.address}: "
                f"{len(client.scheduler_info(n_workers=-1)['workers'])} workers"
            )
            yield client
        finally:
            client.close()
        return
    n = max(1, min(workers or os.cpu_count() or 1, ntasks))
    with _sigint_ignored_in_children():
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
    client = Client(cluster)
    echo(f"local cluster: {n} worker process(es), 1 thread each")
    try:
        yield client
    finally:
        client.close()
        cluster.close()


@contextmanager
def _sigint_ignored_in_children():
    """Worker processes started in here ignore SIGINT (an ignored signal stays ignored in
    children), so a Ctrl-C on the terminal reaches the sweep alone and it stops them in order."""
    if sys.platform == "win32" or threading.current_thread() is not threading.main_thread():
        yield  # signal handlers can only be set from the main thread
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
