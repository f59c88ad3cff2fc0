"""The order in which `pytest -n 2 --dist loadfile` hands test files to its workers: the costliest
first, so that the long end-to-end files run side by side from the start and the short ones fill
in at the end (pytest-xdist's own order, most tests first, leaves the files of one or two long
runs for last, one worker running them while the other has finished). Each file still runs whole
on one worker, its module fixtures built once.

COST_S: CPU seconds of each file over about 5 s (`make test` on two cores; the sum of its tests'
setup, call and teardown). Only the order depends on these figures: refresh them when a file's
cost changes much (`pytest --durations=0` shows where time goes). Unlisted files count
DEFAULT_TEST_S a test."""

from __future__ import annotations

from collections import OrderedDict
from pathlib import PurePath

from xdist.scheduler import LoadFileScheduling

COST_S = {
    "test_vendored_robots.py": 150,
    "test_barn.py": 108,
    "test_sweep_cluster.py": 105,
    "test_turtlebot3_world.py": 94,
    "test_wheel.py": 80,
    "test_slam_house.py": 55,
    "test_bag_launch.py": 48,
    "test_launch_stop.py": 41,
    "test_qbot.py": 35,
    "test_view_browser.py": 32,
    "test_gazebo_package.py": 30,
    "test_cart_linearizing.py": 27,
    "test_amcl_house.py": 23,
    "test_twil_sim_launch.py": 22,
    "test_nav_launch.py": 21,
    "test_sweep_failed_run.py": 20,
    "test_carmen.py": 17,
    "test_nav_backstepping.py": 17,
    "test_gmapping.py": 15,
    "test_convert_limits.py": 15,
    "test_foxglove_launch.py": 14,
    "test_mcap.py": 10,
    "test_demo.py": 9,
    "test_computed_torque.py": 8,
    "test_backstepping.py": 8,
    "test_view_panel.py": 8,
    "test_gazebo_worlds.py": 8,
    "test_gazebo_plugins.py": 8,
    "test_mesh_laser.py": 8,
    "test_launch_xml_twins.py": 7,
    "test_models.py": 7,
    "test_nav_dwa.py": 7,
    "test_amcl_global_tb3.py": 6,
    "test_ekf_localization.py": 6,
    "test_ros1_files.py": 6,
    "test_launch_messages.py": 6,
    "test_nav_planners.py": 5,
    "test_world_size.py": 5,
    "test_sweep_worker.py": 5,
    "test_layers.py": 5,
}

DEFAULT_TEST_S = 0.1


def cost(scope: str, tests: int) -> float:
    """The estimated seconds of a loadfile scope (a test file's path relative to the root)."""
    return COST_S.get(PurePath(scope).name, DEFAULT_TEST_S * tests)


class CostliestFileFirst(LoadFileScheduling):
    """xdist's loadfile scheduling with its queue of files sorted by `cost`, longest first."""

    _sorted = False

    def _assign_work_unit(self, node) -> None:
        if not self._sorted:  # the queue is complete by the first assignment
            units = sorted(self.workqueue.items(), key=lambda unit: -cost(unit[0], len(unit[1])))
            self.workqueue = OrderedDict(units)
            self._sorted = True
        super()._assign_work_unit(node)
