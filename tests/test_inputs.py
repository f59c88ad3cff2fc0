"""Inputs that are too big or odd: YAML alias bombs and duplicate keys in every YAML the project
reads, command-line numbers as roslaunch takes them, seeds, and the one rule for relative paths
(core/yaml_io.py, launch/substitutions.py, core/paths.py)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.core.node import Master
from twil_control.core.params import ParamServer
from twil_control.core.typed_params import load_typed
from twil_control.core.yaml_io import MAX_ALIAS_EXPANSION, YamlError, load_yaml
from twil_control.gazebo.gzserver import DrakeWorldParams
from twil_control.launch import __main__ as launch_main
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError
from twil_control.launch.runner import Launch
from twil_control.mapping.map_io import MapFileError, read_map
from twil_control.nodes.cart_reference import CartReferenceError, load_program
from twil_control.nodes.timed_pub import TimedPubError, TimedPublisher
from twil_control.sweep.spec import SweepError, load_sweep
from twil_control.world.models import ModelError

#: Six levels of nine aliases each: 9**6 = 531,441 strings once expanded, from 8 lines.
BOMB = "".join(
    [f"{chr(97 + k)}: &{chr(97 + k)} [" + ", ".join([f"*{chr(96 + k)}"] * 9) + "]\n" for k in range(1, 6)]
)
BOMB = 'a: &a ["x", "x", "x", "x", "x", "x", "x", "x", "x"]\n' + BOMB


# ---- YAML: aliases and duplicate keys, in every kind of file ---------------------------------


def _timed_pub(path: Path):
    master = Master()
    master.params.set("/pub", {"topic": "out", "type": "std_msgs/Float64", "file": str(path)})
    return TimedPublisher(master, "pub")


def _sweep(path: Path):
    return load_sweep(path)


def _map(path: Path):
    return read_map(path)


def _cart(path: Path):
    return load_program(path, 7, None)


def _rosparam(path: Path):
    return ParamServer().load_file(path, "/x")


def _launch(path: Path):
    return load_launch(path)


def _directives(path: Path):  # Drake's model directives: checked by our loader before Drake's
    from pydrake.multibody.plant import MultibodyPlant

    from twil_control.world.models import add_model

    dmd = path.with_name(path.stem + ".dmd.yaml")
    dmd.write_text(path.read_text())
    return add_model(MultibodyPlant(0.0), dmd)


READERS = [
    (_launch, LaunchError),
    (_rosparam, YamlError),
    (_timed_pub, TimedPubError),
    (_cart, CartReferenceError),
    (_map, MapFileError),
    (_sweep, SweepError),
    (_directives, ModelError),
]


@pytest.mark.parametrize("read, error", READERS, ids=lambda r: getattr(r, "__name__", ""))
def test_every_yaml_file_refuses_an_alias_bomb_naming_the_file_and_line(tmp_path, read, error):
    path = tmp_path / "bomb.yaml"
    path.write_text(BOMB + "launch: *f\n")
    with pytest.raises(error) as caught:
        read(path)
    assert re.search(
        rf"bomb(\.dmd)?\.yaml:7: aliases expand this document from 23 to 1,270,482 nodes "
        rf"\(alias \*f alone stands for 597,871\); at most {MAX_ALIAS_EXPANSION:,} "
        rf"added nodes are allowed",
        str(caught.value),
    )


@pytest.mark.parametrize("read, error", READERS, ids=lambda r: getattr(r, "__name__", ""))
def test_every_yaml_file_refuses_duplicate_keys_naming_both_lines(tmp_path, read, error):
    path = tmp_path / "twice.yaml"
    path.write_text(
        "- time: 1.0\n  msg: {}\n- time: 2.0\n  msg: {}\n  time: 3.0\n"
        if read in (_timed_pub, _cart)
        else "resolution: 0.05\nlaunch: []\nresolution: 1\n"
    )
    with pytest.raises(
        error,
        match=r"twice(\.dmd)?\.yaml:(5|3): duplicate key '(time|resolution)' "
        r"\(first defined at line (3|1)\)",
    ):
        read(path)


def test_aliases_within_the_limit_and_merge_keys_still_load(tmp_path):
    path = tmp_path / "ok.yaml"
    path.write_text("defaults: &d {kp: 25.0, kd: 10.0}\njoints: [*d, *d, *d]\nwheel: {<<: *d, kp: 5.0}\n")
    data = load_yaml(path)
    assert data["joints"] == [{"kp": 25.0, "kd": 10.0}] * 3
    assert data["wheel"] == {"kp": 5.0, "kd": 10.0}


def test_a_recursive_alias_and_deep_nesting_are_refused_with_their_line(tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text("a: 1\nb: &self [1, *self]\n")
    with pytest.raises(
        YamlError,
        match=r"loop.yaml:2: alias \*self refers to a mapping or list "
        r"that contains it",
    ):
        load_yaml(path)
    path.write_text("x: " + "[" * 150 + "]" * 150 + "\n")
    with pytest.raises(
        YamlError,
        match=r"loop.yaml:1:\d+: YAML error: mappings and lists nest "
        r"more than 100 levels deep",
    ):
        load_yaml(path)


def test_an_error_that_is_not_bad_input_is_not_reported_as_bad_input(capsys, monkeypatch):
    """Only a TwilControlError is bad input (one line, exit 2); a MemoryError goes on up, so that
    Python prints its traceback and exits 1 (tests/test_error_family.py runs that end to end)."""

    def out_of_memory(*_args, **_kw):
        raise MemoryError()

    monkeypatch.setattr("twil_control.launch.loader.load_launch", out_of_memory)
    with pytest.raises(MemoryError):
        launch_main.main(["launch/twil_sim.launch.yaml"])
    assert "error:" not in capsys.readouterr().err


# ---- numbers ---------------------------------------------------------------------------------


def _world_params(**args: str) -> DrakeWorldParams:
    plan = load_launch(PACKAGE_ROOT / "launch/twil_sim.launch.yaml", args)
    return load_typed(plan.params, "/gazebo", DrakeWorldParams)


@pytest.mark.parametrize("text, value", [("1e-3", 1e-3), ("1E-3", 1e-3), ("5.0e-4", 5e-4), ("0.002", 0.002)])
def test_command_line_numbers_with_an_exponent_are_numbers(text, value):
    assert _world_params(time_step=text).time_step == value


def test_a_time_step_too_long_for_contact_is_refused_saying_why():
    with pytest.raises(
        ValueError,
        match=r"parameter '/gazebo/time_step' must be a finite number "
        r"> 0 and <= 0.01; a longer step lets a robot move more than "
        r"a centimetre .* \(got 10\)",
    ):
        _world_params(time_step="10")
    for text in ("0", "-1e-3", "0.011"):
        with pytest.raises(ValueError, match=r"time_step' must be a finite number > 0 and <= 0.01;"):
            _world_params(time_step=text)


@pytest.mark.parametrize("seed", ["-1", "-7"])
def test_a_negative_seed_is_refused_naming_the_option_for_every_launch(capsys, seed):
    for launch in ("launch/twil_sim.launch.yaml", "launch/qbot_sim.launch.yaml"):
        assert launch_main.main([launch, "--seed", seed, "--no-bag", "--duration", "0.01"]) == 2
        assert capsys.readouterr().err.startswith(f"error: --seed must be an integer >= 0 (got {seed})")


def test_the_largest_seeds_numpy_takes_are_taken():
    master = Master()
    master.seed = 2**64
    assert 0 <= master.rng("node").integers(10) < 10


# ---- paths -----------------------------------------------------------------------------------


def test_a_relative_world_is_found_from_another_directory_through_the_package_root(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    plan = load_launch("launch/qbot_sim.launch.yaml", {"world": "sim/worlds/house.sdf"})
    world = next(node for node in Launch(plan).nodes if node.fqn == "/gazebo")
    sim = world.make_simulation()
    assert sim.world_files == [PACKAGE_ROOT / "sim/worlds/house.sdf"]  # as gzserver resolved it
    assert len(sim.anchored_sources) == 66  # the house's 33 shapes, a collision and a visual each


def test_a_relative_path_is_looked_up_in_the_working_directory_first(tmp_path, monkeypatch):
    mine = tmp_path / "sim/worlds/house.sdf"
    mine.parent.mkdir(parents=True)
    mine.write_text((PACKAGE_ROOT / "sim/worlds/default.sdf").read_text())
    monkeypatch.chdir(tmp_path)
    from twil_control.core.paths import find_file

    assert find_file("sim/worlds/house.sdf") == mine
    assert find_file("config/twil.yaml") == PACKAGE_ROOT / "config/twil.yaml"


@pytest.mark.parametrize(
    "launch, arg, what",
    [
        ("launch/twil_sim.launch.yaml", "world", "world file"),
        ("launch/wam_computed_torque.launch.yaml", "reference", "reference program"),
        ("launch/twil_cart_linearizing.launch.yaml", "reference", "reference program"),
        ("launch/qbot_navigation.launch.yaml", "goals_file", "goals file"),
    ],
)
def test_a_missing_relative_path_names_every_place_tried(capsys, tmp_path, monkeypatch, launch, arg, what):
    monkeypatch.chdir(tmp_path)
    name = "no/such.sdf" if arg == "world" else "no/such.yaml"
    assert (
        launch_main.main([str(PACKAGE_ROOT / launch), f"{arg}:={name}", "--no-bag", "--duration", "0.01"])
        == 2
    )
    err = capsys.readouterr().err
    if arg == "world":  # gzserver's rule (core.gazebo_paths): the resource folders too
        stock = PACKAGE_ROOT / "src/twil_control/share/gazebo"
        tried = f"{tmp_path}/{name}, {stock}/{name}, {stock}/worlds/{name}, {PACKAGE_ROOT}/{name}"
        assert f"world file not found: {name} (tried {tried}: as given, then under each" in err
        return
    assert (
        f"{what} not found: {name} (tried {tmp_path}/{name}, "
        f"{PACKAGE_ROOT}/{name}: a relative path is looked up in the working directory, "
        f"then in the package root)" in err
    )
