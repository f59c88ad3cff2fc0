"""Parameter server semantics (rosparam's), safe YAML, and typed parameter schemas."""

from __future__ import annotations  # schemas must work with string annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar, Literal

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.core.params import ParamError, ParamNotFoundError, ParamServer
from twil_control.core.typed_params import load_typed, schema_keys
from twil_control.core.yaml_io import YamlError, load_yaml, load_yaml_with_lines, parse_yaml

CONFIG = PACKAGE_ROOT / "tests" / "data" / "launch" / "config"
SCHEMA_FILE = "tests/data/launch/config/schema.yaml"


# --------------------------------------------------------------------------------------
# ParamServer
# --------------------------------------------------------------------------------------


def test_set_and_get_leaf_and_namespace():
    server = ParamServer()
    server.set("/a/b", 1)
    server.set("/a/c", "x")
    assert server.get("/a/b") == 1
    assert server.get("/a") == {"b": 1, "c": "x"}
    assert server.get("/") == {"a": {"b": 1, "c": "x"}}
    assert server.has("/a") and server.has("/a/b") and not server.has("/a/z")


def test_setting_a_mapping_merges_like_rosparam_set():
    server = ParamServer()
    server.set("/ns", {"keep": 1, "sub": {"x": 1}})
    server.set("/ns", {"new": 2, "sub": {"y": 2}})
    assert server.get("/ns") == {"keep": 1, "new": 2, "sub": {"x": 1, "y": 2}}


def test_a_value_replaces_a_namespace_and_a_namespace_replaces_a_value():
    server = ParamServer()
    server.set("/ns/sub/x", 1, source="first")
    server.set("/ns/sub", 5, source="second")
    assert server.get("/ns") == {"sub": 5}
    assert server.source_of("/ns/sub/x") is None
    server.set("/ns/sub/y", 2)  # rosmaster turns the value back into a namespace
    assert server.get("/ns/sub") == {"y": 2}


def test_get_returns_a_copy():
    server = ParamServer()
    server.set("/ns", {"list": [1, 2], "sub": {"x": 1}})
    copy = server.get("/ns")
    copy["list"].append(3)
    copy["sub"]["x"] = 99
    assert server.get("/ns") == {"list": [1, 2], "sub": {"x": 1}}


def test_missing_parameter_is_a_key_error_naming_it_and_its_siblings():
    server = ParamServer()
    server.set("/ns/rate", 1)
    server.set("/ns/gain", 2)
    with pytest.raises(KeyError) as err:
        server.get("/ns/rat")
    assert isinstance(err.value, ParamError)
    assert str(err.value) == "parameter '/ns/rat' is not set; '/ns' has: gain, rate"
    assert server.get("/ns/rat", 7) == 7
    assert server.get("/ns/rat", None) is None


def test_delete_leaf_namespace_and_missing():
    server = ParamServer()
    server.set("/a", {"b": 1, "c": {"d": 2}}, source="f.yaml:1")
    server.delete("/a/c")
    assert server.get("/a") == {"b": 1}
    assert server.source_of("/a/c/d") is None
    with pytest.raises(ParamNotFoundError, match="'/a/zz' is not set"):
        server.delete("/a/zz")
    server.delete("/")
    assert server.names() == []


def test_names_lists_leaves_sorted():
    server = ParamServer()
    server.set("/z", 1)
    server.set("/a", {"c": [1, 2], "b": {"x": True}})
    assert server.names() == ["/a/b/x", "/a/c", "/z"]


def test_names_must_be_global_and_legal():
    server = ParamServer()
    with pytest.raises(ParamError, match=r"'rate' must be global \(start with '/'\)"):
        server.set("rate", 1)
    with pytest.raises(ParamError, match="invalid ROS name '/bad-name'"):
        server.set("/bad-name", 1)
    with pytest.raises(ParamError, match="character '-'"):
        server.set("/ns", {"bad-key": 1}, source="f.yaml:3")


def test_null_and_unsupported_values_are_refused_with_their_source():
    server = ParamServer()
    with pytest.raises(ParamError, match=r"^f.yaml:4: parameter '/ns/k' has no value"):
        server.set("/ns", {"k": None}, source="f.yaml:4")
    with pytest.raises(ParamError, match="unsupported type object"):
        server.set("/x", object())
    with pytest.raises(ParamError, match="cannot set the root namespace '/'"):
        server.set("/", 3)


def test_dump_and_source_of():
    server = ParamServer()
    server.set("/ns/a", 1, source="command line")
    assert server.dump("/ns") == {"a": 1}
    assert server.source_of("/ns/a") == "command line"
    assert server.source_of("/ns") == "command line"  # a namespace: its first leaf
    assert server.source_of("/nothing") is None
    with pytest.raises(ParamError, match="is a parameter, not a namespace"):
        server.dump("/ns/a")


def test_load_file_records_file_and_line_for_every_key():
    server = ParamServer()
    server.load_file(CONFIG / "controllers.yaml", "/twil/ros_control")
    assert server.get("/twil/ros_control/cart_linearizing_controller/gains") == {"kp": 100.0, "kd": 20}
    label = "tests/data/launch/config/controllers.yaml"
    assert server.source_of("/twil/ros_control/joint_state_controller/publish_rate") == f"{label}:4"
    assert server.source_of("/twil/ros_control/cart_linearizing_controller/gains/kd") == f"{label}:9"
    assert server.source_of("/twil/ros_control/cart_linearizing_controller/gains") == f"{label}:7"
    assert server.files_under("/twil") == [label]


def test_load_file_with_param_sets_the_whole_document_at_one_name(tmp_path):
    listing = tmp_path / "list.yaml"
    listing.write_text("[1, 2, 3]\n")
    server = ParamServer()
    server.load_file(listing, "/ns", param="values")
    assert server.get("/ns/values") == [1, 2, 3]
    with pytest.raises(
        ParamError,
        match=r"list.yaml:1: parameters loaded into namespace "
        r"'/ns' must be a mapping .* got a list",
    ):
        server.load_file(listing, "/ns")


def test_load_file_global_keys_stay_global_like_rosparam(tmp_path):
    file = tmp_path / "p.yaml"
    file.write_text("local: 1\n/global: 2\n")
    server = ParamServer()
    server.load_file(file, "/ns")
    assert server.get("/") == {"ns": {"local": 1}, "global": 2}


# --------------------------------------------------------------------------------------
# Safe YAML
# --------------------------------------------------------------------------------------


def test_yaml_syntax_error_names_file_line_and_column():
    with pytest.raises(YamlError) as err:
        load_yaml(CONFIG / "bad_syntax.yaml")
    message = str(err.value)
    assert message.startswith("tests/data/launch/config/bad_syntax.yaml:4:")
    assert "YAML syntax error" in message


def test_duplicate_keys_are_refused_with_both_lines():
    with pytest.raises(YamlError) as err:
        load_yaml(CONFIG / "duplicate.yaml")
    assert str(err.value) == (
        "tests/data/launch/config/duplicate.yaml:4: duplicate key 'kp' (first defined at "
        "line 2); YAML would silently keep only the last one"
    )


def test_python_object_tags_are_refused_not_executed(tmp_path):
    with pytest.raises(YamlError) as err:
        load_yaml(CONFIG / "python_tag.yaml")
    assert str(err.value).startswith(
        "tests/data/launch/config/python_tag.yaml:1:7: YAML tag "
        "'!!python/object/apply:os.system' is not allowed"
    )
    marker = tmp_path / "created_by_yaml"
    with pytest.raises(YamlError, match="not allowed"):
        parse_yaml(f"x: !!python/object/apply:os.mkdir [{str(marker)!r}]\n", "t.yaml")
    assert not marker.exists()


def test_missing_yaml_file():
    with pytest.raises(YamlError, match=r"config/nope.yaml: no such file$"):
        load_yaml(CONFIG / "nope.yaml")


def test_lines_are_kept_for_keys_and_list_items():
    data, lines = load_yaml_with_lines(CONFIG / "schema.yaml")
    assert data["cart"]["joints"] == ["j1", "j2"]
    assert lines[("cart",)] == 2
    assert lines[("cart", "gains", "kd")] == 7
    assert lines[("cart", "joints", 1)] == 8


def test_rosparam_angle_tags():
    data, _ = parse_yaml("a: !degrees 180\nb: !radians 1.5\n")
    assert data["a"] == pytest.approx(math.pi)
    assert data["b"] == 1.5
    with pytest.raises(YamlError, match=r"t.yaml:1:4: .*!degrees needs a plain number"):
        parse_yaml("a: !degrees pi/2\n", "t.yaml")


# --------------------------------------------------------------------------------------
# Typed schemas
# --------------------------------------------------------------------------------------


@dataclass
class Gains:
    kp: float
    kd: float = 0.0


@dataclass
class Cart:
    publish_rate: int
    gains: Gains
    mode: Literal["cartesian", "joint"] = "joint"
    joints: list[str] = field(default_factory=list)
    limits: dict[str, float] = field(default_factory=dict)
    offset: tuple[float, ...] = (0.0, 0.0)
    timeout: float | None = None
    name: str | None = None
    enabled: bool = True

    def __post_init__(self):
        if self.publish_rate <= 0:
            raise ValueError(f"publish_rate must be > 0, got {self.publish_rate}")


def _server_from_schema_file() -> ParamServer:
    server = ParamServer()
    server.load_file(PACKAGE_ROOT / SCHEMA_FILE, "/twil")
    return server


def _loaded(text: str, tmp_path: Path, name: str = "cart.yaml") -> ParamServer:
    file = tmp_path / name
    file.write_text(text)
    server = ParamServer()
    server.load_file(file, "/twil/cart")
    return server


def test_schema_keys():
    assert schema_keys(Gains) == ("kp", "kd")


def test_load_typed_reads_nested_literal_dict_list_and_converts_ints_to_float():
    cart = load_typed(_server_from_schema_file(), "/twil/cart", Cart)
    assert cart == Cart(
        publish_rate=100,
        gains=Gains(kp=10.0, kd=2.5),
        mode="cartesian",
        joints=["j1", "j2"],
        limits={"j1": 1.5, "j2": 2.0},
    )
    assert type(cart.gains.kp) is float  # int in YAML, float in the schema
    assert type(cart.limits["j2"]) is float
    assert cart.timeout is None and cart.offset == (0.0, 0.0)


def test_unknown_parameter_names_file_line_key_and_allowed_keys(tmp_path):
    server = _loaded("publish_rate: 1\ngains: {kp: 1}\npublsh_rate: 2\n", tmp_path)
    with pytest.raises(ParamError) as err:
        load_typed(server, "/twil/cart", Cart)
    message = str(err.value)
    assert message.startswith(f"{tmp_path / 'cart.yaml'}:3: unknown parameter '/twil/cart/publsh_rate'")
    assert "did you mean 'publish_rate'?" in message
    assert message.endswith(
        "allowed: enabled, gains, joints, limits, mode, name, offset, publish_rate, timeout"
    )


def test_unknown_parameter_in_a_nested_schema(tmp_path):
    server = _loaded("publish_rate: 1\ngains:\n  kp: 1\n  ki: 3\n", tmp_path)
    with pytest.raises(
        ParamError,
        match=r"cart.yaml:4: unknown parameter "
        r"'/twil/cart/gains/ki'; allowed: kd, kp$",
    ):
        load_typed(server, "/twil/cart", Cart)


@pytest.mark.parametrize(
    "line, expected",
    [
        (
            "publish_rate: true",
            "parameter '/twil/cart/publish_rate' must be an integer (got True); booleans are not numbers",
        ),
        ("publish_rate: 2.5", "parameter '/twil/cart/publish_rate' must be an integer (got 2.5)"),
        (
            "publish_rate: '100'",
            "parameter '/twil/cart/publish_rate' must be an integer (got '100'); YAML read it as a string",
        ),
        ("enabled: 1", "parameter '/twil/cart/enabled' must be a boolean (true or false) (got 1)"),
        (
            "mode: cartesan",
            "parameter '/twil/cart/mode' must be one of 'cartesian', 'joint' (got 'cartesan')",
        ),
        ("joints: j1", "parameter '/twil/cart/joints' must be a list of strings (got 'j1')"),
        ("joints: [j1, 2]", "parameter '/twil/cart/joints[1]' must be a string (got 2)"),
        ("limits: {j1: yes}", "parameter '/twil/cart/limits/j1' must be a number (got True)"),
        (
            "timeout: 1e-3",
            "parameter '/twil/cart/timeout' must be a number (got '1e-3'); YAML "
            "read it as a string: quote-free numbers need a '.' before an exponent",
        ),
        ("gains: 3", "parameter '/twil/cart/gains' must be a mapping with keys kp, kd (got 3)"),
    ],
)
def test_wrong_types_name_file_line_param_expected_type_and_value(tmp_path, line, expected):
    base = {"publish_rate": "publish_rate: 10", "gains": "gains: {kp: 1}"}
    key = line.split(":")[0]
    base[key] = line
    text = "\n".join(base.values()) + "\n"
    server = _loaded(text, tmp_path)
    number = list(base).index(key) + 1 if key in ("publish_rate", "gains") else 3
    with pytest.raises(ParamError) as err:
        load_typed(server, "/twil/cart", Cart)
    assert str(err.value).startswith(f"{tmp_path / 'cart.yaml'}:{number}: {expected}")


def test_bool_is_not_accepted_for_float(tmp_path):
    server = _loaded("publish_rate: 1\ngains: {kp: false}\n", tmp_path)
    with pytest.raises(ParamError, match=r"'/twil/cart/gains/kp' must be a number \(got False\)"):
        load_typed(server, "/twil/cart", Cart)


def test_missing_required_names_param_namespace_and_where_params_came_from(tmp_path):
    server = _loaded("gains: {kp: 1}\n", tmp_path)
    with pytest.raises(ParamError) as err:
        load_typed(server, "/twil/cart", Cart)
    assert str(err.value) == (
        f"missing required parameter '/twil/cart/publish_rate' for Cart; parameters under "
        f"'/twil/cart' were loaded from {tmp_path / 'cart.yaml'}"
    )
    with pytest.raises(
        ParamError,
        match="missing required parameters '/empty/publish_rate', "
        "'/empty/gains' for Cart; no parameters are set "
        "under '/empty'",
    ):
        load_typed(ParamServer(), "/empty", Cart)


def test_post_init_value_error_becomes_param_error_with_namespace_and_source(tmp_path):
    server = _loaded("publish_rate: 0\ngains: {kp: 1}\n", tmp_path)
    with pytest.raises(ParamError) as err:
        load_typed(server, "/twil/cart", Cart)
    assert str(err.value) == (
        f"{tmp_path / 'cart.yaml'}:1: invalid parameters in "
        f"'/twil/cart' (Cart): publish_rate must be > 0, got 0"
    )


def test_optional_and_tuple_fields(tmp_path):
    server = _loaded(
        "publish_rate: 1\ngains: {kp: 1}\ntimeout: 2\nname: arm\noffset: [1, 2.5, 3]\n", tmp_path
    )
    cart = load_typed(server, "/twil/cart", Cart)
    assert cart.timeout == 2.0 and type(cart.timeout) is float
    assert cart.name == "arm"
    assert cart.offset == (1.0, 2.5, 3.0)


def test_namespace_that_is_a_value_is_an_error():
    server = ParamServer()
    server.set("/twil/cart", 3, source="x.yaml:2")
    with pytest.raises(
        ParamError,
        match=r"^x.yaml:2: parameter '/twil/cart' must be a "
        r"namespace holding publish_rate, gains",
    ):
        load_typed(server, "/twil/cart", Cart)


# --------------------------------------------------------------------------------------
# The schemas of nodes standing for someone else's ROS package
# --------------------------------------------------------------------------------------


@dataclass
class Sensor:
    ros_package: ClassVar[str] = "costmap_2d"
    topic: str = "scan"


@dataclass
class Planner:
    """A schema of a ROS package's node: unknown keys warned, one parameter it cannot honour,
    one renamed."""

    ros_package: ClassVar[str] = "some_planner"
    no_effect: ClassVar[dict] = {
        "publish_cloud": (False, "no clouds are published"),
        "buffer": "not simulated",
    }
    renamed: ClassVar[dict] = {"max_rot_vel": "max_vel_theta"}
    max_vel_theta: float = 1.0
    publish_cloud: bool = False
    buffer: float = 0.2
    sensor: Sensor = field(default_factory=Sensor)


def _planner_file(tmp_path, text: str):
    server = _loaded(text, tmp_path, "planner.yaml")
    warnings: list[str] = []
    return server, warnings, lambda: load_typed(server, "/twil/cart", Planner, warnings.append)


def test_an_unknown_key_of_a_ros_package_schema_is_one_warning_and_the_load_goes_on(tmp_path):
    server, warnings, load = _planner_file(tmp_path, "max_vel_thetta: 2.0\nsensor: {topik: /scan}\n")
    assert load() == Planner()  # the defaults, as the package would run
    where = tmp_path / "planner.yaml"
    assert warnings == [
        f"{where}:1: unknown parameter '/twil/cart/max_vel_thetta' (did you mean 'max_vel_theta'?) is "
        f"ignored, as some_planner ignores parameters it does not read; allowed: buffer, max_vel_theta, "
        f"publish_cloud, sensor",
        f"{where}:2: unknown parameter '/twil/cart/sensor/topik' (did you mean 'topic'?) is ignored, as "
        f"costmap_2d ignores parameters it does not read; allowed: topic",
    ]
    load()
    assert len(warnings) == 2  # once per parameter and server


def test_a_case_slip_is_suggested_before_a_shorter_name(tmp_path):
    server, warnings, load = _planner_file(tmp_path, "Max_Vel_Theta: 2.0\n")
    load()
    assert "(did you mean 'max_vel_theta'?)" in warnings[0]


def test_wrong_types_and_values_of_a_ros_package_schema_stay_errors(tmp_path):
    server, warnings, load = _planner_file(tmp_path, "max_vel_theta: fast\n")
    with pytest.raises(
        ParamError, match=r"planner.yaml:1: parameter '/twil/cart/max_vel_theta' must be a number"
    ):
        load()


def test_a_parameter_the_simulation_cannot_honour_warns_once_unless_at_its_harmless_value(tmp_path):
    server, warnings, load = _planner_file(tmp_path, "publish_cloud: true\nbuffer: 0.5\n")
    assert load().buffer == 0.5  # still read, as the package reads it
    assert warnings == [
        f"{tmp_path / 'planner.yaml'}:1: parameter '/twil/cart/publish_cloud' = True has no "
        f"effect here: no clouds are published",
        f"{tmp_path / 'planner.yaml'}:2: parameter '/twil/cart/buffer' = 0.5 has no effect "
        f"here: not simulated",
    ]
    server, warnings, load = _planner_file(tmp_path, "publish_cloud: false\n")
    load()
    assert warnings == []


def test_a_renamed_parameter_is_read_under_its_new_name_with_a_warning(tmp_path):
    server, warnings, load = _planner_file(tmp_path, "max_rot_vel: 2.5\n")
    assert load().max_vel_theta == 2.5
    assert warnings == [
        f"{tmp_path / 'planner.yaml'}:1: parameter '/twil/cart/max_rot_vel' has been renamed "
        f"to 'max_vel_theta' (its value is used)"
    ]
    server, warnings, load = _planner_file(tmp_path, "max_rot_vel: 2.5\nmax_vel_theta: 0.5\n")
    assert load().max_vel_theta == 0.5
    assert "(ignored: the new name is set too)" in warnings[0]
    server, warnings, load = _planner_file(tmp_path, "max_rot_vel: slow\n")
    with pytest.raises(
        ParamError, match=r"planner.yaml:1: parameter '/twil/cart/max_vel_theta' must be a number"
    ):
        load()
