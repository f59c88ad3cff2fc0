"""qbot through generated doorways and corridors with its own navigation files
(launch/qbot_navigation.launch.yaml: gmapping building the map, navfn, TrajectoryPlanner): goals reached.

    .venv/bin/python bench/door_bench.py --seeds 0 1 --jobs 2 --budget 1800   # at most 30 min of episodes
    .venv/bin/python bench/door_bench.py --widths 0.8 1.1 --angles 55 --kinds door --slam false

Each world (bench/_nav_worlds.py door_scenario): two rooms joined by a doorway or a 2.5 m corridor of
the given width, a cabinet beside the door, a plant pot behind it; the start 2.2-2.8 m before the
opening, the given angle off the wall's normal, the goal 1.5-2 m beyond. One process per episode;
reached = move_base SUCCEEDED (the robot's own estimate within its 0.5 m goal tolerance) with the
true pose within 0.55 m of the goal (5 cm for the SLAM estimate's error). --keep DIR keeps the
failures' bags and worlds; --from-rows scores the rows a run saved with --json, running nothing
(give the run's --seeds, --widths, ...: they name the episodes it planned).
"""

from __future__ import annotations

import argparse
import itertools
import json
import random
import sys
from collections import defaultdict
from pathlib import Path

import _nav_worlds as worlds
from _nav_episode import QBOT_LAUNCH, Episode, reached, run_many

WIDTHS = (0.8, 0.9, 1.0, 1.1, 1.2)
ANGLES = (0.0, 30.0, 55.0)
KINDS = ("door", "corridor")


def episodes(args) -> list[Episode]:
    # seed by seed, each seed's combinations in a fixed shuffled order: a run cut short by --budget
    # still spreads over the widths, angles and kinds
    out = []
    for seed in args.seeds:
        combos = list(itertools.product(args.kinds, args.widths, args.angles))
        random.Random(seed).shuffle(combos)
        for kind, width, angle in combos:
            sc = worlds.door_scenario(kind, width, angle, seed, furniture=not args.no_furniture)
            launch_args = {"slam": args.slam, **dict(a.split(":=", 1) for a in args.arg)}
            out.append(
                Episode(
                    sc,
                    args.launch,
                    launch_args,
                    args.timeout,
                    seed,
                    keep=args.keep,
                    keep_failures_only=not args.keep_all,
                )
            )
    return out


def line(r: dict) -> str:
    end = r.get("end_xy") or (None, None)
    where = f"({end[0]:5.2f},{end[1]:5.2f})" if end[0] is not None else "(  -  ,  -  )"
    t = r.get("time_s")
    return (
        f"{r['name']:28s} {'ok ' if r.get('reached') else 'NO '} {r.get('status', ''):>9s} "
        f"{t if t is not None else float('nan'):6.1f} s  final {r.get('final_m', float('nan')):5.2f} m  "
        f"end {where}  contacts {r.get('contacts', 0):3d}  "
        f"{r.get('sim_s', 0) / max(r.get('wall_s', 1), 1e-9):4.2f}x  {r.get('text') or r.get('error', '')}"
    )


def shares(rows: list[dict], key) -> dict:
    groups = defaultdict(list)
    for r in rows:
        groups[key(r)].append(bool(r.get("reached")))
    return {k: (sum(v), len(v)) for k, v in sorted(groups.items())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--widths", type=float, nargs="+", default=WIDTHS)
    ap.add_argument("--angles", type=float, nargs="+", default=ANGLES)
    ap.add_argument("--kinds", nargs="+", default=KINDS, choices=KINDS)
    ap.add_argument("--seeds", type=int, nargs="+", default=(0, 1))
    ap.add_argument("--slam", default="true", help="the launch's slam arg (false: rasterised map)")
    ap.add_argument("--no-furniture", action="store_true")
    ap.add_argument("--timeout", type=float, default=150.0, help="simulated seconds per episode")
    ap.add_argument("--jobs", type=int, default=1, help="episodes at a time")
    ap.add_argument("--launch", type=Path, default=QBOT_LAUNCH)
    ap.add_argument("--arg", action="append", default=[], help="another launch arg name:=value")
    ap.add_argument("--keep", type=Path, default=None, help="copy failed episodes' bags and worlds here")
    ap.add_argument("--keep-all", action="store_true", help="with --keep: every episode's")
    ap.add_argument("--json", type=Path, default=None, help="write the rows here too")
    ap.add_argument(
        "--budget", type=float, default=None, help="s of wall time: episodes not started by then are left out"
    )
    ap.add_argument(
        "--from-rows", type=Path, metavar="JSON", help="score these saved rows (--json), run nothing"
    )
    args = ap.parse_args(argv)
    from _common import BenchResult

    result = BenchResult(
        "door_bench",
        "qbot with its own navigation files (gmapping, navfn, TrajectoryPlanner) through generated "
        "doorways and corridors 0.8-1.2 m wide, approached at several angles past furniture: goals reached",
    )
    eps = episodes(args)
    if args.from_rows is not None:
        rows = json.loads(args.from_rows.read_text())
        for r in rows:  # scored again by this version's rule
            r["reached"] = reached(r, Episode.tolerance + Episode.localisation_allowance)
            print(line(r))
    else:
        print(
            f"{len(eps)} episodes: kinds {args.kinds}, widths {args.widths}, angles {args.angles}, "
            f"seeds {args.seeds}"
        )
        rows = run_many(eps, args.jobs, on_row=lambda r: print(line(r), flush=True), budget=args.budget)
    if len(rows) < len(eps):
        print(f"the wall-time budget ran out: {len(rows)} of {len(eps)} episodes run")
    n = len(rows)
    n_reached = sum(bool(r.get("reached")) for r in rows)
    contacts = sum(r.get("contacts", 0) for r in rows)
    print()
    for label, key in (
        ("kind", lambda r: r["kind"]),
        ("width", lambda r: f"{r['width']:.2f}"),
        ("angle", lambda r: f"{r['angle_deg']:g}"),
    ):
        print(f"by {label}: " + ", ".join(f"{k} {a}/{b}" for k, (a, b) in shares(rows, key).items()))
    sim = sum(r.get("sim_s", 0.0) for r in rows)
    wall = sum(r.get("wall_s", 0.0) for r in rows)
    share = n_reached / n if n else 0.0
    print(
        f"\nreached {n_reached}/{n} = {share:.3f} (target >= 0.95); contact samples {contacts}; "
        f"simulated {sim:.0f} s in {wall:.0f} s of episode wall time"
    )
    if args.from_rows is not None:  # the wall time above is the scoring's, not the run's
        result.add("episodes run", "earlier: scored from their saved rows (--from-rows)")
    result.add("episodes", n)
    result.add("episodes_planned", len(eps))
    result.add(
        "reached",
        share,
        "share of the goals",
        target=">= 0.95",
        headline="doors and corridors: goals reached",
    )
    result.add("contact_samples", contacts, "samples touching the world", target="== 0")
    for kind, (a, b) in shares(rows, lambda r: r["kind"]).items():
        result.add(f"reached_{kind}", a / b, "share", row=kind)
    for width, (a, b) in shares(rows, lambda r: f"{r['width']:.2f}").items():
        result.add(f"width_{width}", a / b, "share")
    result.add("simulated_s", sim, "s")
    result.add("episode_wall_s", wall, "s")
    result.records = {"rows": [{k: v for k, v in r.items() if k != "traceback"} for r in rows]}
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str))
    result.write()
    return 0 if share >= 0.95 else 1


if __name__ == "__main__":
    sys.exit(main())
