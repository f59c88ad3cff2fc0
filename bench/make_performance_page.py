"""Writes docs/performance.md from the benches' result files (bench/results/*.json, written by
_result.BenchResult, schema in bench/README.md): a summary of every headline figure with its
target, then one section per part of _catalog.PARTS with each bench's newest figures, its
command, date, commit and the machine's load and steal, and the outside figures it compares to.

    .venv/bin/python bench/make_performance_page.py [--results bench/results] [--out docs/performance.md] [--check]

--check: exit 1 if the page differs from what the results give (a test runs it). A result file
that is not JSON or lacks a required field stops the page with an error naming the file.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from _catalog import BENCHES, PARTS, Bench
from _result import target_met

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
REQUIRED = ("name", "date", "commit", "command", "machine", "figures")

GAZEBO = (
    "Gazebo (classic) paces its physics to real time by default: the target real-time factor is "
    "real_time_update_rate x max_step_size, 1000 Hz x 1 ms = 1.0 "
    "([Gazebo classic, Modifying a world](https://classic.gazebosim.org/tutorials?cat=build_world&tut=modifying_world)). "
    "The launches here run as fast as they can (`--realtime R` paces them): a real-time factor above 1 "
    "is time Gazebo would not give back."
)
GMAPPING = (
    "The original C++ gmapping (OpenSLAM's GridSLAM as the ROS gmapping package uses it), built from "
    "source and run on the same Intel scans, synthesised odometry and parameters on a machine of this "
    "kind: **64.7 ms** of CPU per processed scan at 30 particles and **179.6 ms** at 80, where this "
    "project's filter took 11.8 and 29.2 ms in the same comparison, with the same accuracy. Compare the "
    "`intel 30 particles serial` and `intel 80 particles serial` rows (CPU per processed scan, one thread, "
    "as the original)."
)
AMCL = (
    "The original C++ amcl (ros-planning/navigation, noetic-devel): its pf, map and sensors libraries "
    "built from source with g++ -O2 (RelWithDebInfo, as ROS packages are built) and a replay driver that "
    "does what amcl_node's laserReceived does (the update test, the odometry and laser models, "
    "resampling, the heaviest cluster's mean), fed the same recorded scans, odometry at their stamps, "
    "map and parameters as this project's filter (`--export`; neither the libraries nor the driver are "
    "part of this repository), 10 seeds per start, in the same bench run (`--driver`). Its figures are the "
    "`C++ amcl` rows and `CXX_ANCHOR` in `bench/amcl_bench.py`: **3.40 ms** of CPU per filter update "
    "tracking and **5.86 ms** from global localisation, where this project's filter took 0.84 and 1.23 ms; "
    "95th-percentile pose error 12.5 cm against 9.4 cm."
)
TB3_GLOBAL = (
    "The original C++ amcl (the same libraries and replay driver as amcl_bench's anchor) on the global "
    "phase's recorded scans and odometry, 10 filter seeds per run (`CXX_GLOBAL` in "
    "`bench/tb3_world_bench.py`): within 0.3 m to the end in **93 of 100** replays, this project's "
    "filter in 100 of 100. A seed draws the same first particles on every run and the outcome follows "
    "the draw, so these weigh about ten draws each; over 50 seeds on two of the runs this project's "
    "filter found the robot in 88 of 100, which makes 8 of 10 in the bench likely, not certain. On the "
    "runs of a single 0.6 rad/s turn followed by 16 s east: 44 and 50 of 100, the rest on the world's "
    "half- and quarter-turn copies; with amcl.launch's diff model a slow turn hardly spreads the "
    "particles, so the first draw decides (docs/localization.md, Global localisation)."
)
NAV2 = (
    "Nav2's global planners on a roughly 75 m path (navigation2, `nav2_smac_planner/README.md`, Metrics): "
    "NavFn 146 ms, Smac 2D A* 243 ms, Hybrid-A* 144 ms, State Lattice 113 ms. Those plans are 15 times "
    "longer than the house's (median 5.3 m on a 0.05 m grid), so compare orders of magnitude, not ratios."
)
ANCHORS = {
    "twil_sim_rtf": [GAZEBO],
    "ros_control_bench": [GAZEBO],
    "cart_bench": [GAZEBO],
    "qbot_bench": [GAZEBO],
    "slam_bench": [GMAPPING, GAZEBO],
    "amcl_bench": [AMCL],
    "tb3_world_bench": [TB3_GLOBAL],
    "carmen_slam_eval": [
        (
            'Published gmapping on the same logs (Kümmerle et al., "On measuring the accuracy of SLAM algorithms", '
            "Autonomous Robots 2009): consecutive relations 0.031 ± 0.026 m and 1.3 ± 4.7° on Intel, 0.060 ± 0.049 m "
            "and 1.2 ± 1.3° on ACES."
        ),
        GMAPPING,
    ],
    "nav_bench": [NAV2, GAZEBO],
    "view_rtf": [GAZEBO],
}

# What the design of a measured part rests on: figures from one-off measurements that no bench
# repeats, kept here beside the bench that covers the part.
NOTES = {
    "amcl_bench": [
        (
            "Why the original's error is larger: amcl's map code centres cell i at origin + i x resolution, "
            "half a cell from where nav_msgs/OccupancyGrid puts it, so its estimates sit half a cell low in "
            "x and y. Replaying this run (3 seeds) with the map handed to it half a cell further on, its "
            "mean error fell from 6.5 to 4.6 cm and its mean signed error from (-4.8, -2.2) to (-2.5, -0.2) "
            "cm in (x, y); this project's, with the cells where the grid puts them, is 4.8 cm. Global localisation in the house, "
            "whose rooms look alike, settles in a wrong room in about half the seeds for both: over 12 seeds "
            "5 converged for the original and 7 for this project."
        ),
        (
            "The beam model (`laser_model_type: beam`, the same replay, 2 seeds run 3 times each, the two "
            "interleaved): 10.1 ms of CPU per update against the original's 21.0 ms (0.48), the same "
            "estimates as cell-by-cell ray casting: the walk jumps over free cells by the map's chessboard "
            "clearance, and the beam's direction comes from the particle's and the bearing's cosines, one "
            "cosine and sine per particle instead of per ray."
        ),
    ],
    "slam_bench": [
        (
            "Where a processed scan's time goes (the house scene, 80 particles, 640 beams): scan matching "
            "94-96%, registration into the particles' maps 3-5%, resampling under 0.1%. A particle's match is "
            "about 14 hill-climbing rounds and 33,000 beam-moves of 40-45 ns each, so 80 particles need about "
            "105 ms of CPU: at least 53 ms of wall time on two cores."
        ),
        (
            "Each beam-move is one chain of about 150 dependent instructions (cell keys, tile, cell, mean, "
            "distance, exponential): 32-bit cell words, per-cell neighbour blocks, branch-free loops and "
            "software prefetching each changed the matching time by less than the machine's noise. A "
            "vectorised pass (AVX2 gathers, one pose per pass) took 31-35 ns per beam against the scalar "
            "matcher's 28-30 ns per beam-move with a lookup and 19-20 ns from its cache: it works through all "
            "nine kernel cells of a beam where the scalar walk visits the set bits, 2.8-3.4 on average."
        ),
    ],
    "husky_rtf": [
        (
            "Where the Husky's simulated second goes (its LMS1xx, the square; perf samples of the running "
            "phase): Drake's plant step about 40% of the CPU, almost all of it the SAP contact solve (0.23 ms "
            "a 1 ms step on an idle core, 0.4 ms on this shared one: the contact problem built, a solver "
            "context allocated and solved at every step). The wheels' velocity interface is Drake's implicit "
            "joint PD, which only SAP honours, and the worlds ask for Gazebo's 1 ms step, so this is the floor "
            "without changing the physics. The rest is Python: the 1 kHz ros_control cycle (read, "
            "diff_drive_controller, write, cmd_vel_out at 1 kHz as publish_cmd asks), the EKF, the laser, the "
            "IMU and the recorder (about 2.5%)."
        ),
    ],
    "jackal_barn_rtf": [
        (
            "Where a BARN episode's running phase goes (a profile of the 20 s episode): Drake's plant "
            "step about a third, move_base a quarter (TrajectoryPlanner at 20 Hz, its footprint check "
            "the largest part; navfn's A* re-planning at 20 Hz), the 1 kHz ros_control cycle an "
            "eighth, then the recorder, the costmaps, the IMU and odometry, the laser and the EKF. "
            "A run keeps the memory it frees (launch/allocator.py): with glibc's defaults the "
            "episode faulted about 42,000 pages a simulated second, a tenth of its CPU."
        ),
    ],
    "ros_control_bench": [
        (
            "What the 1 kHz cycle's cost rests on: computed torque as one inverse-dynamics pass of the control "
            "model (14 us against 27 us for M, C qd and tau_g apart and the product); the adapter's write() as "
            "one compiled call (1.5 us against 10 us of numpy); messages built after the cycle, as "
            "realtime_tools' RealtimePublisher does (10-20 us inside it); the garbage collector frozen after "
            "start-up (a collection inside a cycle cost 130-180 us); the recorder serialising between "
            "simulated slices, not inside the cycle."
        ),
    ],
    "nav_bench": [
        (
            "What the navigation stack's costs rest on: OMPL's motion check is compiled (numpy's per-call "
            "overhead, about 100 us for the dozens of small array operations a motion needs, was most of "
            "the planning time); the local planner's rollouts are compiled (in numpy they cost about 1 ms a "
            "cycle in temporaries); a global costmap's static layer is resampled only when the map, the "
            "window or the map -> costmap transform moved (46 ms an update at 0.05 m on the house map); a plan's "
            "poses share one header (built one by one they cost about 50 us a pose)."
        ),
    ],
    "param_load_bench": [
        (
            "YAML is parsed by libyaml's scanner and parser under PyYAML's composer: five times faster than "
            "PyYAML's own on a large parameter file, with the same checks and the same lines."
        ),
    ],
    "view_rtf": [
        (
            "Why the view drops frames while the simulation is behind real time: a browser without a GPU "
            "renders WebGL in software on the simulation's cores, about 100 ms of CPU per frame for a "
            "750 x 500 canvas in headless Chromium on this host."
        ),
    ],
    "bag_bench": [
        (
            "Why the bag tools have their own reader: on a bag of 1.2 million messages rosbags' Reader took "
            "9-11 s to open (it parses every index entry into objects) and about 60-90 s to deserialise the "
            "million status messages an analysis reads, where `bag info` answered in 1.3-3 s and "
            "`bag analyze` in 9-17 s, Python start-up included."
        ),
    ],
    "world_build_bench": [
        (
            "A world is read a few hundred static models at a time into scratch plants: Drake's cost per "
            "model grows with the plant, and each plant has a fixed cost of its own; 200 models a plant "
            "measured best."
        ),
    ],
    "qbot_bench": [
        (
            "A small numpy array costs about 1 us from Python, so the 100 Hz hot paths compute in plain "
            "floats: tf lookups' quaternion products, and wheel odometry's mean of each side's wheel angles "
            "(np.mean of two values took about 5 us)."
        ),
        (
            "Point contact, not hydroelastic: the robots' wheels are spheres, and with hydroelastic contact "
            "the wheeled runs were 2 to 3 times slower and the wheels slipped 1 to 2%."
        ),
        (
            "The plant's output ports are computed when read (use_sampled_output_ports False) and "
            "the worlds' static models are anchored geometry: the bare qbot plant in the house took 184 us per "
            "simulated ms with 33 welded static bodies and 118 us anchored."
        ),
    ],
}


class ResultError(ValueError):
    """A result file the page cannot use: its message names the file and what is wrong."""


def load_results(folder: Path) -> dict[str, list[dict]]:
    """{bench name: its results, oldest first}; every file must be a JSON object with REQUIRED."""
    out: dict[str, list[dict]] = {}
    for path in sorted(folder.glob("*.json")):
        try:
            data = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as error:
            raise ResultError(f"{path}: not a readable JSON file ({error})") from None
        if not isinstance(data, dict):
            raise ResultError(f"{path}: not a JSON object")
        missing = [key for key in REQUIRED if key not in data]
        if missing:
            raise ResultError(
                f"{path}: missing {', '.join(missing)} (a result file needs {', '.join(REQUIRED)}: "
                "bench/README.md; write it with _result.BenchResult)"
            )
        if not isinstance(data["figures"], dict):
            raise ResultError(
                f"{path}: figures must be an object (figure name -> value), not "
                f"{type(data['figures']).__name__}"
            )
        for key in ("units", "targets", "headline"):
            if not isinstance(data.get(key, {}), dict):
                raise ResultError(f"{path}: {key} must be an object shaped like figures")
        figures = flatten(data["figures"])
        for key in ("targets", "headline"):
            stray = [".".join(p) for p in flatten(data.get(key, {})) if p not in figures]
            if stray:
                raise ResultError(f"{path}: {key} {', '.join(repr(s) for s in stray)} not among its figures")
        for where, target in flatten(data.get("targets", {})).items():
            try:
                target_met(str(target), 0.0)
            except ValueError as error:
                raise ResultError(f"{path}: the target of {'.'.join(where)!r}: {error}") from None
        data["_file"] = path.name
        out.setdefault(str(data["name"]), []).append(data)
    for results in out.values():
        results.sort(key=lambda d: (str(d["date"]), d["_file"]))
    return out


def flatten(tree, prefix: tuple = ()) -> dict[tuple, object]:
    """{path of keys: leaf} of a nested mapping."""
    if not isinstance(tree, dict):
        return {prefix: tree}
    flat = {}
    for key, value in tree.items():
        flat.update(flatten(value, prefix + (str(key),)))
    return flat


def fmt(value) -> str:
    if isinstance(value, bool) or value is None:
        return {True: "yes", False: "no", None: "-"}[value]
    if isinstance(value, list) and (
        any(isinstance(v, (dict, list)) for v in value) or len(value) > 8 or len(str(value)) > 200
    ):
        return f"({len(value)} records: see the result file)"
    if isinstance(value, str):
        value = value.replace("|", "\\|")
        return value[:197] + "..." if len(value) > 200 else value
    if isinstance(value, float):
        return f"{value:,.4g}" if abs(value) < 1e4 else f"{value:,.0f}"
    if isinstance(value, list):
        return ", ".join(fmt(v) for v in value)
    return str(value)


def verdict(target: str, value) -> str:
    met = target_met(target, value)
    return "-" if met is None else ("met" if met else "**not met**")


def cell(value, target: str | None) -> str:
    return fmt(value) + (f" (target {target}: {verdict(target, value)})" if target else "")


def load_text(load) -> str:
    if isinstance(load, list):
        return " / ".join(fmt(float(v)) if isinstance(v, (int, float)) else str(v) for v in load)
    return str(load)


def machine_line(machine) -> str:
    """CPU, cores, load average at the start and end, the host's steal, the note."""
    if not isinstance(machine, dict):
        return str(machine)
    parts = [
        str(machine.get("cpu_model", "CPU unknown")),
        f"{machine.get('cores', 'unknown')} cores",
        (
            f"load average {load_text(machine.get('load_average_start', 'unknown'))} at the start, "
            f"{load_text(machine.get('load_average_end', 'unknown'))} at the end"
        ),
    ]
    steal = machine.get("steal_share", "unknown")
    parts.append(
        f"host steal {100 * steal:.0f}%" if isinstance(steal, (int, float)) else f"host steal {steal}"
    )
    if machine.get("note"):
        parts.append(str(machine["note"]))
    return "; ".join(parts)


def headlines(name: str, result: dict) -> list[tuple]:
    """(label, value, unit, target) of each headline figure of a result."""
    figures, units, targets = (
        flatten(result["figures"]),
        flatten(result.get("units", {})),
        flatten(result.get("targets", {})),
    )
    rows = []
    for path, label in flatten(result.get("headline", {})).items():
        rows.append(
            (
                label if isinstance(label, str) else ", ".join(path),
                figures[path],
                units.get(path, ""),
                targets.get(path),
            )
        )
    return rows


def summary(catalog: list[Bench], results: dict[str, list[dict]]) -> list[str]:
    lines = ["| figure | value | target | met | bench | command |", "|---|---|---|---|---|---|"]
    for bench in catalog:
        if not results.get(bench.name):
            continue
        latest = results[bench.name][-1]
        for label, value, unit, target in headlines(bench.name, latest):
            shown = f"{fmt(value)} {unit}" if unit and value is not None else fmt(value)
            lines.append(
                f"| {fmt(label)} | {shown} | {target or ''} | "
                f"{verdict(target, value) if target else ''} | [{bench.name}](#{bench.name}) | "
                f"`{latest['command']}` |"
            )
    return lines


def figure_tables(result: dict) -> list[str]:
    """The figures: the plain ones as figure/value/unit rows, the rows (a mapping of values) as one
    table with a column per key, each table (a mapping of rows) under its own name."""
    figures, units, targets = result["figures"], result.get("units", {}), result.get("targets", {})
    plain = {k: v for k, v in figures.items() if not isinstance(v, dict)}
    rows = {
        k: v
        for k, v in figures.items()
        if isinstance(v, dict) and not any(isinstance(x, dict) for x in v.values())
    }
    tables = {k: v for k, v in figures.items() if k not in plain and k not in rows}
    lines = []
    if plain:
        lines += ["| figure | value | unit |", "|---|---|---|"]
        lines += [
            f"| {fmt(k)} | {cell(v, targets.get(k))} | {fmt(units.get(k, ''))} |" for k, v in plain.items()
        ]
        lines.append("")
    if rows:
        lines += row_table(rows, units, targets)
    for title, table in tables.items():
        lines += [f"*{title}*", ""]
        lines += row_table(table, units.get(title, {}), targets.get(title, {}))
    return lines


def row_table(rows: dict, units: dict, targets: dict) -> list[str]:
    columns = list(
        dict.fromkeys(c for row in rows.values() for c in (row if isinstance(row, dict) else {"value": row}))
    )
    unit_of = {
        c: next((units[r][c] for r in rows if isinstance(units.get(r), dict) and c in units[r]), "")
        for c in columns
    }
    header = ["", *(f"{c} ({unit_of[c]})" if unit_of[c] else c for c in columns)]
    lines = ["| " + " | ".join(fmt(h) for h in header) + " |", "|" + "---|" * len(header)]
    for name, row in rows.items():
        row = row if isinstance(row, dict) else {"value": row}
        row_targets = targets.get(name, {}) if isinstance(targets.get(name), dict) else {}
        lines.append(
            "| "
            + " | ".join(
                [fmt(name), *(cell(row[c], row_targets.get(c)) if c in row else "" for c in columns)]
            )
            + " |"
        )
    return lines + [""]


def how_run(bench: Bench) -> str:
    sets = [
        f"`make bench`{' with ' + ' '.join(bench.args) if bench.args else ''}"
        if bench.args is not None
        else "",
        f"`make bench-long`{' with ' + ' '.join(bench.long_args) if bench.long_args else ''}"
        if bench.long_args is not None
        else "",
    ]
    sets = [s for s in sets if s]
    text = "Runs in " + " and ".join(sets) if sets else "Runs by hand only"
    return text + (f"; needs {bench.needs}." if bench.needs else ".")


def section(bench: Bench, results: list[dict]) -> list[str]:
    lines = [f"### {bench.name}", ""]
    latest = results[-1] if results else None
    if latest is None:
        lines += [f"No results yet: run `.venv/bin/python bench/{bench.name}.py`. {how_run(bench)}", ""]
    else:
        if latest.get("measures"):
            lines += [f"**Measures:** {latest['measures']}", ""]
        lines += ["```bash", latest["command"], "```", "", how_run(bench), ""]
        lines += [
            f"**Latest:** {latest['date']}, commit `{latest['commit']}`"
            + (
                f", {fmt(latest['wall_s'])} s of wall time"
                if isinstance(latest.get("wall_s"), (int, float))
                else ""
            )
            + f". Machine: {machine_line(latest['machine'])}."
            + (f" {len(results) - 1} earlier result(s) in bench/results/." if len(results) > 1 else ""),
            "",
        ]
        if latest.get("image"):  # a path from the repository root; the page lives in docs/
            lines += [f"![{bench.name}]({os.path.relpath(ROOT / latest['image'], ROOT / 'docs')})", ""]
        lines += figure_tables(latest)
    for anchor in ANCHORS.get(bench.name, []):
        lines += [f"> **Beside it:** {anchor}", ""]
    for note in NOTES.get(bench.name, []):
        lines += [f"*Design figure:* {note}", ""]
    return lines


def render(results: dict[str, list[dict]]) -> str:
    parts = [(title, list(benches)) for title, benches in PARTS]
    others = sorted(set(results) - set(BENCHES))
    if others:
        parts.append(("Other benches", [Bench(name, args=None) for name in others]))
    catalog = [b for _, benches in parts for b in benches]
    lines = [
        "# Performance",
        "",
        (
            "<!-- Generated by bench/make_performance_page.py from bench/results/*.json: edit those or the "
            "generator, not this page. -->"
        ),
        "",
        (
            "Every benchmark in `bench/`, what it measures, how to run it, its latest figures and the machine "
            "they came from, and the outside figures it compares to. The benches measure ratios and costs in one "
            "run (a launch against the bare plant, one implementation against another): the machines these "
            "figures come from are shared virtual machines whose speed drifts by tens of per cent over minutes, "
            "so each result records the load average and the hypervisor's steal while it ran. A figure from a "
            "loaded machine is an upper bound on the cost."
        ),
        "",
        "```bash",
        "make bench                                     # the default set (bench/run_all.py), then this page",
        "make bench-long                                # the long set: runs of many minutes, or with outside needs",
        ".venv/bin/python bench/cart_bench.py           # one bench: prints its figures, writes bench/results/",
        ".venv/bin/python bench/make_performance_page.py   # this page from bench/results/",
        "```",
        "",
        "Result files: `bench/results/NAME_DATE.json`; their schema is in `bench/README.md`.",
        "",
        "## Summary",
        "",
        "The headline figures of each bench's newest result, with their targets where there is one.",
        "",
        *summary(catalog, results),
        "",
    ]
    for title, benches in parts:
        lines += [f"## {title}", ""]
        for bench in benches:
            lines += section(bench, results.get(bench.name, []))
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", type=Path, default=HERE / "results")
    ap.add_argument("--out", type=Path, default=ROOT / "docs/performance.md")
    ap.add_argument("--check", action="store_true", help="exit 1 if the page is not what the results give")
    a = ap.parse_args(argv)
    try:
        page = render(load_results(a.results))
    except ResultError as error:
        print(f"make_performance_page: {error}", file=sys.stderr)
        return 2
    if a.check:
        if not a.out.is_file() or a.out.read_text() != page:
            print(
                f"{a.out} is not what {a.results} gives: run bench/make_performance_page.py", file=sys.stderr
            )
            return 1
        return 0
    a.out.write_text(page)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
