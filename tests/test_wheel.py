"""The package as a user installs it: the sdist and the wheel built from this checkout, the wheel
installed with its declared dependencies only (at the locked versions) into a fresh venv, then
every module imported and a launch, `$(find twil_control)` and the demo run from a folder
outside the checkout. About 1.5 min with uv's cache warm; on a fresh machine uv first downloads
the dependencies (another minute or so)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import bag_connections

from twil_control import PACKAGE_ROOT

pytestmark = pytest.mark.slow

UV = Path(sys.executable).with_name("uv")

IMPORT_ALL = """
import importlib, pkgutil, twil_control
names = [m.name for m in pkgutil.walk_packages(twil_control.__path__, "twil_control.")]
for name in names:
    importlib.import_module(name)
print(len(names), twil_control.PACKAGE_ROOT)
"""


def _run(argv: list, cwd: Path, timeout: float = 600, **env_vars: str) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")} | env_vars
    r = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, f"{argv}: exit {r.returncode}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    return r


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> tuple[Path, Path]:
    """(the venv's python, an empty working folder outside the checkout)."""
    tmp = tmp_path_factory.mktemp("wheel")
    _run([sys.executable, "-m", "build", "--outdir", str(tmp / "dist"), str(PACKAGE_ROOT)], cwd=tmp)
    wheels = list((tmp / "dist").glob("twil_control-*.whl"))
    assert len(wheels) == 1 and list((tmp / "dist").glob("twil_control-*.tar.gz"))
    venv = tmp / "venv"
    _run([str(UV), "venv", "--quiet", "--python", sys.executable, str(venv)], cwd=tmp)
    python = venv / "bin" / "python"
    lock = PACKAGE_ROOT / "requirements.lock"
    _run(
        [str(UV), "pip", "install", "--quiet", "--python", str(python), "-c", str(lock), str(wheels[0])], tmp
    )
    work = tmp / "elsewhere"
    work.mkdir()
    return python, work


def test_every_module_imports_with_the_declared_dependencies_alone(installed):
    python, work = installed
    count, root = _run([str(python), "-c", IMPORT_ALL], cwd=work).stdout.split()
    assert int(count) > 200
    # the catkin folders come from the installed package, not from this checkout
    assert Path(root).is_relative_to(python.parent.parent) and (Path(root) / "package.xml").is_file()


def test_a_shipped_launch_runs_from_any_folder(installed):
    """launch/qbot_sim.launch.yaml is found in the package root; it names its world, robot and
    parameters through $(find twil_control)."""
    python, work = installed
    bag = work / "qbot.bag"
    argv = [python, "-m", "twil_control.launch", "launch/qbot_sim.launch.yaml", "--duration", "1"]
    _run([*map(str, argv), "--bag", str(bag)], cwd=work)
    msgtype, _, count = bag_connections(bag)["/qbot/odom"]
    assert msgtype == "nav_msgs/msg/Odometry" and count >= 45  # 50 Hz over 1 s, within one period


def test_the_demo_runs_from_any_folder(installed):
    """Its launch, configuration and robots found in the installed package, its output written in
    the working folder. Numba's JIT off: compiling the demo's kernels afresh in this venv (the
    launch above has compiled and cached the qbot's in it) would take twice as long as the run."""
    python, work = installed
    argv = [str(python), "-m", "twil_control.demo", "--duration", "1", "--no-html", "--out", "runs"]
    r = _run(argv, work, NUMBA_DISABLE_JIT="1")
    assert "final error against the odometry" in r.stdout
    assert len(list((work / "runs").glob("demo_*.bag"))) == 1
