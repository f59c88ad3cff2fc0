"""A bench's result file: BenchResult writes bench/results/NAME_DATE.json in the schema of
bench/README.md (the figures with their units, targets and headline labels, the command, the
commit, and the machine with its load and steal). No Drake or project imports: the page
generator reads results with it."""

from __future__ import annotations

import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"


def results_folder() -> Path:
    """$BENCH_RESULTS (a trial run's results, kept out of the page's), else bench/results/."""
    return Path(os.environ.get("BENCH_RESULTS") or RESULTS)


def figure_path(name: str) -> Path:
    """Where a bench draws its figure: docs/img/ for the page's results, else beside the results
    (a trial run leaves the page's figures as they are); the folder is made if missing."""
    folder = results_folder()
    folder = ROOT / "docs" / "img" if folder.resolve() == RESULTS else folder
    folder.mkdir(parents=True, exist_ok=True)
    return folder / name


def git_commit(root: Path = ROOT) -> str:
    """The checkout's short commit, with "-dirty" when tracked files differ from it."""
    try:
        head = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=root, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


TARGET = re.compile(r"^(<=|>=|<|>|==) ?(-?\d+(?:\.\d+)?(?:e[-+]?\d+)?)$")


def target_met(target: str, value) -> bool | None:
    """Whether a number meets a target such as "< 100" or ">= 0.9" (None: not a number)."""
    m = TARGET.match(target)
    if m is None:
        raise ValueError(
            f"target {target!r}: write an operator (<, <=, >, >=, ==) and a number, e.g. '< 100'"
        )
    if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
        return None
    limit = float(m.group(2))
    return {
        "<": value < limit,
        "<=": value <= limit,
        ">": value > limit,
        ">=": value >= limit,
        "==": value == limit,
    }[m.group(1)]


def _put(tree: dict, path: list[str], value) -> None:
    for key in path[:-1]:
        tree = tree.setdefault(key, {})
    tree[path[-1]] = value


def portable_command(argv: list[str], root: Path = ROOT) -> str:
    """The bench's command line as another machine can read it: paths inside the repository made
    relative to it, any other absolute path replaced by its option's name in capitals (``--keep
    /tmp/x`` -> ``--keep KEEP``), as a result file must not carry this machine's folders."""

    def word(arg: str, option: str | None) -> str:
        if not arg.startswith("/"):
            return arg
        path = Path(arg)
        if path.is_relative_to(root):
            return str(path.relative_to(root)) or "."
        return (option or "--path").lstrip("-").replace("-", "_").upper()

    out, option = [], None
    for arg in argv:
        if arg.startswith("--") and "=" in arg:
            name, value = arg.split("=", 1)
            out.append(f"{name}={word(value, name)}")
            option = None
            continue
        out.append(word(arg, option))
        option = arg if arg.startswith("-") else None
    return " ".join(out)


class BenchResult:
    """One bench run's figures, written as bench/results/NAME_DATE.json (schema in bench/README.md):
    the figures, what they measure, the command, the commit, and the machine with its load and
    the hypervisor's steal over the run (the benches are ratios measured in one run because the
    machine may be shared: BENCH_NOTE says so in the file).

    A figure is a number or a short text; `row` puts it in a row of the bench's table (the
    figure's key is the column), `table` in a table of its own; units, targets and headline
    labels are kept in mappings of the same shape as the figures. `records` holds raw data
    (per-run records) that the page does not show."""

    def __init__(self, name: str, measures: str) -> None:
        self.name, self.measures = name, measures
        self.figures: dict = {}
        self.units: dict = {}
        self.targets: dict = {}
        self.headline: dict = {}
        self.records: dict = {}
        self.image: str | None = None  # a figure (PNG, path from the repository root) the page shows
        self.command = portable_command(
            [".venv/bin/python", f"bench/{Path(sys.argv[0]).name}", *sys.argv[1:]]
        )
        # the code that runs, taken now: a bench may write files of the checkout (its figure)
        self.commit = git_commit()
        self._load0, self._wall0 = os.getloadavg(), time.perf_counter()
        self._steal0 = host_steal_seconds()

    def add(
        self,
        key: str,
        value,
        unit: str = "",
        *,
        target: str | None = None,
        row: str | None = None,
        table: str | None = None,
        headline: str | bool = False,
    ) -> None:
        """A figure: a number (rounded to 4 significant digits) or a short text. `target`: what
        the figure must meet ("< 100", ">= 0.9"); `headline`: show it in the page's summary
        (a label, or True for the figure's own name)."""
        if table is not None and row is None:
            raise ValueError(f"{self.name}: figure {key!r} in table {table!r} needs a row")
        path = [p for p in (table, row) if p is not None] + [key]
        _put(self.figures, path, rounded(value))
        if unit:
            _put(self.units, path, unit)
        if target is not None:
            target_met(target, 0.0)  # a malformed target fails here, not on the page
            _put(self.targets, path, target)
        if headline:
            _put(self.headline, path, headline if isinstance(headline, str) else ", ".join(path))

    def write(self, folder: Path | None = None) -> Path:
        """Writes the file into `folder`, else `results_folder()`."""
        folder = Path(folder) if folder else results_folder()
        wall = time.perf_counter() - self._wall0
        now = datetime.datetime.now(datetime.UTC)
        data = {
            "name": self.name,
            "date": now.isoformat(timespec="seconds"),
            "commit": self.commit,
            "measures": self.measures,
            "command": self.command,
            "machine": {
                "hostname": platform.node(),
                "cpu_model": cpu_model(),
                "cores": os.cpu_count(),
                "load_average_start": [round(v, 2) for v in self._load0],
                "load_average_end": [round(v, 2) for v in os.getloadavg()],
                "steal_share": round(
                    (host_steal_seconds() - self._steal0) / (max(wall, 1e-9) * (os.cpu_count() or 1)), 3
                ),
                "python": platform.python_version(),
                "system": f"{platform.system()} {platform.machine()}",
                "note": os.environ.get("BENCH_NOTE", ""),
            },
            "wall_s": round(wall, 1),
            "figures": self.figures,
            "units": self.units,
            "targets": self.targets,
            "headline": self.headline,
        }
        if self.records:
            data["records"] = self.records
        if self.image:
            data["image"] = self.image
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / f"{self.name}_{now.strftime(DATE_FORMAT)}.json"
        path.write_text(json.dumps(data, indent=1) + "\n")
        print(f"results: {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")
        return path


DATE_FORMAT = "%Y-%m-%dT%H%M%SZ"  # in result file names


def rounded(value):
    """A figure as written: numbers to 4 significant digits, text as it is."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, np.number)):
        return float(f"{value:.4g}")
    return value


def host_steal_seconds() -> float:
    """CPU seconds the hypervisor has given other guests, summed over this machine's CPUs
    (/proc/stat's steal column): what a run's wall time holds beyond its own work."""
    with open("/proc/stat") as f:
        return int(f.readline().split()[8]) / os.sysconf("SC_CLK_TCK")
