"""Every benchmark, one after the other (`make bench`); each prints its own ratios and figures."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
BENCHES = ["twil_sim_rtf.py", "ros_control_bench.py", "cart_bench.py", "qbot_bench.py", "laser_bench.py",
           "bag_bench.py", "slam_bench.py", "nav_bench.py", "sweep_bench.py"]


def main() -> int:
    failed = []
    for name in BENCHES:
        if not (HERE / name).is_file():
            continue
        print(f"== {name}", flush=True)
        if subprocess.call([sys.executable, str(HERE / name)], cwd=HERE) != 0:
            failed.append(name)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
