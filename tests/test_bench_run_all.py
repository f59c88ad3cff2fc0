"""bench/run_all.py (make bench, make bench-long): the set's benches with their arguments, past
a failing one, the failed named at the end with exit 1; a bench script the catalog lacks stops it."""

from __future__ import annotations

import importlib
import sys

import pytest

from twil_control import PACKAGE_ROOT

BENCH = PACKAGE_ROOT / "bench"


@pytest.fixture
def run_all(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))
    module = importlib.import_module("run_all")
    from _catalog import Bench

    log = tmp_path / "ran.txt"
    script = "import sys; open({log!r}, 'a').write(' '.join(sys.argv) + '\\n'); sys.exit({code})\n"
    for name, code in (("quick", 0), ("broken", 3), ("slow", 0), ("after", 0), ("make_performance_page", 0)):
        (tmp_path / f"{name}.py").write_text(script.format(log=str(log), code=code))
    monkeypatch.setattr(module, "HERE", tmp_path)
    monkeypatch.setattr(
        module,
        "PARTS",
        [
            ("one", [Bench("quick", args=("--duration", "1")), Bench("broken")]),
            ("two", [Bench("slow", args=None, long_args=("--large",)), Bench("after")]),
        ],
    )
    return module, log


def ran(log) -> list[str]:
    return [" ".join(a.rsplit("/", 1)[-1] for a in line.split()) for line in log.read_text().splitlines()]


def test_the_default_set_runs_past_a_failing_bench_and_names_it(run_all, capsys):
    module, log = run_all
    assert module.main([]) == 1
    assert ran(log) == ["quick.py --duration 1", "broken.py", "after.py", "make_performance_page.py"]
    assert "run_all: failed: broken (exit 3)" in capsys.readouterr().err


def test_the_long_set_and_only(run_all):
    module, log = run_all
    assert module.main(["--long"]) == 0
    assert ran(log) == ["slow.py --large", "make_performance_page.py"]
    log.unlink()
    assert module.main(["--only", "after"]) == 0
    assert ran(log) == ["after.py", "make_performance_page.py"]
    assert module.main(["--only", "slow"]) == 2  # not in the default set


def test_a_bench_script_missing_from_the_catalog_stops_it(run_all, capsys):
    module, log = run_all
    (module.HERE / "new_bench.py").write_text("")
    assert module.main([]) == 2
    assert "bench/new_bench.py not in bench/_catalog.py" in capsys.readouterr().err
    assert not log.exists()


def test_every_bench_script_is_in_the_catalog():
    sys.path.insert(0, str(BENCH))
    try:
        assert importlib.import_module("run_all").uncatalogued() == []
    finally:
        sys.path.remove(str(BENCH))
