"""Writes docs/performance.md from the benches' JSON results (bench/results/*.json, schema in
bench/README.md): per bench what it measures, its command, the latest figures and the machine
they came from, with the outside figures they compare to.

    .venv/bin/python bench/make_performance_page.py [--results bench/results] [--out docs/performance.md] [--check]

--check: exit 1 if the page differs from what the results give (a test runs it).
"""
from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
NOT_BENCHES = {"_common", "run_all", "make_performance_page"}

# The benches in the page's order; any other bench (a script here or a name in the results)
# follows, alphabetically.
ORDER = ["twil_sim_rtf", "ros_control_bench", "cart_bench", "qbot_bench", "gil_bench", "serialize_bench",
         "bag_bench", "laser_bench", "slam_bench", "carmen_slam_eval", "nav_bench", "nav_goals", "view_overhead",
         "view_rtf", "foxglove_overhead", "sweep_bench"]

GAZEBO = ("Gazebo (classic) paces its physics to real time by default: the target real-time factor is "
          "real_time_update_rate x max_step_size, 1000 Hz x 1 ms = 1.0 "
          "([Gazebo classic, Modifying a world](https://classic.gazebosim.org/tutorials?cat=build_world&tut=modifying_world)). "
          "The launches here run as fast as they can (`--realtime R` paces them): a real-time factor above 1 "
          "is time Gazebo would not give back.")
GMAPPING = ("The original C++ gmapping (OpenSLAM's GridSLAM as the ROS gmapping package uses it), built from "
            "source and run on the same Intel scans, synthesised odometry and parameters on a machine of this "
            "kind: **64.7 ms** of CPU per processed scan at 30 particles and **179.6 ms** at 80, where this "
            "project's filter took 11.8 and 29.2 ms in the same comparison, with the same accuracy. Compare the "
            "`intel 30 particles serial` and `intel 80 particles serial` rows (CPU per processed scan, one thread, "
            "as the original).")
NAV2 = ("Nav2's global planners on a roughly 75 m path (navigation2, `nav2_smac_planner/README.md`, Metrics): "
        "NavFn 146 ms, Smac 2D A* 243 ms, Hybrid-A* 144 ms, State Lattice 113 ms. Those plans are 15 times "
        "longer than the house's (median 5.3 m on a 0.05 m grid), so compare orders of magnitude, not ratios.")
ANCHORS = {
    "twil_sim_rtf": [GAZEBO], "ros_control_bench": [GAZEBO], "cart_bench": [GAZEBO], "qbot_bench": [GAZEBO],
    "slam_bench": [GMAPPING, GAZEBO], "carmen_slam_eval": [
        "Published gmapping on the same logs (Kümmerle et al., \"On measuring the accuracy of SLAM algorithms\", "
        "Autonomous Robots 2009): consecutive relations 0.031 ± 0.026 m and 1.3 ± 4.7° on Intel, 0.060 ± 0.049 m "
        "and 1.2 ± 1.3° on ACES.", GMAPPING],
    "nav_bench": [NAV2, GAZEBO], "view_rtf": [GAZEBO],
}

# What the design of a measured part rests on: figures from one-off measurements that no bench
# repeats, kept here beside the bench that covers the part.
NOTES = {
    "slam_bench": [
        "Where a processed scan's time goes (the house scene, 80 particles, 640 beams): scan matching "
        "94-96%, registration into the particles' maps 3-5%, resampling under 0.1%. A particle's match is "
        "about 14 hill-climbing rounds and 33,000 beam-moves of 40-45 ns each, so 80 particles need about "
        "105 ms of CPU: at least 53 ms of wall time on two cores.",
        "Each beam-move is one chain of about 150 dependent instructions (cell keys, tile, cell, mean, "
        "distance, exponential): 32-bit cell words, per-cell neighbour blocks, branch-free loops and "
        "software prefetching each changed the matching time by less than the machine's noise. A "
        "vectorised pass (AVX2 gathers, one pose per pass) took 31-35 ns per beam against the scalar "
        "matcher's 28-30 ns per beam-move with a lookup and 19-20 ns from its cache: it works through all "
        "nine kernel cells of a beam where the scalar walk visits the set bits, 2.8-3.4 on average.",
    ],
    "ros_control_bench": [
        "What the 1 kHz cycle's cost rests on: computed torque as one inverse-dynamics pass of the control "
        "model (14 us against 27 us for M, C qd and tau_g apart and the product); the adapter's write() as "
        "one compiled call (1.5 us against 10 us of numpy); messages built after the cycle, as "
        "realtime_tools' RealtimePublisher does (10-20 us inside it); the garbage collector frozen after "
        "start-up (a collection inside a cycle cost 130-180 us); the recorder serialising between "
        "simulated slices, not inside the cycle.",
    ],
    "qbot_bench": [
        "The plant's output ports are computed when read (use_sampled_output_ports False) and "
        "the worlds' static models are anchored geometry: the bare qbot plant in the house took 184 us per "
        "simulated ms with 33 welded static bodies and 118 us anchored.",
    ],
}


def load_results(folder: Path) -> dict[str, list[dict]]:
    """{bench name: its results, oldest first}. Tolerates the simple shape {name, date, commit,
    machine (text or mapping), figures (numbers, text, or nested mappings)}."""
    out: dict[str, list[dict]] = {}
    for path in sorted(folder.glob("*.json")):
        try:
            data = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as error:
            print(f"skipping {path.name}: {error}", file=sys.stderr)
            continue
        if not isinstance(data, dict):
            print(f"skipping {path.name}: not a JSON object", file=sys.stderr)
            continue
        name = str(data.get("name") or data.get("bench") or path.stem.split("_20")[0])
        data["_file"] = path.name
        out.setdefault(name, []).append(data)
    for results in out.values():
        results.sort(key=lambda d: (str(d.get("date", "")), d["_file"]))
    return out


def flatten(figures, prefix: str = "") -> dict[str, object]:
    if not isinstance(figures, dict):
        return {prefix or "value": figures}
    flat = {}
    for key, value in figures.items():
        name = f"{prefix}.{key}" if prefix else str(key)
        flat.update(flatten(value, name) if isinstance(value, dict) else {name: value})
    return flat


META = {"name", "bench", "date", "commit", "machine", "cpu", "cores", "load", "measures", "command", "units",
        "wall_s", "_file"}


def figures_of(result: dict) -> dict:
    """A result's figures: its `figures`, or (a file without that key) every key but the metadata."""
    figures = result.get("figures")
    return figures if figures is not None else {k: v for k, v in result.items() if k not in META}


def fmt(value) -> str:
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, list) and (any(isinstance(v, (dict, list)) for v in value) or len(value) > 8
                                    or len(str(value)) > 200):
        return f"({len(value)} records: see the result file)"
    if isinstance(value, str) and len(value) > 200:
        return value[:197] + "..."
    if isinstance(value, float):
        return f"{value:,.4g}" if abs(value) < 1e5 else f"{value:,.0f}"
    if isinstance(value, list):
        return ", ".join(fmt(v) for v in value)
    return str(value)


def machine_line(machine, result: dict | None = None) -> str:
    """The machine of a result: its `machine` mapping, or a name with top-level cpu, cores, load."""
    if not isinstance(machine, dict):
        result = result or {}
        machine = {"cpu_model": " ".join(str(v) for v in (machine, result.get("cpu")) if v) or "not recorded",
                   "cores": result.get("cores"), "load_average": result.get("load")}
    parts = [machine.get("cpu_model") or machine.get("cpu"), f"{machine['cores']} cores" if machine.get("cores") else None]
    load = machine.get("load_average_start") or machine.get("load_average")
    if load:
        parts.append("load average " + " / ".join(fmt(float(v)) for v in load)
                     + (f" (end {' / '.join(fmt(float(v)) for v in machine['load_average_end'])})"
                        if machine.get("load_average_end") else ""))
    if machine.get("steal_share") is not None:
        parts.append(f"host steal {100 * float(machine['steal_share']):.0f}%")
    if machine.get("note"):
        parts.append(str(machine["note"]))
    return "; ".join(p for p in parts if p)


def script_summary(name: str) -> str:
    """The first paragraph of the bench script's docstring, if the script exists."""
    path = HERE / f"{name}.py"
    if not path.is_file():
        return ""
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return " ".join(doc.split("\n\n")[0].split())


def section(name: str, results: list[dict]) -> list[str]:
    lines = [f"### {name}", ""]
    latest = results[-1] if results else None
    what = (latest or {}).get("measures") or script_summary(name)
    if what:
        lines += [f"**Measures:** {what}", ""]
    command = (latest or {}).get("command") or (f".venv/bin/python bench/{name}.py" if (HERE / f"{name}.py").is_file()
                                                else "")
    if command:
        lines += ["```bash", command, "```", ""]
    if latest is None:
        lines += ["No results yet: run the command.", ""]
    else:
        lines += [f"**Latest:** {latest.get('date', 'undated')}, commit `{latest.get('commit', '?')}`"
                  + (f", {fmt(latest['wall_s'])} s of wall time" if latest.get("wall_s") is not None else "")
                  + f". Machine: {machine_line(latest.get('machine'), latest)}."
                  + (f" {len(results) - 1} earlier result(s) in bench/results/." if len(results) > 1 else ""), ""]
        units = latest.get("units") if isinstance(latest.get("units"), dict) else {}
        figures = flatten(figures_of(latest))
        if figures:
            lines += ["| figure | value | unit |", "|---|---|---|"]
            lines += [f"| {key} | {fmt(value)} | {units.get(key, '')} |" for key, value in figures.items()]
            lines.append("")
    for anchor in ANCHORS.get(name, []):
        lines += [f"> **Beside it:** {anchor}", ""]
    for note in NOTES.get(name, []):
        lines += [f"*Design figure:* {note}", ""]
    return lines


def render(results: dict[str, list[dict]]) -> str:
    scripts = {p.stem for p in HERE.glob("*.py") if p.stem not in NOT_BENCHES}
    names = [n for n in ORDER if n in scripts or n in results]
    names += sorted((scripts | set(results)) - set(names))
    lines = [
        "# Performance",
        "",
        "<!-- Generated by bench/make_performance_page.py from bench/results/*.json: edit those or the "
        "generator, not this page. -->",
        "",
        "Every benchmark in `bench/`, what it measures, how to run it, its latest figures and the machine "
        "they came from, and the outside figures it compares to. The benches measure ratios and costs in one "
        "run (a launch against the bare plant, one implementation against another): the machines these "
        "figures come from are shared virtual machines whose speed drifts by tens of per cent over minutes, "
        "so each result records the load average and the hypervisor's steal while it ran. A figure from a "
        "loaded machine is an upper bound on the cost.",
        "",
        "```bash",
        "make bench                                     # the default set (bench/run_all.py), then this page",
        ".venv/bin/python bench/cart_bench.py           # one bench: prints its figures, writes bench/results/",
        ".venv/bin/python bench/make_performance_page.py   # this page from bench/results/",
        "```",
        "",
        "Result files: `bench/results/NAME_DATE.json`; their schema is in `bench/README.md`.",
        "",
        "## Summary",
        "",
        "| bench | latest | commit | results |",
        "|---|---|---|---|",
    ]
    for name in names:
        rs = results.get(name, [])
        lines.append(f"| [{name}](#{name}) | {rs[-1].get('date', 'undated') if rs else 'not run'} | "
                     f"{rs[-1].get('commit', '?') if rs else ''} | {len(rs)} |")
    lines += ["", "## Benchmarks", ""]
    for name in names:
        lines += section(name, results.get(name, []))
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", type=Path, default=HERE / "results")
    ap.add_argument("--out", type=Path, default=ROOT / "docs/performance.md")
    ap.add_argument("--check", action="store_true", help="exit 1 if the page is not what the results give")
    a = ap.parse_args(argv)
    page = render(load_results(a.results))
    if a.check:
        if not a.out.is_file() or a.out.read_text() != page:
            print(f"{a.out} is not what {a.results} gives: run bench/make_performance_page.py", file=sys.stderr)
            return 1
        return 0
    a.out.write_text(page)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
