"""twil_control: a ROS 1 style workspace for TWIL + WAM and qbot, simulated in Drake."""

from importlib.resources import files
from pathlib import Path

__version__ = "0.1.0"


def _package_root() -> Path:
    """The installed package's copy of the catkin folders (``share/twil_control``, put there by
    the wheel's build), else the checkout that holds this source tree (an editable install)."""
    installed = files(__name__) / "share" / __name__
    if isinstance(installed, Path) and (installed / "package.xml").is_file():
        return installed.resolve()
    return Path(__file__).resolve().parents[2]


#: The package root as catkin sees it (the folder holding package.xml, launch/, config/, sim/):
#: $(find twil_control).
PACKAGE_ROOT = _package_root()
