"""A wrong-way import breaks the contract that names its rule (import-linter, pyproject.toml).

That the contracts, ruff and the types hold on the tree itself is `make lint` and `make types`,
which `make test` runs before the suite. The tool runs as a user runs it (docs/layers.md), from
a copy of the package root, with the venv's executable: a failure prints its report."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from twil_control import PACKAGE_ROOT

BIN = Path(sys.executable).parent


def _run(argv: list[str], cwd: Path, pythonpath: Path | None = None) -> subprocess.CompletedProcess:
    exe = BIN / argv[0]
    assert exe.exists(), f"{exe} is missing: install the test extras (pip install -e '.[test]')"
    env = dict(os.environ, NO_COLOR="1", COLUMNS="200")
    if pythonpath is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(pythonpath), env.get("PYTHONPATH", "")])
    return subprocess.run(
        [str(exe), *argv[1:]], cwd=cwd, env=env, capture_output=True, text=True, timeout=300
    )


@pytest.fixture(scope="module")
def tree_copy(tmp_path_factory) -> Path:
    """A copy of the package and its contracts, to break on purpose."""
    root = tmp_path_factory.mktemp("layers")
    shutil.copytree(
        PACKAGE_ROOT / "src", root / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info")
    )
    shutil.copy(PACKAGE_ROOT / "pyproject.toml", root)
    return root


# (module that gets the import, the import, the contract that must break)
WRONG_WAY = [
    (
        "ros_control/nodes.py",
        "from twil_control.launch import node_types",
        "Layers: a package imports only the layers below it",
    ),
    (
        "view/panel.py",
        "from twil_control.bag import reader",
        "Layers: a package imports only the layers below it",
    ),
    (
        "control/polar.py",
        "from twil_control.core import node",
        "Pure math (control/, navigation/, mapping/, localization/) reaches neither Drake nor the ROS replica",
    ),
    (
        "mapping/raster.py",
        "from twil_control.world import world_section",
        "Pure math (control/, navigation/, mapping/, localization/) reaches neither Drake nor the ROS replica",
    ),
    ("gazebo/laser_node.py", "import pydrake.math", "Drake (pydrake) is imported only by world/ and view/"),
    (
        "ros_control/srv.py",
        "from twil_control.world import models",
        "The ROS replica (core/, ros_control/) reaches no Drake",
    ),
    (
        "description/urdf.py",
        "from twil_control.world import body_state",
        "Robot descriptions (description/) are read without Drake",
    ),
    (
        "nodes/map_server.py",
        "def _late():\n    from twil_control.world import models  # inside a function: still an import",
        "ROS-role nodes (nodes/) see topics, params and tf, never the simulator",
    ),
    (
        "world/models.py",
        "from twil_control.launch import loader",
        "Drake code (world/, view/) never parses launch files",
    ),
]


@pytest.mark.parametrize("module, line, contract", WRONG_WAY, ids=[m for m, _, _ in WRONG_WAY])
def test_a_wrong_way_import_breaks_its_contract(tree_copy, module, line, contract):
    path = tree_copy / "src/twil_control" / module
    original = path.read_text()
    path.write_text(original + f"\n{line}  # the wrong way\n")
    try:
        run = _run(["lint-imports", "--no-cache"], tree_copy, pythonpath=tree_copy / "src")
    finally:
        path.write_text(original)
    report = " ".join(run.stdout.split())  # the report wraps long contract names
    assert run.returncode == 1, report + run.stderr
    assert f"{contract} BROKEN" in report, report
    assert "twil_control." + module.removesuffix(".py").replace("/", ".") in report, report


def test_bag_holds_no_view_code_only_its_command_line_calls_the_view():
    """`bag play --view` draws through view/bag_replay.py; the bag library itself never imports
    the view (only the CLI module composes the two)."""
    import ast

    bag = PACKAGE_ROOT / "src" / "twil_control" / "bag"
    offenders = []
    for path in sorted(bag.rglob("*.py")):
        if path.name == "__main__.py":
            continue
        package = ["twil_control", *path.relative_to(bag.parent).parent.parts]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):  # resolved to an absolute module name
                base = package[: len(package) - node.level + 1] if node.level else []
                name = ".".join([*base, node.module or ""])
            elif isinstance(node, ast.Import):
                name = " ".join(alias.name for alias in node.names)
            else:
                continue
            if "twil_control.view" in name:
                offenders.append(f"{path.name}:{node.lineno}")
    assert offenders == []
    assert (PACKAGE_ROOT / "src" / "twil_control" / "view" / "bag_replay.py").exists()


def test_no_two_modules_share_a_file_name():
    """A module's file name says which one it is: `server.py` in two packages would not."""
    from collections import defaultdict

    where = defaultdict(list)
    for path in (PACKAGE_ROOT / "src" / "twil_control").rglob("*.py"):
        if path.name not in ("__init__.py", "__main__.py"):
            where[path.name].append(str(path.parent.name))
    assert {name: dirs for name, dirs in where.items() if len(dirs) > 1} == {}
