"""The roslaunch replica's loader: args, scoping, params, nodes, remaps, includes, errors."""

import textwrap

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import declared_args, load_launch, parse_cli_args
from twil_control.launch.plan import LaunchError

DATA = "tests/data/launch"
MAIN = f"{DATA}/main.launch.yaml"


def write(tmp_path, text, name="test.launch.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def error_of(path, overrides=None) -> str:
    with pytest.raises(LaunchError) as err:
        load_launch(path, overrides)
    return str(err.value)


# --------------------------------------------------------------------------------------
# The full tour (main.launch.yaml)
# --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def main_plan():
    return load_launch(PACKAGE_ROOT / MAIN)


def test_arg_defaults_and_fixed_values(main_plan):
    assert main_plan.args == {
        "world": f"{PACKAGE_ROOT}/sim/worlds/default.sdf",
        "x": "0.0",
        "use_arm": "true",
        "robot_name": "twil",
    }


def test_params_keep_yaml_types_unless_substituted(main_plan):
    params = main_plan.params
    assert params.get("/use_sim_time") is True
    assert params.get("/spawn_x") == 0.0 and type(params.get("/spawn_x")) is float
    assert params.get("/world_file") == f"{PACKAGE_ROOT}/sim/worlds/default.sdf"
    assert params.get("/label") == "42"  # quoted in YAML, no substitution: a string


def test_rosparam_file_is_loaded_into_its_namespace_with_sources(main_plan):
    params = main_plan.params
    assert params.get("/twil/ros_control/cart_linearizing_controller/gains") == {"kp": 100.0, "kd": 20}
    assert (
        params.source_of("/twil/ros_control/joint_state_controller/publish_rate")
        == "tests/data/launch/config/controllers.yaml:4"
    )
    assert params.source_of("/spawn_x") == f"{MAIN}:8"


def test_group_ns_node_ns_args_and_flags(main_plan):
    spawner = main_plan.node("/twil/ros_control/controller_spawner")
    assert (spawner.pkg, spawner.type, spawner.name) == (
        "controller_manager",
        "spawner",
        "controller_spawner",
    )
    assert spawner.namespace == "/twil/ros_control"
    assert spawner.args == ["joint_state_controller", "cart_linearizing_controller"]
    assert spawner.required is True and spawner.output == "screen"
    assert spawner.source == f"{MAIN}:18"
    assert [n.fqn for n in main_plan.nodes] == [
        "/twil/ros_control/controller_spawner",
        "/twil/odom",
        "/base",
        "/qbot/driver",
    ]


def test_node_private_params_and_node_rosparam_in_document_order(main_plan):
    assert main_plan.params.get("/twil/ros_control/controller_spawner") == {
        "stop_timeout": 5.0,
        "publish_rate": 100,
        "start_x": 0.0,
    }
    # a global name among a node's params stays global, as in roslaunch
    assert main_plan.params.get("/global_from_node") == 7
    assert main_plan.params.source_of("/twil/ros_control/controller_spawner/publish_rate") == f"{MAIN}:26"


def test_remaps_resolve_in_the_node_namespace_from_every_enclosing_scope(main_plan):
    spawner = main_plan.node("/twil/ros_control/controller_spawner")
    assert spawner.remappings == {
        "/twil/ros_control/tf": "/tf",  # top-level remap
        "/twil/ros_control/cmd_vel": "/qbot/cmd_vel",  # group remap
        "/twil/ros_control/scan": "/qbot/laser/scan",  # node remap (list form)
        "/twil/ros_control/controller_spawner/status": "/twil/ros_control/status_out",
    }
    odom = main_plan.node("/twil/odom")
    assert odom.remappings == {
        "/twil/tf": "/tf",
        "/twil/cmd_vel": "/qbot/cmd_vel",
        "/twil/odom": "/twil/odom_raw",
    }  # mapping form
    # the group's remap does not leak out of the group
    assert main_plan.node("/base").remappings == {"/tf": "/tf"}


def test_include_gets_its_own_arg_scope_and_namespace(main_plan):
    assert main_plan.params.get("/qbot/robot") == "qbot_twil"
    assert main_plan.params.get("/qbot/driver/rate") == 20
    driver = main_plan.node("/qbot/driver")
    assert driver.source == f"{DATA}/child.launch.yaml:6"
    assert driver.remappings == {"/qbot/tf": "/tf"}  # includer's remaps apply inside


def test_record_entries_union_in_order_and_files_are_listed(main_plan):
    assert main_plan.record_topics == ["/joint_states", "/tf", "/odom"]
    assert [p.relative_to(PACKAGE_ROOT).as_posix() for p in main_plan.files] == [
        MAIN,
        f"{DATA}/config/controllers.yaml",
        f"{DATA}/config/spawner.yaml",
        f"{DATA}/child.launch.yaml",
    ]


def test_record_absent_means_all(tmp_path):
    assert load_launch(write(tmp_path, "launch: []\n")).record_topics is None


# --------------------------------------------------------------------------------------
# Args
# --------------------------------------------------------------------------------------


def test_overrides_replace_defaults_and_are_typed_where_substituted():
    plan = load_launch(MAIN, {"x": "1.5", "use_arm": "false"})
    assert plan.args["x"] == "1.5"
    assert plan.params.get("/spawn_x") == 1.5
    assert [n.fqn for n in plan.nodes] == ["/base", "/qbot/driver"]  # group skipped


def test_unknown_override_is_refused_listing_declared_args():
    assert error_of(MAIN, {"wrold": "x.sdf"}) == (
        f"unknown arg 'wrold' for {MAIN}; declared args: world, x, use_arm, robot_name"
    )


def test_value_args_cannot_be_overridden():
    message = error_of(MAIN, {"robot_name": "other"})
    assert message.startswith(
        f"{MAIN}:6: arg 'robot_name' is declared with 'value' "
        f"(fixed) and cannot be overridden (by robot_name:=other)"
    )


def test_required_arg_must_be_given():
    child = f"{DATA}/child.launch.yaml"
    assert error_of(child) == (
        f"{child}:3: arg 'robot' is required by {child} (declared at line 3): pass it as robot:=<value>"
    )
    assert load_launch(child, {"robot": "r1"}).params.get("/robot") == "r1"


def test_include_must_pass_required_args_and_only_declared_ones(tmp_path):
    missing = write(tmp_path, f"launch:\n  - include: {{file: {DATA}/child.launch.yaml}}\n")
    assert (
        "arg 'robot' is required by tests/data/launch/child.launch.yaml (declared at "
        "line 3): pass it in the include's args" in error_of(missing)
    )
    extra = write(
        tmp_path,
        f"""\
        launch:
          - include: {{file: {DATA}/child.launch.yaml, args: {{robot: r, colour: red}}}}
        """,
    )
    assert error_of(extra) == (
        f"{extra}:2: include of {DATA}/child.launch.yaml passes "
        f"undeclared arg 'colour'; declared args: robot, rate"
    )


def test_pass_all_args_hands_every_arg_down_and_explicit_args_win():
    plan = load_launch(f"{DATA}/pass_all.launch.yaml")
    assert plan.params.get("/robot") == "wam"
    assert plan.params.get("/driver/rate") == 99


def test_args_are_scoped_to_their_group(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - group:
              children:
                - arg: {name: inner, default: a}
          - param: {name: p, value: "$(arg inner)"}
        """,
    )
    assert error_of(path) == (
        f"{path}:5: $(arg inner): arg 'inner' is not declared in {path}; declared args: none"
    )


def test_arg_declared_twice_or_with_default_and_value(tmp_path):
    twice = write(tmp_path, "launch:\n  - arg: {name: a, default: 1}\n  - arg: {name: a}\n")
    assert error_of(twice) == f"{twice}:3: arg 'a' is already declared at line 2"
    both = write(tmp_path, "launch:\n  - arg: {name: a, default: 1, value: 2}\n", "b.yaml")
    assert "has both 'default' and 'value'" in error_of(both)


def test_declared_args_lists_args_as_written():
    args = declared_args(MAIN)
    assert list(args) == ["world", "x", "use_arm", "robot_name"]
    assert args["x"].doc == "spawn x [m]" and args["x"].default == 0.0 and args["x"].line == 4


def test_parse_cli_args():
    assert parse_cli_args(["x:=1.5", "world:=a:=b", "empty:="]) == {"x": "1.5", "world": "a:=b", "empty": ""}
    for bad in ("x=1", "x", ":=3", "a b:=1"):
        with pytest.raises(LaunchError, match=r"expected the form name:=value"):
            parse_cli_args([bad])


# --------------------------------------------------------------------------------------
# Conditions and substitutions
# --------------------------------------------------------------------------------------


def test_if_and_unless():
    plan = load_launch(f"{DATA}/conditions.launch.yaml")
    assert [n.name for n in plan.nodes] == ["headless"]
    assert plan.params.get("/") == {"sim_only": 1, "always": 1}
    plan = load_launch(f"{DATA}/conditions.launch.yaml", {"use_gui": "True", "sim": "0"})
    assert [n.name for n in plan.nodes] == ["gui"]
    assert plan.params.get("/") == {"always": 1}


def test_condition_values_must_be_booleans(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - arg: {name: flag, default: maybe}
          - node: {pkg: p, type: t, name: n, if: "$(arg flag)"}
        """,
    )
    assert error_of(path) == (
        f"{path}:3: 'if' must evaluate to true, false, 1 or 0, got 'maybe' (from '$(arg flag)')"
    )
    both = write(tmp_path, "launch:\n  - param: {name: p, value: 1, if: true, unless: false}\n", "both.yaml")
    assert "cannot set both 'if' and 'unless' on the same element" in error_of(both)


def test_env_optenv_dirname_find_and_deterministic_anon(monkeypatch):
    monkeypatch.setenv("TWIL_TEST_HOME", "/home/test")
    monkeypatch.delenv("TWIL_TEST_UNSET", raising=False)
    plan = load_launch(f"{DATA}/substitutions.launch.yaml")
    assert plan.params.get("/") == {
        "home": "/home/test",
        "opt_set": "/home/test",
        "opt_unset": "a default with spaces",
        "here": str(PACKAGE_ROOT / DATA),
        "pkg": str(PACKAGE_ROOT),
        "same_anon": "probe_1",
    }
    assert [n.name for n in plan.nodes] == ["probe_1", "other_2"]
    again = load_launch(f"{DATA}/substitutions.launch.yaml")
    assert [n.name for n in again.nodes] == ["probe_1", "other_2"]


def test_unset_env_is_an_error(monkeypatch):
    monkeypatch.delenv("TWIL_TEST_HOME", raising=False)
    message = error_of(f"{DATA}/substitutions.launch.yaml")
    assert message.startswith(
        f"{DATA}/substitutions.launch.yaml:2: $(env TWIL_TEST_HOME): "
        f"environment variable 'TWIL_TEST_HOME' is not set"
    )


@pytest.mark.parametrize(
    "value, expected",
    [
        ("$(eval open('x'))", "$(eval open('x')): calling 'open' is not allowed in $(eval ...)"),
        ("$(eval __import__('os').system('echo hi'))", "double underscores are not allowed"),
        ("x $(eval 1 + 1)", "$(eval ...) must be the whole value, as in roslaunch"),
        (
            "$(rospack find x)",
            "unknown substitution $(rospack find x); supported: $(find pkg), "
            "$(arg name), $(env NAME), $(optenv NAME [default]), $(dirname), "
            "$(anon name), $(eval expression)",
        ),
        (
            "$(find no_such_pkg)/worlds",
            "$(find no_such_pkg): package 'no_such_pkg' not found; "
            "searched (--package-path, then ROS_PACKAGE_PATH, then this "
            "project and the packages it provides): ",
        ),
        ("$(arg nope)", "arg 'nope' is not declared in"),
        ("$(arg a b)", "expected exactly one argument, an arg name"),
        ("$(find twil_control", "unterminated substitution"),
        ("$(find $(arg a))", "nested substitutions are not supported"),
    ],
)
def test_bad_substitutions_are_refused_with_file_and_line(tmp_path, value, expected):
    path = write(
        tmp_path,
        f"""\
        launch:
          - arg: {{name: a, default: x}}
          - param: {{name: p, value: "{value}"}}
        """,
    )
    message = error_of(path)
    assert message.startswith(f"{path}:3: ")
    assert expected in message


# --------------------------------------------------------------------------------------
# Params
# --------------------------------------------------------------------------------------


def test_param_types(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - arg: {name: t, default: "true"}
          - param: {name: auto_bool, value: "$(arg t)"}
          - param: {name: plain_string_true, value: "true"}
          - param: {name: as_str, value: 5, type: str}
          - param: {name: as_int, value: "7", type: int}
          - param: {name: as_double, value: 3, type: double}
          - param: {name: as_bool, value: "1", type: bool}
          - param: {name: as_yaml, value: "{a: 1, b: [x, y]}", type: yaml}
          - param: {name: inline_list, value: [1, 2.5]}
          - param: {name: from_text, textfile: tests/data/launch/config/spawner.yaml}
        """,
    )
    params = load_launch(path).params
    assert params.get("/auto_bool") is True
    assert params.get("/plain_string_true") == "true"
    assert params.get("/as_str") == "5"
    assert params.get("/as_int") == 7
    assert params.get("/as_double") == 3.0 and type(params.get("/as_double")) is float
    assert params.get("/as_bool") is True
    assert params.get("/as_yaml") == {"a": 1, "b": ["x", "y"]}
    assert params.get("/inline_list") == [1, 2.5]
    assert params.get("/from_text") == "stop_timeout: 5.0\n"


@pytest.mark.parametrize(
    "entry, expected",
    [
        ("{name: p, value: 2.5, type: int}", "param '/p' has type int but its value 2.5 is not an integer"),
        ("{name: p, value: abc, type: double}", "its value 'abc' is not a number"),
        ("{name: p, value: yes please, type: bool}", "is not true, false, 1 or 0"),
        ("{name: p, value: 1, type: float}", "param type 'float' is not one of str, int, double, bool, yaml"),
        ("{name: p, value: null}", "param '/p' has no value (null)"),
        ("{name: p}", "param 'p' needs exactly one of 'value', 'textfile' or 'command'"),
        ("{name: bad-name, value: 1}", "invalid ROS name 'bad-name'"),
        (
            "{name: p, command: cat robot.urdf}",
            "param command 'cat robot.urdf': 'command' runs only xacro (in-process",
        ),
        ("{name: p, command: xacro robot.urdf.xacro}", "xacro input file not found: robot.urdf.xacro"),
        ("{name: p, binfile: x.bin}", "param: 'binfile' is not supported; use 'textfile'"),
    ],
)
def test_bad_params(tmp_path, entry, expected):
    path = write(tmp_path, f"launch:\n  - param: {entry}\n")
    message = error_of(path)
    assert message.startswith(f"{path}:2: ")
    assert expected in message


def test_private_params_inside_a_node(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - group:
              ns: robot
              children:
                - node:
                    pkg: p
                    type: t
                    name: n
                    params: {rate: 10, sub: {gain: 2.0}}
                    rosparam:
                      - {param: "~limits", value: [1, 2]}
                      - {ns: extra, value: {k: v}}
        """,
    )
    params = load_launch(path).params
    assert params.get("/robot/n") == {"rate": 10, "sub": {"gain": 2.0}, "limits": [1, 2], "extra": {"k": "v"}}
    assert params.source_of("/robot/n/sub/gain") == f"{path}:9"


def test_rosparam_inline_param_delete_and_subst_value(tmp_path):
    config = write(tmp_path, "rate: $(arg rate)\nname: $(arg name)\n", "sub.yaml")
    path = write(
        tmp_path,
        f"""\
        launch:
          - arg: {{name: rate, default: 25}}
          - arg: {{name: name, default: arm}}
          - rosparam: {{ns: ctrl, value: {{a: 1, b: {{c: 2}}}}}}
          - rosparam: {{ns: ctrl, param: single, value: [1, 2]}}
          - rosparam: {{command: delete, ns: ctrl, param: b}}
          - rosparam: {{command: delete, param: never_set}}
          - rosparam: {{file: {config}, ns: substituted, subst_value: true}}
          - rosparam: {{file: {config}, ns: raw}}
          - rosparam: {{value: {{s: "$(arg rate)"}}, ns: inline_raw}}
        """,
    )
    params = load_launch(path).params
    assert params.get("/ctrl") == {"a": 1, "single": [1, 2]}
    assert params.get("/substituted") == {"rate": 25, "name": "arm"}
    assert params.source_of("/substituted/name") == f"{config}:2"
    assert params.get("/raw") == {"rate": "$(arg rate)", "name": "$(arg name)"}  # as roslaunch
    assert params.get("/inline_raw/s") == "$(arg rate)"


def test_rosparam_errors_name_the_launch_line(tmp_path):
    bad_yaml = write(tmp_path, "a: [1,\n", "bad.yaml")
    path = write(tmp_path, f"launch:\n  - rosparam: {{file: {bad_yaml}}}\n")
    message = error_of(path)
    assert message.startswith(f"{bad_yaml}:2:1: YAML syntax error")
    assert message.endswith(f"(loaded by {path}:2)")
    both = write(tmp_path, f"launch:\n  - rosparam: {{file: {bad_yaml}, value: {{a: 1}}}}\n", "both.yaml")
    assert "rosparam load needs exactly one of 'file' or 'value'" in error_of(both)
    dump = write(tmp_path, "launch:\n  - rosparam: {command: dump, file: x.yaml}\n", "d.yaml")
    assert "rosparam 'dump' is not supported" in error_of(dump)


def test_missing_rosparam_file_names_launch_file_line_and_the_places_tried(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = write(
        tmp_path,
        """\
        launch:
          - arg: {name: a, default: 1}
          - rosparam: {file: config/does_not_exist.yaml, ns: x}
        """,
    )
    assert error_of(path) == (
        f"{path}:3: rosparam file not found: config/does_not_exist.yaml (tried "
        f"{tmp_path}/config/does_not_exist.yaml, {PACKAGE_ROOT}/config/does_not_exist.yaml: "
        f"a relative path is looked up in the working directory, then next to the launch file, "
        f"then in the package root)"
    )


def test_relative_paths_are_looked_up_in_the_working_directory_then_the_package_root(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    plan = load_launch(PACKAGE_ROOT / MAIN)
    assert plan.params.get("/twil/ros_control/joint_state_controller/publish_rate") == 50
    assert PACKAGE_ROOT / DATA / "config" / "controllers.yaml" in plan.files
    mine = tmp_path / DATA / "config"  # the user's own file where they stand wins, as in roslaunch
    mine.mkdir(parents=True)
    (mine / "controllers.yaml").write_text("joint_state_controller: {publish_rate: 1}\n")
    plan = load_launch(PACKAGE_ROOT / MAIN)
    assert plan.params.get("/twil/ros_control/joint_state_controller/publish_rate") == 1
    assert mine / "controllers.yaml" in plan.files


def test_launch_file_path_falls_back_to_the_package_root(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert load_launch(MAIN).files[0] == PACKAGE_ROOT / MAIN


# --------------------------------------------------------------------------------------
# Nodes and remaps
# --------------------------------------------------------------------------------------


def test_duplicate_node_names_are_refused(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - node: {pkg: p, type: t, name: n, ns: a}
          - group:
              ns: a
              children:
                - node: {pkg: p, type: t, name: n}
        """,
    )
    assert error_of(path) == (
        f"{path}:6: duplicate node name '/a/n' (first declared at "
        f"{path}:2); roslaunch requires unique node names: change "
        f"'name' or 'ns'"
    )


def test_node_requires_pkg_type_and_a_base_name(tmp_path):
    path = write(tmp_path, "launch:\n  - node: {pkg: p, name: n}\n")
    assert error_of(path) == (
        f"{path}:2: node is missing required key 'type'; a node needs pkg, type and name"
    )
    slash = write(tmp_path, "launch:\n  - node: {pkg: p, type: t, name: a/b}\n", "s.yaml")
    assert "invalid base name 'a/b'" in error_of(slash)


def test_node_args_are_shell_split(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - node: {pkg: p, type: t, name: n, args: "--a 1 'two words' \\"x y\\""}
          - node: {pkg: p, type: t, name: m, args: [a b, c]}
        """,
    )
    plan = load_launch(path)
    assert plan.node("/n").args == ["--a", "1", "two words", "x y"]
    assert plan.node("/m").args == ["a b", "c"]


def test_later_remap_of_the_same_name_wins_and_group_remaps_stay_in_the_group(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - remap: {from: scan, to: /first}
          - remap: {from: scan, to: /second}
          - group:
              ns: g
              children:
                - remap: {from: cmd_vel, to: /qbot/cmd_vel}
                - node: {pkg: p, type: t, name: in_group, remap: {scan: /node_level}}
          - node: {pkg: p, type: t, name: after_group}
        """,
    )
    plan = load_launch(path)
    assert plan.node("/g/in_group").remappings == {"/g/scan": "/node_level", "/g/cmd_vel": "/qbot/cmd_vel"}
    assert plan.node("/after_group").remappings == {"/scan": "/second"}


def test_record_topics_resolve_in_the_group_namespace(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - group: {ns: qbot, children: [{record: {topics: [scan, /tf]}}]}
        """,
    )
    assert load_launch(path).record_topics == ["/qbot/scan", "/tf"]


# --------------------------------------------------------------------------------------
# File-level errors
# --------------------------------------------------------------------------------------


def test_missing_launch_file():
    with pytest.raises(LaunchError, match=r"^launch file not found: launch/nope.yaml \(tried "):
        load_launch("launch/nope.yaml")


def test_launch_yaml_syntax_error_names_file_line_and_column(tmp_path):
    path = write(tmp_path, "launch:\n  - node: {pkg: p, type: t\n  - arg: {name: x}\n")
    assert error_of(path).startswith(f"{path}:3:8: YAML syntax error")


@pytest.mark.parametrize(
    "text, expected",
    [
        (
            "nodes: []\n",
            "a launch file is a mapping with the key 'launch' holding a list of elements, got keys nodes",
        ),
        ("", "got an empty file"),
        ("launch: []\nextra: 1\n", "unknown top-level key 'extra'"),
        ("launch:\n  node: {}\n", "'launch' must be a list of elements"),
        (
            "launch:\n  - {node: {}, arg: {}}\n",
            "each entry must be a mapping with one key naming the element",
        ),
    ],
)
def test_launch_file_shape_errors(tmp_path, text, expected):
    assert expected in error_of(write(tmp_path, text))


def test_unknown_element_lists_the_allowed_ones(tmp_path):
    path = write(tmp_path, "launch:\n  - arg: {name: a, default: 1}\n  - nodes: {}\n")
    assert error_of(path) == (
        f"{path}:3: unknown element 'nodes' (did you mean 'node'?); "
        f"allowed elements: arg, group, include, node, param, record, "
        f"remap, rosparam"
    )
    machine = write(tmp_path, "launch:\n  - machine: {name: m}\n", "m.yaml")
    assert (
        "element 'machine': <machine> declares a remote host; every node runs in this "
        "process (roslaunch XML accepts it with a warning)"
    ) in error_of(machine)


def test_unknown_key_lists_the_allowed_keys_with_its_line(tmp_path):
    path = write(
        tmp_path,
        """\
        launch:
          - node:
              pkg: p
              type: t
              name: n
              parms: {rate: 1}
        """,
    )
    assert error_of(path) == (
        f"{path}:6: unknown key 'parms' in node (did you mean 'params'?); allowed keys: pkg, "
        f"type, name, ns, args, params, rosparam, remap, required, respawn, respawn_delay, "
        f"output, clear_params, if, unless"
    )


def test_include_recursion_is_detected():
    message = error_of(f"{DATA}/recursive_a.launch.yaml")
    assert message == (
        f"{DATA}/recursive_b.launch.yaml:2: include recursion: "
        f"{DATA}/recursive_a.launch.yaml -> {DATA}/recursive_b.launch.yaml -> "
        f"{DATA}/recursive_a.launch.yaml"
    )


def test_missing_include_file(tmp_path):
    path = write(tmp_path, "launch:\n  - include: {file: launch/none.launch.yaml}\n")
    assert error_of(path).startswith(
        f"{path}:2: included launch file not found: launch/none.launch.yaml (tried "
        f"{PACKAGE_ROOT}/launch/none.launch.yaml"
    )


def test_conditions_work_on_include_arg_and_remap(tmp_path):
    path = write(
        tmp_path,
        f"""\
        launch:
          - arg: {{name: mode, default: fast, if: false}}
          - arg: {{name: mode, default: slow, unless: false}}
          - include: {{file: {DATA}/child.launch.yaml, if: "0"}}
          - remap: {{from: a, to: /b, unless: true}}
          - node: {{pkg: p, type: t, name: n, params: {{mode: "$(arg mode)"}}}}
        """,
    )
    plan = load_launch(path)
    assert plan.args == {"mode": "slow"}
    assert plan.files == [path]
    assert plan.node("/n").remappings == {}
    assert plan.params.get("/n/mode") == "slow"


def test_pass_all_args_does_not_override_a_fixed_value_arg(tmp_path):
    child = write(
        tmp_path,
        "launch:\n  - arg: {name: robot, value: fixed}\n  - param: {name: r, value: $(arg robot)}\n",
        "child.yaml",
    )
    parent = write(
        tmp_path,
        f"""\
        launch:
          - arg: {{name: robot, default: wam}}
          - include: {{file: {child}, pass_all_args: true, ns: c}}
        """,
    )
    assert load_launch(parent).params.get("/c/r") == "fixed"
    explicit = write(
        tmp_path, f"launch:\n  - include: {{file: {child}, args: {{robot: x}}}}\n", "explicit.yaml"
    )
    assert (
        "arg 'robot' is declared with 'value' (fixed) and cannot be overridden (by the "
        "include's args)" in error_of(explicit)
    )
