"""Resume: which runs a rerun executes, from the records a previous invocation left."""

from __future__ import annotations

from pathlib import Path

from twil_control.sweep.execute import plan, run_dir
from twil_control.sweep.spec import load_sweep
from twil_control.sweep.worker import write_record


def _sweep(tmp_path: Path, metrics: str = "{}"):
    path = tmp_path / "s.yaml"
    path.write_text(
        "launch: launch/wam_computed_torque.launch.yaml\n"
        f"grid: {{seed: [0, 1, 2]}}\nduration: 1.0\nmetrics: {metrics}\n"
    )
    return load_sweep(path)


def _record(out: Path, run, status: str, metrics=None, metrics_error=None, options=None):
    run_dir(out).mkdir(parents=True, exist_ok=True)
    write_record(
        run_dir(out) / f"{run.name}.json",
        {
            "run_id": run.run_id,
            "index": run.index,
            "status": status,
            "error": None if status == "ok" else "boom",
            "bag": "/b.bag",
            "metrics": metrics,
            "metrics_error": metrics_error,
            "metrics_options": {} if options is None else options,
        },
    )


def _todo(sweep, out, **kwargs) -> list[tuple[int, bool]]:
    _, _, tasks = plan(sweep, out, metrics_available=True, **kwargs)
    return [(t.index, t.metrics_only) for t in tasks]


def test_without_records_every_run_is_to_do(tmp_path):
    sweep = _sweep(tmp_path)
    runs, records, tasks = plan(sweep, tmp_path / "out", metrics_available=True)
    assert [t.index for t in tasks] == [0, 1, 2] and records == {}
    assert tasks[2].argv == ["--duration", "1.0", "--seed", "2"]
    assert tasks[0].run_dir == str(tmp_path / "out" / "runs")


def test_finished_runs_are_skipped_whatever_their_status(tmp_path):
    sweep, out = _sweep(tmp_path), tmp_path / "out"
    runs, _, _ = plan(sweep, out)
    _record(out, runs[0], "ok", metrics={"m": 1.0})
    _record(out, runs[1], "failed")
    _record(out, runs[2], "timeout")
    assert _todo(sweep, out) == []
    assert _todo(sweep, out, retry_failed=True) == [(1, False), (2, False)]


def test_metrics_are_recomputed_from_the_bag_when_missing_or_their_options_change(tmp_path):
    sweep, out = _sweep(tmp_path), tmp_path / "out"
    runs, _, _ = plan(sweep, out)
    _record(out, runs[0], "ok", metrics=None)  # analysis was unavailable
    _record(out, runs[1], "ok", metrics={"m": 1.0}, options={"wn": 4.0})
    _record(out, runs[2], "failed", metrics_error="metrics: BagError: x")
    assert _todo(sweep, out) == [(0, True), (1, True)]
    _, _, tasks = plan(sweep, out, metrics_available=False)
    assert [(t.index, t.metrics_only) for t in tasks] == [(1, True)]
    # a run whose launch ended well but whose analysis failed is analysed again on request
    assert _todo(sweep, out, retry_failed=True) == [(0, True), (1, True), (2, True)]
    changed = _sweep(tmp_path, metrics="{wn: 4.0}")
    assert _todo(changed, out) == [(0, True), (2, True)]
