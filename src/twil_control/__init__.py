"""twil_control: a ROS 1 style workspace for TWIL + WAM and qbot, simulated in Drake."""

from pathlib import Path

__version__ = "0.1.0"

#: The package root as catkin sees it (the folder holding package.xml): $(find twil_control).
PACKAGE_ROOT = Path(__file__).resolve().parents[2]
