"""This project's navigation for BARN (launch/barn_move_base.launch: move_base with navfn and
TrajectoryPlanner on config/jackal_nav/) on the BARN test set, run as barn_bench.py runs
jackal_helper's DWA stack, beside Gazebo's DWA rows (res/dwa_out.txt): success, collision,
timeout and metric world by world, the wall and CPU time, and the figure of success by world.

    .venv/bin/python bench/barn_own_bench.py [--src CATKIN_SRC] [--worlds 0:300:6] [--runs 10]
        [--workers N] [--dir DIR] [--from-records DIR]

The arguments are barn_bench.py's.
"""

from __future__ import annotations

import sys

from _result import ROOT
from barn_bench import Stack, main

OWN = Stack(
    "barn_own_bench",
    "The BARN test set with this project's navigation (launch/barn_move_base.launch, config/jackal_nav/): "
    "success, collision, timeout and metric (report_test.py's arithmetic) beside Gazebo's DWA rows "
    "(res/dwa_out.txt), world by world, and the wall and CPU time of the whole set.",
    "this project's navigation",
    {"success": ">= 0.95", "metric": "> gazebo"},
    nav_launch=ROOT / "launch" / "barn_move_base.launch",
)

if __name__ == "__main__":
    sys.exit(main(stack=OWN))
