"""One build step pyproject.toml cannot declare: the catkin folders, which stay at the root of the
repository as in a catkin package, are copied into the wheel as ``twil_control/share/twil_control/``
(catkin's install space layout), where ``twil_control.PACKAGE_ROOT`` finds them once installed."""

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

#: What ``$(find twil_control)`` holds: the manifest and the folders launch files name.
CATKIN = ("package.xml", "launch", "config", "sim")


class BuildPyWithCatkin(build_py):
    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):  # an editable install reads the checkout itself
            return
        here = Path(__file__).parent
        share = Path(self.build_lib) / "twil_control" / "share" / "twil_control"
        for name in CATKIN:
            source, target = here / name, share / name
            if source.is_dir():
                shutil.copytree(source, target, dirs_exist_ok=True)
            else:
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(source, target)


setup(cmdclass={"build_py": BuildPyWithCatkin})
