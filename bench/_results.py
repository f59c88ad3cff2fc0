"""A bench's figures as JSON under bench/results/: name, date, commit, machine, figures."""
from __future__ import annotations

import json
import os
import platform
import subprocess
import time
from pathlib import Path

import twil_control

RESULTS = Path(__file__).resolve().parent / "results"


def _commit() -> str:
    """The commit of the twil_control that was measured (``+dirty`` with uncommitted changes)."""
    root = Path(twil_control.__file__).resolve().parents[2]
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--", "src"],
                               capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def machine() -> dict:
    cpu = next((line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")), platform.processor())
    return {"host": platform.node(), "cpu": cpu, "cores": os.cpu_count(),
            "load_average_1min": round(os.getloadavg()[0], 2), "python": platform.python_version()}


def write(name: str, figures: dict, path: Path | None = None) -> Path:
    """Write bench/results/<name>.json (or `path`) and return where."""
    path = path or RESULTS / f"{name}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {"name": name, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "commit": _commit(),
              "machine": machine(), "figures": figures}
    path.write_text(json.dumps(record, indent=2) + "\n")
    return path
