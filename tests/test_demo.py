"""`make demo` (python -m twil_control.demo): one run of the paper's controller ends with the
summary, the figure next to the bag and the HTML replay, and the summary says what `bag
analyze` measures on that bag."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from twil_control.bag.analyze import analyze_bag


@pytest.mark.slow
def test_demo_prints_the_summary_and_the_paths_of_its_figure_and_replay(tmp_path):
    out = subprocess.run(
        [sys.executable, "-m", "twil_control.demo", "--duration", "2", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    paths = dict(re.findall(r"^(bag|figure|replay): +(\S+)", out.stdout, re.M))
    assert set(paths) == {"bag", "figure", "replay"}, out.stdout
    bag, figure, replay = (
        tmp_path / p.split("/")[-1] for p in (paths["bag"], paths["figure"], paths["replay"])
    )
    assert bag.suffix == ".bag" and figure == bag.with_suffix(".png") and replay == bag.with_suffix(".html")
    assert figure.stat().st_size > 50_000
    html = replay.read_text()
    assert html.startswith("<!DOCTYPE html>") and "animation" in html and len(html) > 500_000
    m = analyze_bag(bag)["cart_controller"]
    assert f"{100 * m['final_position_error_m']:.2f} cm" in out.stdout
    assert f"{100 * m['final_position_error_odometry_m']:.2f} cm" in out.stdout
    assert f"peak wheel torques: right {m['peak_tau_right_Nm']:.2f} N m" in out.stdout
    assert "simulated 2.00 s" in out.stdout


def test_outputs_never_overwrite_an_earlier_run(tmp_path, monkeypatch):
    from twil_control import demo

    monkeypatch.setattr(demo.time, "strftime", lambda fmt: "2026-01-01-00-00-00")
    assert demo.output_stem(tmp_path).name == "demo_2026-01-01-00-00-00"
    (tmp_path / "demo_2026-01-01-00-00-00.html").write_text("")
    assert demo.output_stem(tmp_path).name == "demo_2026-01-01-00-00-00-1"
    (tmp_path / "demo_2026-01-01-00-00-00-1.bag.active").write_text("")
    assert demo.output_stem(tmp_path).name == "demo_2026-01-01-00-00-00-2"


def test_a_bad_launch_argument_is_exit_2_with_nothing_written(tmp_path):
    from twil_control.demo import main

    assert main(["--out", str(tmp_path), "no_such_arg:=1"]) == 2
    assert not list(tmp_path.iterdir())
