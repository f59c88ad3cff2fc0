"""`make bench`: every benchmark but the long ones, one after the other, then docs/performance.md.

Each bench prints its figures and writes them to bench/results/ (bench/README.md). The long ones
(LONG: minutes each, a browser for view_rtf) run by hand; the page lists them with their commands.
Set BENCH_NOTE to say what else the machine was doing (it goes into every result file).
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
HELPERS = {"_common", "run_all", "make_performance_page"}
LONG = {"nav_goals", "carmen_slam_eval", "view_overhead", "view_rtf", "foxglove_overhead"}


def benches() -> list[str]:
    from make_performance_page import ORDER
    found = {p.stem for p in HERE.glob("*.py")} - HELPERS - LONG
    return [n for n in ORDER if n in found] + sorted(found - set(ORDER))


def main() -> int:
    failed = []
    for name in benches():
        print(f"== {name}", flush=True)
        if subprocess.call([sys.executable, str(HERE / f"{name}.py")], cwd=HERE) != 0:
            failed.append(name)
    subprocess.call([sys.executable, str(HERE / "make_performance_page.py")], cwd=HERE)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
