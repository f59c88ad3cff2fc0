"""docs/performance.md is what bench/make_performance_page.py makes of bench/results/: the
newest result of each bench, its headline figures with their targets in the summary, each bench
in its part of bench/_catalog.py; a result file it cannot use stops it with the file's name."""

from __future__ import annotations

import importlib
import json
import sys

import pytest

from twil_control import PACKAGE_ROOT

BENCH = PACKAGE_ROOT / "bench"


@pytest.fixture(scope="module")
def gen():
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("make_performance_page")
    finally:
        sys.path.remove(str(BENCH))


def result(name: str, date: str, **overrides) -> dict:
    data = {
        "name": name,
        "date": date,
        "commit": "abc1234",
        "measures": "the update",
        "command": f".venv/bin/python bench/{name}.py --duration 2",
        "machine": {
            "cpu_model": "Test CPU",
            "cores": 2,
            "load_average_start": [1.5, 1.0, 0.5],
            "load_average_end": [2.0, 1.1, 0.5],
            "steal_share": 0.031,
            "note": "shared",
        },
        "wall_s": 12.0,
        "figures": {},
        "units": {},
        "targets": {},
        "headline": {},
    }
    data.update(overrides)
    return data


def write(folder, name: str, data: dict) -> None:
    (folder / name).write_text(json.dumps(data))


def test_the_committed_page_is_generated_from_the_committed_results(gen):
    assert gen.main(["--check"]) == 0, "regenerate it: .venv/bin/python bench/make_performance_page.py"


def test_every_committed_result_is_in_the_schema_and_every_bench_in_the_catalog(gen):
    import _catalog

    results = gen.load_results(BENCH / "results")  # raises on a file without a required field
    scripts = {p.stem for p in BENCH.glob("*.py") if not p.stem.startswith("_")} - {
        "run_all",
        "make_performance_page",
    }
    assert scripts == set(_catalog.BENCHES)
    assert set(results) <= set(_catalog.BENCHES)
    for name, rs in results.items():
        for r in rs:
            assert isinstance(r["machine"], dict) and "load_average_start" in r["machine"], r["_file"]
            assert r["_file"].startswith(f"{name}_20"), r["_file"]


def test_committed_commands_name_no_folder_of_the_machine_that_ran_them(gen):
    for rs in gen.load_results(BENCH / "results").values():
        for r in rs:
            assert not any(w.startswith("/") for w in r["command"].split()), (r["_file"], r["command"])


def test_a_command_keeps_repository_paths_relative_and_names_other_paths_by_their_option(gen):
    import _result

    root = _result.ROOT
    argv = [".venv/bin/python", "bench/door_bench.py", "--keep", "/tmp/doors", "--json=/tmp/d/rows.json"]
    argv += ["--launch", str(root / "launch" / "x.launch"), "--seeds", "0", "1", "/srv/catkin"]
    assert _result.portable_command(argv, root) == (
        ".venv/bin/python bench/door_bench.py --keep KEEP --json=JSON --launch launch/x.launch "
        "--seeds 0 1 PATH"
    )


def test_the_summary_has_each_headline_with_its_target_and_the_newest_result(gen, tmp_path):
    results = tmp_path / "results"
    results.mkdir()
    old = result(
        "cart_bench",
        "2026-01-01T00:00:00+00:00",
        figures={"update(), wall": {"p99": 140.0}},
        units={"update(), wall": {"p99": "us"}},
        targets={"update(), wall": {"p99": "< 100"}},
        headline={"update(), wall": {"p99": "cart p99"}},
    )
    write(results, "cart_bench_2026-01-01T000000Z.json", old)
    new = result(
        "cart_bench",
        "2026-02-01T00:00:00+00:00",
        figures={
            "launch_rtf": 0.45,
            "update(), wall": {"median": 17.0, "p99": 74.7},
            "cycle, wall": {"median": 63.0, "p99": 120.5},
        },
        units={
            "launch_rtf": "x real time",
            "update(), wall": {"median": "us", "p99": "us"},
            "cycle, wall": {"p99": "us"},
        },
        targets={"update(), wall": {"p99": "< 100"}, "cycle, wall": {"p99": "< 100"}},
        headline={"update(), wall": {"p99": "cart p99"}, "cycle, wall": {"p99": "cart cycle p99"}},
    )
    write(results, "cart_bench_2026-02-01T000000Z.json", new)
    write(
        results,
        "laser_bench_2026-01-05T000000Z.json",
        result(
            "laser_bench",
            "2026-01-05T00:00:00+00:00",
            figures={"scans_per_s": 1500.0},
            targets={"scans_per_s": ">= 2000"},
            headline={"scans_per_s": True},
        ),
    )
    out = tmp_path / "performance.md"
    assert gen.main(["--results", str(results), "--out", str(out)]) == 0
    page = out.read_text()
    summary = page[page.index("## Summary") : page.index("## Real time")]
    command = "`.venv/bin/python bench/cart_bench.py --duration 2`"
    assert f"| cart p99 | 74.7 us | < 100 | met | [cart_bench](#cart_bench) | {command} |" in summary
    assert "| cart cycle p99 | 120.5 us | < 100 | **not met** |" in summary
    assert "| True | 1,500 | >= 2000 | **not met** | [laser_bench](#laser_bench)" not in summary
    assert "| scans_per_s | 1,500 | >= 2000 | **not met** | [laser_bench](#laser_bench)" in summary
    assert "140" not in summary
    # the bench's section: in its part, the newest figures as a table of rows, the machine's load and steal
    part = page[page.index("## Real time and the 1 kHz loop") : page.index("## Recording")]
    cart = part[part.index("### cart_bench") : part.index("### qbot_bench")]
    assert "| launch_rtf | 0.45 | x real time |" in cart
    assert "|  | median (us) | p99 (us) |" in cart
    assert "| update(), wall | 17 | 74.7 (target < 100: met) |" in cart
    assert "| cycle, wall | 63 | 120.5 (target < 100: **not met**) |" in cart
    assert (
        "2026-02-01T00:00:00+00:00, commit `abc1234`, 12 s of wall time" in cart
        and "1 earlier result(s)" in cart
    )
    assert (
        "Machine: Test CPU; 2 cores; load average 1.5 / 1 / 0.5 at the start, 2 / 1.1 / 0.5 at the end; "
        "host steal 3%; shared."
    ) in cart
    # a bench without results still has its section, saying how it runs
    assert (
        "### nav_goals\n\nNo results yet: run `.venv/bin/python bench/nav_goals.py`. Runs in `make bench-long`."
        in page
    )
    assert gen.main(["--results", str(results), "--out", str(out), "--check"]) == 0
    out.write_text(page + "edited by hand\n")
    assert gen.main(["--results", str(results), "--out", str(out), "--check"]) == 1


@pytest.mark.parametrize(
    "content, message",
    [
        (
            {"name": "cart_bench", "date": "2026-01-01", "commit": "abc", "machine": "vm", "figures": {}},
            "missing command",
        ),
        (
            {
                "bench": "world_build",
                "date": "2026-01-01",
                "commit": "abc",
                "command": "x",
                "machine": "vm",
                "figures": {},
            },
            "missing name",
        ),
        (
            {
                "name": "cart_bench",
                "date": "2026-01-01",
                "commit": "abc",
                "command": "x",
                "machine": "vm",
                "figures": [1],
            },
            "figures must be an object",
        ),
        (
            {
                "name": "cart_bench",
                "date": "2026-01-01",
                "commit": "abc",
                "command": "x",
                "machine": "vm",
                "figures": {"a": 1.0},
                "headline": {"b": True},
            },
            "headline 'b' not among its figures",
        ),
        (
            {
                "name": "cart_bench",
                "date": "2026-01-01",
                "commit": "abc",
                "command": "x",
                "machine": "vm",
                "figures": {"a": {"p99": 1.0}},
                "targets": {"a": {"p99": "under 100"}},
            },
            "the target of 'a.p99': target 'under 100': write an operator",
        ),
        ("{not json", "not a readable JSON file"),
    ],
)
def test_a_result_file_it_cannot_use_is_named_with_what_is_wrong(gen, tmp_path, capsys, content, message):
    results = tmp_path / "results"
    results.mkdir()
    write(
        results,
        "twil_sim_rtf_2026-01-01T000000Z.json",
        result("twil_sim_rtf", "2026-01-01", figures={"rtf": 1.0}),
    )
    bad = results / "cart_bench_2026-01-02T000000Z.json"
    bad.write_text(content if isinstance(content, str) else json.dumps(content))
    out = tmp_path / "performance.md"
    assert gen.main(["--results", str(results), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and message in err
    assert not out.exists()
