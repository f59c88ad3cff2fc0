"""docs/performance.md is what bench/make_performance_page.py makes of bench/results/, and the
generator takes the newest result of each bench and the simple shape other benches write."""
from __future__ import annotations

import importlib.util
import json

from twil_control import PACKAGE_ROOT


def generator():
    spec = importlib.util.spec_from_file_location("make_performance_page", PACKAGE_ROOT / "bench/make_performance_page.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_page_is_generated_from_the_committed_results():
    assert generator().main(["--check"]) == 0, "regenerate it: .venv/bin/python bench/make_performance_page.py"


def test_the_page_shows_the_newest_result_and_tolerates_the_simple_shape(tmp_path):
    gen = generator()
    results = tmp_path / "results"
    results.mkdir()
    base = {"name": "cart_bench", "commit": "abc1234", "measures": "the update",
            "machine": {"cpu_model": "Test CPU", "cores": 2, "load_average_start": [1.5, 1.0, 0.5]},
            "figures": {"update_wall_p99_us": 40.0}, "units": {"update_wall_p99_us": "us"}}
    (results / "cart_bench_2026-01-01T000000Z.json").write_text(json.dumps({**base, "date": "2026-01-01T00:00:00+00:00"}))
    newer = {**base, "date": "2026-02-01T00:00:00+00:00", "figures": {"update_wall_p99_us": 17.7}}
    (results / "cart_bench_2026-02-01T000000Z.json").write_text(json.dumps(newer))
    # another engineer's bench: machine as text, nested figures, no units, measures or command
    (results / "chunk_bench_x.json").write_text(json.dumps({
        "name": "chunk_bench", "date": "2026-03-01", "commit": "def5678", "machine": "2-core VM, shared",
        "figures": {"messages_per_s": {"1s_chunks": 120000.0, "1MiB_chunks": 130000.0}, "rtf_ratio": 0.98}}))
    # the shape _common.write_result's first version wrote: "bench", top-level cpu/cores/load, records
    (results / "bridge_bench.json").write_text(json.dumps({
        "bench": "bridge_bench", "date": "2026-03-02T00:00:00+00:00", "commit": "0123abc", "machine": "vm",
        "cpu": "Other CPU", "cores": 2, "load": [9.5, 9.0, 8.0],
        "figures": {"kept": 1.0017, "runs": {"with": [{"rtf": 0.4}, {"rtf": 0.5}]}}}))
    (results / "broken.json").write_text("{not json")
    out = tmp_path / "performance.md"
    assert gen.main(["--results", str(results), "--out", str(out)]) == 0
    page = out.read_text()
    cart = page[page.index("### cart_bench"):page.index("###", page.index("### cart_bench") + 5)]
    assert "| update_wall_p99_us | 17.7 | us |" in cart and "| update_wall_p99_us | 40 |" not in cart
    assert "2026-02-01" in cart and "1 earlier result(s)" in cart
    assert "Test CPU; 2 cores; load average 1.5 / 1 / 0.5" in cart
    chunk = page[page.index("### chunk_bench"):]
    assert "| messages_per_s.1s_chunks | 120,000 |" in chunk and "| rtf_ratio | 0.98 |" in chunk
    assert "Machine: 2-core VM, shared." in chunk
    bridge = page[page.index("### bridge_bench"):page.index("### chunk_bench")]
    assert "Machine: vm Other CPU; 2 cores; load average 9.5 / 9 / 8." in bridge
    assert "| kept | 1.002 |" in bridge and "| runs.with | (2 records: see the result file) |" in bridge
    # every bench script has a section, run or not, with its command
    assert "### nav_goals" in page and ".venv/bin/python bench/nav_goals.py" in page
    # the anchors sit beside the benches they compare to
    slam = page[page.index("### slam_bench"):page.index("###", page.index("### slam_bench") + 5)]
    assert "64.7 ms" in slam and "179.6 ms" in slam
    assert gen.main(["--results", str(results), "--out", str(out), "--check"]) == 0
    out.write_text(page + "edited by hand\n")
    assert gen.main(["--results", str(results), "--out", str(out), "--check"]) == 1
