"""bench/door_bench.py's scoring: reached = move_base SUCCEEDED with the true pose within the goal
tolerance (0.5 m) plus the 5 cm allowed for the SLAM estimate's error; --from-rows scores saved
rows without running an episode."""

from __future__ import annotations

import importlib
import json

from twil_control import PACKAGE_ROOT

BENCH = PACKAGE_ROOT / "bench"


def test_saved_rows_are_scored_by_the_goal_tolerance_plus_the_localisation_allowance(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.syspath_prepend(str(BENCH))
    door_bench = importlib.import_module("door_bench")
    monkeypatch.setenv("BENCH_RESULTS", str(tmp_path / "results"))
    common = {"kind": "door", "width": 1.0, "angle_deg": 30.0, "contacts": 0, "sim_s": 40.0, "wall_s": 50.0}
    rows = [
        {"name": "a", "status": "SUCCEEDED", "final_m": 0.503, **common},  # the estimate 2 cm off
        {"name": "b", "status": "SUCCEEDED", "final_m": 0.58, **common},  # beyond the allowance
        {"name": "c", "status": "ABORTED", "final_m": 0.2, **common},
        {"name": "d", "status": "SUCCEEDED", "final_m": 0.31, **common},
    ]
    saved = tmp_path / "rows.json"
    saved.write_text(json.dumps(rows))
    door_bench.main(["--from-rows", str(saved), "--seeds", "0", "--kinds", "door", "--widths", "1.0"])
    assert "reached 2/4 = 0.500" in capsys.readouterr().out
    (result,) = (tmp_path / "results").glob("door_bench_*.json")
    data = json.loads(result.read_text())
    assert data["figures"]["reached"] == 0.5
    assert [r["reached"] for r in data["records"]["rows"]] == [True, False, False, True]
