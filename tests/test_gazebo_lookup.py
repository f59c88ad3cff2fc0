"""Gazebo's lookup rules (core.gazebo_paths): world names as gzserver resolves them, model://
through GAZEBO_MODEL_PATH, the packages' gazebo_ros exports and the stock models, and what a
model that is not found says."""

from __future__ import annotations

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.core import gazebo_paths, packages
from twil_control.description.gazebo_world import normalise
from twil_control.description.urdf import DescriptionError
from twil_control.gazebo.gzserver import world_argument

DATA = PACKAGE_ROOT / "tests" / "data" / "gazebo"


def _model(root, name: str, body: str = "") -> None:
    folder = root / name
    folder.mkdir(parents=True)
    (folder / "model.config").write_text(
        f"<model><name>{name}</name><sdf version='1.6'>model.sdf</sdf></model>"
    )
    (folder / "model.sdf").write_text(f"<sdf version='1.6'><model name='{name}'>{body}</model></sdf>")


def _package(root, name: str, export: str) -> None:
    root.mkdir(parents=True)
    (root / "package.xml").write_text(
        f"<package format='2'><name>{name}</name><export>{export}</export></package>"
    )


@pytest.fixture
def env(tmp_path, monkeypatch):
    for var in ("GAZEBO_MODEL_PATH", "GAZEBO_RESOURCE_PATH", "ROS_PACKAGE_PATH"):
        monkeypatch.delenv(var, raising=False)
    packages.set_extra_paths([])
    monkeypatch.chdir(tmp_path)
    return monkeypatch


def test_model_uris_resolve_in_gazebo_order_and_the_stock_models_come_last(tmp_path, env):
    first, second, ws = tmp_path / "first", tmp_path / "second", tmp_path / "ws"
    _model(first, "crate")
    _model(second, "crate")
    _model(second, "barrel")
    _package(ws / "my_gazebo", "my_gazebo", '<gazebo_ros gazebo_model_path="${prefix}/models"/>')
    _model(ws / "my_gazebo" / "models", "barrel")
    _model(ws / "my_gazebo" / "models", "cone")
    _model(ws / "my_gazebo" / "models", "ground_plane")  # a user's own shadows the stock one
    env.setenv("GAZEBO_MODEL_PATH", f"{first}:{second}")
    env.setenv("ROS_PACKAGE_PATH", str(ws))
    assert gazebo_paths.find_model("crate") == first / "crate"
    assert gazebo_paths.find_model("barrel") == second / "barrel"  # the variable before the exports
    assert gazebo_paths.find_model("cone") == ws / "my_gazebo" / "models" / "cone"
    assert gazebo_paths.find_model("ground_plane") == ws / "my_gazebo" / "models" / "ground_plane"
    assert gazebo_paths.find_model("sun") == gazebo_paths.STOCK / "models" / "sun"
    assert gazebo_paths.model_folders() == [
        first,
        second,
        ws / "my_gazebo" / "models",
        gazebo_paths.STOCK / "models",
    ]
    assert (
        packages.resolve_url("model://cone/model.sdf") == ws / "my_gazebo" / "models" / "cone" / "model.sdf"
    )


def test_a_missing_model_names_it_every_folder_searched_and_the_unreachable_database(tmp_path, env):
    env.setenv("GAZEBO_MODEL_PATH", str(tmp_path / "models"))
    world = tmp_path / "w.world"
    world.write_text(
        "<sdf version='1.6'><world name='w'>\n\n<include><uri>model://ghost</uri></include></world></sdf>"
    )
    with pytest.raises(DescriptionError) as info:
        normalise(world)
    message = str(info.value)
    assert message.startswith(f"{world}:3: <include> 'model://ghost': model 'ghost' not found")
    assert f"in {tmp_path / 'models'}, {gazebo_paths.STOCK / 'models'} " in message
    assert "online model database is not reachable" in message


def test_world_names_resolve_as_given_then_under_the_resource_folders_then_the_stock_worlds(tmp_path, env):
    res, ws = tmp_path / "res", tmp_path / "ws"
    (res / "worlds").mkdir(parents=True)
    (res / "worlds" / "room.world").write_text("<sdf version='1.6'><world name='w'/></sdf>")
    (res / "flat.world").write_text("<sdf version='1.6'><world name='w'/></sdf>")
    _package(ws / "my_gazebo", "my_gazebo", '<gazebo_ros gazebo_media_path="${prefix}"/>')
    (ws / "my_gazebo" / "worlds").mkdir()
    (ws / "my_gazebo" / "worlds" / "yard.world").write_text("<sdf version='1.6'><world name='w'/></sdf>")
    (tmp_path / "here.world").write_text("<sdf version='1.6'><world name='w'/></sdf>")
    env.setenv("GAZEBO_RESOURCE_PATH", str(res))
    env.setenv("ROS_PACKAGE_PATH", str(ws))
    assert gazebo_paths.resolve_world("here.world") == tmp_path / "here.world"
    assert gazebo_paths.resolve_world("room.world") == res / "worlds" / "room.world"
    assert gazebo_paths.resolve_world("flat.world") == res / "flat.world"
    assert gazebo_paths.resolve_world("worlds/yard.world") == ws / "my_gazebo" / "worlds" / "yard.world"
    assert gazebo_paths.resolve_world("worlds/empty.world") == gazebo_paths.STOCK / "worlds" / "empty.world"
    with pytest.raises(gazebo_paths.WorldNotFoundError) as info:
        gazebo_paths.resolve_world("nowhere.world")
    tried = str(info.value).split("(tried ")[1].split(": as given")[0].split(", ")
    assert tried[:3] == [
        str(tmp_path / "nowhere.world"),
        str(res / "nowhere.world"),
        str(res / "worlds/nowhere.world"),
    ]
    assert str(gazebo_paths.STOCK / "worlds" / "nowhere.world") in tried and len(tried) == 8


def test_the_stock_empty_world_is_a_ground_plane_and_a_sun(env):
    world = normalise(gazebo_paths.resolve_world("worlds/empty.world"))
    assert [(m.name, m.static) for m in world.models] == [("ground_plane", True)]
    assert world.ignored["light"] == 1  # the sun is a light, without meaning here
    assert world.converted["collision plane -> 0.1 m box"] == 1
    assert b"<box><size>100.0 100.0 0.1</size></box>" in world.text


@pytest.mark.parametrize(
    "args, world",
    [
        (["-e", "ode", "worlds/empty.world"], "worlds/empty.world"),
        (["-u", "--verbose", "-e", "ode", "/tmp/room.xml"], "/tmp/room.xml"),  # any suffix (issue 35, 11)
        (["/dev/stdin"], "/dev/stdin"),
        (["-s", "libgazebo_ros_api_plugin.so", "room", "--seed", "3"], "room"),
        (["-e", "ode"], None),
    ],
)
def test_the_world_is_gzservers_positional_argument_whatever_its_suffix(args, world):
    assert world_argument(args) == world


def test_a_world_read_from_dev_stdin_runs(tmp_path):
    """Issue 35, 11: a world without a .sdf/.world suffix was 'no world file'."""
    import subprocess
    import sys

    launch = tmp_path / "stdin.launch"
    launch.write_text(
        '<launch><node name="gazebo" pkg="gazebo_ros" type="gzserver" args="-e ode /dev/stdin"/></launch>'
    )
    world = (gazebo_paths.STOCK / "worlds" / "empty.world").read_text()
    child = subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(launch),
            "--duration",
            "0.2",
            "--bag",
            str(tmp_path / "s.bag"),
        ],
        input=world,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert child.returncode == 0, child.stderr[-2000:]
    assert (
        "/dev/stdin: 3 Gazebo elements without meaning in this simulation, ignored (element count): "
        "cast_shadows 1, light 1, mu2 (friction is isotropic here: mu is used) 1\n" in child.stderr
    )
