"""`make bench` and `make bench-long`: the benches of one set (bench/_catalog.py) one after the
other, each printing its figures and writing its result to bench/results/, then
docs/performance.md from the results. A bench that fails does not stop the others: the failed
ones are named at the end and the exit status is 1.

    .venv/bin/python bench/run_all.py [--long] [--only NAME ...]

The default set is the benches of a few minutes each; --long the runs of many minutes and those
that need something outside the repository. Set BENCH_NOTE to say what else the machine was
doing (it goes into every result file).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

from _catalog import PARTS, Bench

HERE = Path(__file__).resolve().parent
HELPERS = {
    "_catalog",
    "_common",
    "_result",
    "_barn_data",
    "_kinematic_nav",
    "_nav_episode",
    "_nav_worlds",
    "run_all",
    "make_performance_page",
}


def bench_set(long: bool) -> list[tuple[Bench, tuple[str, ...]]]:
    """The benches of a set with their arguments, in the page's order."""
    chosen = []
    for _, benches in PARTS:
        for bench in benches:
            args = bench.long_args if long else bench.args
            if args is not None:
                chosen.append((bench, args))
    return chosen


def uncatalogued() -> list[str]:
    """Bench scripts in bench/ that _catalog.PARTS does not list (they would never run)."""
    listed = {b.name for _, benches in PARTS for b in benches}
    return sorted({p.stem for p in HERE.glob("*.py")} - HELPERS - listed)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--long", action="store_true", help="the long set instead of the default one")
    ap.add_argument("--only", nargs="+", metavar="NAME", help="only these benches of the set")
    a = ap.parse_args(argv)
    missing = uncatalogued()
    if missing:
        print(
            f"run_all: bench/{', bench/'.join(m + '.py' for m in missing)} not in bench/_catalog.py: add "
            "each to a part of PARTS",
            file=sys.stderr,
        )
        return 2
    chosen = bench_set(a.long)
    if a.only:
        unknown = sorted(set(a.only) - {b.name for b, _ in chosen})
        if unknown:
            print(
                f"run_all: {', '.join(unknown)} not in the {'long' if a.long else 'default'} set; it has "
                f"{', '.join(b.name for b, _ in chosen)}",
                file=sys.stderr,
            )
            return 2
        chosen = [(b, args) for b, args in chosen if b.name in a.only]
    failed = []
    for bench, args in chosen:
        print(f"== {bench.name} {' '.join(args)}".rstrip(), flush=True)
        code = subprocess.call([sys.executable, str(HERE / f"{bench.name}.py"), *args], cwd=HERE.parent)
        if code != 0:
            print(f"== {bench.name} failed (exit {code})", flush=True)
            failed.append(f"{bench.name} (exit {code})")
    page = subprocess.call([sys.executable, str(HERE / "make_performance_page.py")], cwd=HERE.parent)
    if page != 0:
        failed.append("make_performance_page")
    if failed:
        print(f"run_all: failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    print(f"run_all: {len(chosen)} benches ran")
    return 0


if __name__ == "__main__":
    sys.exit(main())
