"""Every bench, in the performance page's order, grouped in its parts, and how run_all.py runs it:
`make bench` runs the default set (`args`), `make bench-long` the long set (`long_args`): the
runs of many minutes, or that need something outside the repository (`needs`). A bench in
neither set runs by hand only (its arguments name folders outside the repository)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Bench:
    name: str  # the script bench/NAME.py and its results' name
    args: tuple[str, ...] | None = ()  # arguments in the default set; None: not in it
    long_args: tuple[str, ...] | None = None  # arguments in the long set; None: not in it
    needs: str = ""  # what the run needs beyond the checkout and its venv


PARTS: list[tuple[str, list[Bench]]] = [
    (
        "Real time and the 1 kHz loop",
        [
            Bench("twil_sim_rtf"),
            Bench("ros_control_bench"),
            Bench("cart_bench"),
            Bench("qbot_bench"),
            Bench("gil_bench"),
            Bench("fall_monitor_bench"),
        ],
    ),
    ("Recording", [Bench("bag_chunk_bench"), Bench("bag_bench")]),
    ("Laser and SLAM", [Bench("laser_bench"), Bench("slam_bench"), Bench("carmen_slam_eval")]),
    (
        "Localisation",
        [Bench("amcl_bench"), Bench("ekf_bench"), Bench("tb3_world_bench", args=None, long_args=())],
    ),
    (
        "Navigation",
        [
            Bench("nav_bench"),
            Bench("nav_goals", args=None, long_args=()),
            Bench(
                "barn_bench",
                args=None,
                long_args=(),
                needs="a catkin src with the-barn-challenge, jackal and jackal_simulator (melodic-devel), "
                "given with --src or on ROS_PACKAGE_PATH",
            ),
            Bench(
                "barn_own_bench",
                args=None,
                long_args=(),
                needs="a catkin src with the-barn-challenge, jackal and jackal_simulator (melodic-devel), "
                "given with --src or on ROS_PACKAGE_PATH",
            ),
            Bench("door_bench", args=None, long_args=()),
            Bench("clutter_bench", args=None),
        ],
    ),
    (
        "View, Foxglove and sweeps",
        [
            Bench("view_overhead"),
            Bench("view_rtf", needs="Chromium and ChromeDriver (`make browser`)"),
            Bench("foxglove_overhead"),
            Bench("sweep_bench"),
        ],
    ),
    ("World size", [Bench("world_build_bench", long_args=("--large",))]),
    ("Parameters", [Bench("param_load_bench")]),
    ("Formulas written once: before and after", [Bench("formulas_ab", args=None, long_args=())]),
    (
        "Robot descriptions from other packages",
        [
            Bench("tryout_robots", args=None, long_args=("--goals", "3")),
            Bench("husky_rtf", args=None, long_args=()),
            Bench("jackal_barn_rtf", args=None, long_args=()),
            Bench(
                "physics_step_bench",
                args=None,
                long_args=(),
                needs="for BARN worlds other than the vendored 0 and 6, a catkin src with the-barn-challenge, "
                "jackal and jackal_simulator (melodic-devel), given with --barn-src",
            ),
        ],
    ),
]

BENCHES: dict[str, Bench] = {b.name: b for _, benches in PARTS for b in benches}
