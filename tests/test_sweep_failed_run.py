"""A sweep records a run whose controller does not load as failed, with the reason, while the
runs around it are ok: a broken run never enters the table as a result."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from twil_control import PACKAGE_ROOT
from twil_control.sweep import load_sweep, run_sweep

pytestmark = [pytest.mark.slow, pytest.mark.cluster]

SWEEP = """
launch: launch/twil_cart_linearizing.launch.yaml
duration: 0.2
timeout: 120
list:
  - {gamma1: 0.4}
  - {gamma1: -1.0}   # refused by the controller: its spawner, required, stops the launch
  - {gamma1: 0.8}
"""


def test_a_bad_gain_run_is_failed_with_its_reason_and_the_others_ok(tmp_path):
    path = tmp_path / "gains.yaml"
    path.write_text(SWEEP)
    outcome = run_sweep(load_sweep(path), tmp_path / "out", workers=2, progress=False)
    frame = outcome.frame.set_index("gamma1")
    assert frame.loc[0.4, "status"] == "ok" and frame.loc[0.8, "status"] == "ok"
    bad = frame.loc[-1.0]
    assert bad["status"] == "failed"
    lines = (PACKAGE_ROOT / "launch/twil_cart_linearizing.launch.yaml").read_text().splitlines()
    line = next(i for i, text in enumerate(lines, 1) if "gains/gamma1" in text)  # where the arg sets it
    assert bad["error"] == (
        "exit code 2: error: required node /twil/ros_control/controller_spawner failed at t = 0.000 s: "
        "Failed to load cart_linearizing_controller: Initializing controller 'cart_linearizing_controller' "
        f"failed: launch/twil_cart_linearizing.launch.yaml:{line}: parameter "
        "'/twil/ros_control/cart_linearizing_controller/gains/gamma1' must be a finite number > 0 (got -1.0); "
        "the launch was not started"
    )
    assert pd.isna(bad["bag"])  # nothing ran: no bag
    assert not list((tmp_path / "out" / "runs").glob(f"run_{bad['run_id']}.bag*"))
    record = json.loads((tmp_path / "out" / "runs" / f"run_{bad['run_id']}.json").read_text())
    assert record["returncode"] == 2 and record["metrics"] is None
    for good in (0.4, 0.8):
        assert frame.loc[good, "odometry.duration_s"] > 0.15  # metrics of a bag that ran
    assert "runs: 3  ok: 2  failed: 1" in outcome.summary
