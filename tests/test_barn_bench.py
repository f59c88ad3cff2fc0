"""bench/barn_bench.py: a set that twil_control.barn refuses before any trial writes no result."""

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
