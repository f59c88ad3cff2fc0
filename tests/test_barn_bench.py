"""bench/barn_bench.py: a set that twil_control.barn refuses before any trial writes no result; a
trial run (BENCH_RESULTS elsewhere) draws its figure beside its results."""

from __future__ import annotations

import importlib
import json

from twil_control import PACKAGE_ROOT

BENCH = PACKAGE_ROOT / "bench"
VENDOR = PACKAGE_ROOT / "tests" / "data" / "ros1" / "vendor"


def test_a_records_folder_of_another_stack_stops_the_bench_with_exit_2_and_no_result(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.syspath_prepend(str(BENCH))
    barn_bench = importlib.import_module("barn_bench")
    results = tmp_path / "results"
    monkeypatch.setenv("BENCH_RESULTS", str(results))
    records = tmp_path / "records"
    records.mkdir()
    (records / "barn.json").write_text(json.dumps({"nav_launch": "/elsewhere/other.launch"}))
    argv = ["--src", str(VENDOR), "--worlds", "0:1:1", "--runs", "1", "--dir", str(records)]
    assert barn_bench.main(argv) == 2
    err = capsys.readouterr().err
    assert "no trial could start" in err
    assert not results.exists() and not (records / "out.txt").exists()


def test_a_trial_run_draws_its_figure_beside_its_results_and_leaves_the_page_s_alone(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))
    barn_bench = importlib.import_module("barn_bench")
    results = tmp_path / "results"
    monkeypatch.setenv("BENCH_RESULTS", str(results))
    page_figure = PACKAGE_ROOT / "docs" / "img" / "barn_success_by_world.png"
    before = page_figure.stat().st_mtime_ns
    barn = tmp_path / "src" / "the-barn-challenge"  # a catkin src's layout of the vendored packages
    barn.mkdir(parents=True)
    (barn / "jackal_helper").symlink_to(VENDOR / "jackal_helper")
    (barn / "res").symlink_to(VENDOR / "the-barn-challenge" / "res")
    records = tmp_path / "records"
    (records / "runs").mkdir(parents=True)
    (records / "runs" / "run_w000_r00.txt").write_text("0 1 0 0 23.3000 0.2917\n")
    assert barn_bench.main(["--src", str(barn.parent), "--from-records", str(records)]) == 0
    (written,) = results.glob("barn_bench_*.json")
    figure = results / "barn_success_by_world.png"
    assert json.loads(written.read_text())["image"] == str(figure)
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert page_figure.stat().st_mtime_ns == before
