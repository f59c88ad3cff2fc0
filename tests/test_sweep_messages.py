"""What a sweep says when it cannot do what it was asked (sweep/__main__.py, sweep/worker.py):
--out naming a file is one error line and exit 2; a run stopped by its timeout before the
launch's time started says no bag was written, not that its bag holds what ran."""

from __future__ import annotations

from twil_control import PACKAGE_ROOT
from twil_control.sweep import worker
from twil_control.sweep.__main__ import main as sweep_main
from twil_control.sweep.worker import RunTask, execute_run

SWEEP = str(PACKAGE_ROOT / "config/sweeps/cart_gains.yaml")


def test_out_naming_a_file_is_one_error_line(tmp_path, capsys):
    file = tmp_path / "results.csv"
    file.write_text("not a folder\n")
    assert sweep_main([SWEEP, "--out", str(file)]) == 2
    err = capsys.readouterr().err
    assert err == f"error: --out {file} is a file; name a folder for the sweep's runs and table\n"
    assert sweep_main([SWEEP, "--out", str(file / "inside")]) == 2
    assert capsys.readouterr().err.startswith(f"error: --out {file / 'inside'}: cannot make the folder")
    assert file.read_text() == "not a folder\n"


def test_a_run_stopped_while_starting_up_says_it_wrote_no_bag(tmp_path, monkeypatch):
    # the worker looks at its run every POLL seconds, and a light launch starts its time within
    # the first second on a fast machine: looking every 10 ms stops it while Python still imports
    monkeypatch.setattr(worker, "POLL", 0.01)
    task = RunTask(
        run_id="early",
        index=0,
        launch=str(PACKAGE_ROOT / "launch/wam_computed_torque.launch.yaml"),
        argv=["--duration", "300"],
        run_dir=str(tmp_path),
        timeout=0.01,
    )
    record = execute_run(task)
    assert record["status"] == "timeout" and record["bag"] is None
    assert record["error"] == (
        "timed out after 0.01 s wall time (stopped while starting up, before its time started; "
        "no bag was written)"
    )
    assert not (tmp_path / "run_early.bag").exists()
