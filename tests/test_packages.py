"""Package discovery (rospack's role) and xacro in-process: ROS_PACKAGE_PATH and --package-path,
$(find), package:// and model://, the launch loader's param command, Drake's package map."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.core import packages
from twil_control.description.xacro_command import XacroError, run_xacro
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError

ROBOTS = PACKAGE_ROOT / "tests" / "data" / "robots"
TINY = ROBOTS / "tiny_description"


@pytest.fixture(autouse=True)
def _clean_paths(monkeypatch):
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    monkeypatch.delenv("GAZEBO_MODEL_PATH", raising=False)
    packages.set_extra_paths([])
    yield
    packages.set_extra_paths([])


def _package(folder: Path, name: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "package.xml").write_text(f"<package format='2'><name>{name}</name></package>")
    return folder


def test_ros_package_path_is_crawled_as_rospack_does(tmp_path, monkeypatch):
    first = _package(tmp_path / "ws1" / "src" / "deep" / "pkg_a", "pkg_a")
    _package(first / "nested", "nested_pkg")  # inside a package: not crawled
    _package(tmp_path / "ws1" / "ignored" / "pkg_b", "pkg_b")
    (tmp_path / "ws1" / "ignored" / "CATKIN_IGNORE").touch()
    second = _package(tmp_path / "ws2" / "other_folder_name", "pkg_a")  # same name, later path
    monkeypatch.setenv("ROS_PACKAGE_PATH", f"{tmp_path / 'ws1'}:{tmp_path / 'ws2'}")
    found = packages.all_packages()
    assert found["pkg_a"] == first  # the first on the path wins
    assert "nested_pkg" not in found and "pkg_b" not in found
    assert found["twil_control"] == PACKAGE_ROOT  # always found
    packages.set_extra_paths([tmp_path / "ws2"])  # --package-path comes first
    assert packages.find("pkg_a") == second


def test_a_missing_package_names_every_path_searched(tmp_path, monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "a"))
    packages.set_extra_paths([tmp_path / "b"])
    with pytest.raises(packages.PackageNotFoundError) as info:
        packages.find("no_such_pkg")
    assert str(info.value) == (
        f"package 'no_such_pkg' not found; searched (--package-path, then ROS_PACKAGE_PATH, then "
        f"this project and the packages it provides): {tmp_path / 'b'}, {tmp_path / 'a'}, {PACKAGE_ROOT}, "
        f"{packages.PROVIDED}; add the folder "
        f"holding it with --package-path DIR or ROS_PACKAGE_PATH"
    )


def test_package_and_model_urls_resolve_through_the_search_path(tmp_path, monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS))
    assert packages.resolve_url("package://tiny_description/meshes/base.stl") == TINY / "meshes" / "base.stl"
    model = tmp_path / "models" / "crate"
    model.mkdir(parents=True)
    (model / "model.config").write_text("<model/>")
    (model / "crate.sdf").write_text("<sdf/>")
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(tmp_path / "models"))
    assert packages.resolve_url("model://crate/crate.sdf") == model / "crate.sdf"
    with pytest.raises(
        packages.PackageNotFoundError, match="tiny_description/meshes/none.stl: file not found"
    ):
        packages.resolve_url("package://tiny_description/meshes/none.stl")


def test_xacro_runs_in_process_with_find_macros_and_args(monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS))
    xacro = str(TINY / "urdf" / "tiny.urdf.xacro")
    two = run_xacro(["/opt/ros/noetic/share/xacro/xacro", "--inorder", xacro])
    four = run_xacro([xacro, "drive:=skid_steer"])
    assert re.findall(r'joint name="(\w+_wheel_joint)" type', two) == [
        "left_wheel_joint",
        "right_wheel_joint",
    ]
    assert len(re.findall(r'joint name="\w+_wheel_joint" type="continuous"', four)) == 4
    # the wheel macro's inertia: izz = m r^2 / 2 = 0.3 * 0.05^2 / 2
    wheel = two[two.index('<link name="left_wheel_link">') :]
    izz = float(re.search(r'izz="([^"]+)"', wheel)[1])
    assert izz == pytest.approx(0.000375, rel=1e-12)
    assert "libgazebo_ros_diff_drive.so" in two and "libgazebo_ros_skid_steer_drive.so" in four
    with pytest.raises(XacroError, match="xacro option '--deps' is not supported"):
        run_xacro([xacro, "--deps"])


def test_xacro_names_the_missing_package_and_the_paths(tmp_path):
    source = tmp_path / "r.urdf.xacro"
    source.write_text(
        '<robot name="r" xmlns:xacro="http://ros.org/wiki/xacro">'
        '<xacro:include filename="$(find absent_description)/urdf/x.xacro"/></robot>'
    )
    with pytest.raises(XacroError) as info:
        run_xacro([str(source)])
    assert f"xacro {source}: package 'absent_description' not found; searched" in str(info.value)


def _launch_file(tmp_path, body: str) -> Path:
    path = tmp_path / "t.launch.yaml"
    path.write_text(textwrap.dedent(body))
    return path


def test_launch_param_command_runs_xacro_and_refuses_anything_else(tmp_path, monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS))
    path = _launch_file(
        tmp_path,
        """\
        launch:
          - arg: {name: drive, default: ros_control}
          - param: {name: robot_description,
                    command: "$(find xacro)/xacro.py $(find tiny_description)/urdf/tiny.urdf.xacro drive:=$(arg drive)"}
          - param: {name: mesh_dir, value: "$(find tiny_description)/meshes"}
        """,
    )
    params = load_launch(path).params
    assert "libgazebo_ros_control.so" in params.get("/robot_description")
    assert params.get("/mesh_dir") == str(TINY / "meshes")
    bad = _launch_file(tmp_path, 'launch:\n  - param: {name: p, command: "rm -rf /tmp/x"}\n')
    with pytest.raises(
        LaunchError, match=r"t.launch.yaml:2: param command 'rm -rf /tmp/x': 'command' runs only xacro"
    ):
        load_launch(bad)


def test_drake_package_map_holds_every_package_found(monkeypatch):
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    from twil_control.world.models import register_package

    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS))
    package_map = register_package(Parser(MultibodyPlant(0.001))).package_map()
    assert Path(package_map.GetPath("tiny_description")) == TINY
    assert Path(package_map.GetPath("twil_control")) == PACKAGE_ROOT
