"""roslaunch XML: roslaunch's corner cases (arg override rules, include ns and pass_all_args,
group clear_params, remap scoping, if/unless, ~params, param typing, rosparam text), $(eval)'s
whitelist, hardened parsing (XML bombs, external entities, malformed XML), what is warned and
what is refused, relative paths, and every unknown node type in one error."""

from __future__ import annotations

import logging
import textwrap

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import load_launch
from twil_control.launch.node_types import NodeTypeError
from twil_control.launch.plan import LaunchError
from twil_control.launch.runner import Launch


def write(tmp_path, text, name="test.launch"):
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text).lstrip())
    return path


def error_of(path, overrides=None) -> str:
    with pytest.raises(LaunchError) as err:
        load_launch(path, overrides)
    return str(err.value)


# --------------------------------------------------------------------------------------
# args: value and default, scoping, includes
# --------------------------------------------------------------------------------------

ARGS = """
<launch>
  <arg name="robot" default="qbot"/>
  <arg name="fixed" value="42"/>
  <arg name="speed" default="0.5" doc="m/s"/>
  <param name="robot" value="$(arg robot)"/>
  <param name="fixed" value="$(arg fixed)"/>
  <param name="speed" value="$(arg speed)"/>
</launch>
"""


def test_default_is_overridden_from_the_command_line_and_value_is_not(tmp_path):
    path = write(tmp_path, ARGS)
    assert load_launch(path).params.get("/") == {"robot": "qbot", "fixed": 42, "speed": 0.5}
    plan = load_launch(path, {"robot": "twil", "speed": "2"})
    assert plan.params.get("/") == {"robot": "twil", "fixed": 42, "speed": 2}
    assert plan.args == {"robot": "twil", "fixed": "42", "speed": "2"}
    assert error_of(path, {"fixed": "1"}) == (
        f"{path}:3:3: arg 'fixed' is declared with 'value' (fixed) and cannot be overridden "
        f"(by fixed:=1); declare it with 'default' to make it overridable"
    )


def test_args_are_scoped_to_their_group_and_declared_once(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <group ns="g">
            <arg name="inner" default="a"/>
            <param name="p" value="$(arg inner)"/>
          </group>
          <param name="q" value="$(arg inner)"/>
        </launch>""",
    )
    assert error_of(path) == (
        f"{path}:6:3: $(arg inner): arg 'inner' is not declared in {path}; declared args: none"
    )
    twice = write(tmp_path, '<launch><arg name="a" default="1"/><arg name="a"/></launch>', "twice.launch")
    assert error_of(twice) == f"{twice}:1:36: arg 'a' is already declared at line 1"
    both = write(tmp_path, '<launch><arg name="a" default="1" value="2"/></launch>', "b.launch")
    assert "arg 'a' has both 'default' and 'value'" in error_of(both)


CHILD = """
<launch>
  <arg name="robot"/>
  <arg name="rate" default="10"/>
  <param name="robot" value="$(arg robot)"/>
  <param name="rate" value="$(arg rate)"/>
  <node pkg="p" type="t" name="driver"/>
</launch>
"""


def test_include_ns_args_and_child_arg_defaults(tmp_path):
    write(tmp_path, CHILD, "child.launch")
    path = write(
        tmp_path,
        """
        <launch>
          <arg name="name" default="qbot"/>
          <include file="$(dirname)/child.launch" ns="robot">
            <arg name="robot" value="$(arg name)_1"/>
            <arg name="rate" default="20"/>
          </include>
          <include file="$(dirname)/child.launch" ns="other">
            <arg name="robot" value="x"/>
          </include>
        </launch>""",
    )
    plan = load_launch(path)
    assert plan.params.get("/robot") == {"robot": "qbot_1", "rate": 20}
    assert plan.params.get("/other") == {"robot": "x", "rate": 10}
    assert [n.fqn for n in plan.nodes] == ["/robot/driver", "/other/driver"]
    assert plan.nodes[0].source == f"{tmp_path}/child.launch:6:3"


def test_include_must_give_required_args_and_only_declared_ones(tmp_path):
    write(tmp_path, CHILD, "child.launch")
    missing = write(tmp_path, '<launch><include file="$(dirname)/child.launch"/></launch>', "missing.launch")
    assert (
        f"{tmp_path}/child.launch:2:3: arg 'robot' is required by {tmp_path}/child.launch "
        f"(declared at line 2): pass it in the include's args"
    ) == error_of(missing)
    extra = write(
        tmp_path,
        """
        <launch>
          <include file="$(dirname)/child.launch">
            <arg name="robot" value="r"/>
            <arg name="colour" value="red"/>
          </include>
        </launch>""",
        "extra.launch",
    )
    assert error_of(extra) == (
        f"{extra}:2:3: include of {tmp_path}/child.launch passes "
        f"undeclared arg 'colour'; declared args: robot, rate"
    )


def test_pass_all_args_hands_every_arg_down_and_the_include_args_win(tmp_path):
    write(tmp_path, CHILD, "child.launch")
    path = write(
        tmp_path,
        """
        <launch>
          <arg name="robot" default="wam"/>
          <arg name="rate" default="5"/>
          <arg name="unused" default="not declared by the child"/>
          <include file="$(dirname)/child.launch" pass_all_args="true" ns="a"/>
          <include file="$(dirname)/child.launch" pass_all_args="true" ns="b">
            <arg name="rate" value="99"/>
          </include>
        </launch>""",
    )
    plan = load_launch(path, {"robot": "twil"})
    assert plan.params.get("/a") == {"robot": "twil", "rate": 5}
    assert plan.params.get("/b") == {"robot": "twil", "rate": 99}


# --------------------------------------------------------------------------------------
# groups, clear_params, remaps, if/unless, ~params
# --------------------------------------------------------------------------------------


def test_group_clear_params_needs_ns_and_clears_nothing_this_launch_set(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <param name="/g/early" value="1"/>
          <group ns="g" clear_params="true">
            <param name="late" value="2"/>
          </group>
        </launch>""",
    )
    # roslaunch clears the namespace before it sets any parameter of the launch
    assert load_launch(path).params.get("/g") == {"early": 1, "late": 2}
    bad = write(tmp_path, '<launch><group clear_params="true"/></launch>', "bad.launch")
    assert error_of(bad) == (f"{bad}:1:9: group 'clear_params' needs 'ns' (roslaunch refuses to clear '/')")


def test_remaps_apply_to_later_nodes_in_their_scope_and_includes(tmp_path):
    write(tmp_path, '<launch><node pkg="p" type="t" name="inner"/></launch>', "inc.launch")
    path = write(
        tmp_path,
        """
        <launch>
          <node pkg="p" type="t" name="before"/>
          <remap from="scan" to="/first"/>
          <remap from="scan" to="/second"/>
          <group ns="g">
            <remap from="cmd_vel" to="/qbot/cmd_vel"/>
            <node pkg="p" type="t" name="in_group">
              <remap from="scan" to="/node_level"/>
              <remap from="odom" to="/never" if="false"/>
            </node>
          </group>
          <node pkg="p" type="t" name="after"/>
          <include file="$(dirname)/inc.launch" ns="i"/>
        </launch>""",
    )
    plan = load_launch(path)
    assert plan.node("/before").remappings == {}
    assert plan.node("/g/in_group").remappings == {"/g/scan": "/node_level", "/g/cmd_vel": "/qbot/cmd_vel"}
    assert plan.node("/after").remappings == {"/scan": "/second"}
    assert plan.node("/i/inner").remappings == {"/i/scan": "/second"}


def test_if_and_unless_work_on_every_element(tmp_path):
    write(
        tmp_path,
        '<launch><arg name="v" default="0"/><param name="v" value="$(arg v)"/></launch>',
        "inc.launch",
    )
    path = write(
        tmp_path,
        """
        <launch>
          <arg name="on" default="true"/>
          <arg name="mode" value="a" if="$(arg on)"/>
          <arg name="mode" value="b" unless="$(arg on)"/>
          <param name="mode" value="$(arg mode)"/>
          <group if="false"><node pkg="p" type="t" name="never"/></group>
          <node pkg="p" type="t" name="n" unless="$(eval not on)">
            <param name="kept" value="1" if="$(arg on)"/>
            <param name="dropped" value="1" unless="$(arg on)"/>
            <rosparam if="0">dropped_too: 1</rosparam>
          </node>
          <include file="$(dirname)/inc.launch" ns="i">
            <arg name="v" value="1" if="$(arg on)"/>
            <arg name="v" value="2" unless="$(arg on)"/>
          </include>
        </launch>""",
    )
    plan = load_launch(path)
    assert [n.fqn for n in plan.nodes] == ["/n"]
    assert plan.params.get("/") == {"mode": "a", "n": {"kept": 1}, "i": {"v": 1}}
    plan = load_launch(path, {"on": "False"})
    assert plan.nodes == [] and plan.params.get("/") == {"mode": "b", "i": {"v": 2}}
    bad = write(tmp_path, '<launch><param name="p" value="1" if="yes"/></launch>', "bad.launch")
    assert error_of(bad) == f"{bad}:1:9: 'if' must evaluate to true, false, 1 or 0, got 'yes'"


def test_private_params_outside_a_node_go_to_every_later_node_in_scope(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <node pkg="p" type="t" name="before"/>
          <param name="~rate" value="10"/>
          <group ns="g">
            <param name="~gain" value="2.0"/>
            <node pkg="p" type="t" name="a"/>
          </group>
          <node pkg="p" type="t" name="b">
            <param name="rate" value="20"/>
          </node>
        </launch>""",
    )
    params = load_launch(path).params
    assert not params.has("/before")
    assert params.get("/g/a") == {"rate": 10, "gain": 2.0}
    assert params.get("/b") == {"rate": 20}  # the node's own param wins
    assert params.source_of("/g/a/gain") == f"{path}:5:5"


def test_a_nodes_params_override_its_rosparam_whatever_their_order(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <node pkg="p" type="t" name="n">
            <param name="rate" value="1"/>
            <rosparam>
              rate: 2
              gains: {p: 1.0}
            </rosparam>
            <rosparam param="limits">[1, 2]</rosparam>
          </node>
        </launch>""",
    )
    params = load_launch(path).params
    assert params.get("/n") == {"rate": 1, "gains": {"p": 1.0}, "limits": [1, 2]}
    assert params.source_of("/n/gains/p") == f"{path}:6"


# --------------------------------------------------------------------------------------
# params and rosparam
# --------------------------------------------------------------------------------------


def test_param_values_are_typed_as_roslaunch_types_xml_strings(tmp_path):
    (tmp_path / "text.txt").write_text("some text\n")
    path = write(
        tmp_path,
        """
        <launch>
          <param name="int" value="3"/>
          <param name="float" value=" 3.0 "/>
          <param name="exp_is_a_number" value="1e3"/>
          <param name="bool" value="True"/>
          <param name="str" value="hello"/>
          <param name="forced_str" value="3" type="str"/>
          <param name="forced_double" value="3" type="double"/>
          <param name="boolean" value="1" type="boolean"/>
          <param name="yaml" value="{a: 1, b: [x, y]}" type="yaml"/>
          <param name="auto" value="2.5" type="auto"/>
          <param name="text" textfile="$(dirname)/text.txt"/>
        </launch>""",
    )
    params = load_launch(path).params.get("/")
    assert params == {
        "int": 3,
        "float": 3.0,
        "exp_is_a_number": 1000.0,
        "bool": True,
        "str": "hello",
        "forced_str": "3",
        "forced_double": 3.0,
        "boolean": True,
        "yaml": {"a": 1, "b": ["x", "y"]},
        "auto": 2.5,
        "text": "some text\n",
    }
    assert type(params["forced_double"]) is float and type(params["int"]) is int


def test_rosparam_inline_text_ns_param_delete_and_subst_value(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <arg name="rate" default="25"/>
          <rosparam ns="ctrl">
            a: 1
            b: {c: 2}
            raw: $(arg rate)
          </rosparam>
          <rosparam ns="ctrl" subst_value="true">substituted: $(arg rate)</rosparam>
          <rosparam param="ctrl/single">[1, 2]</rosparam>
          <rosparam command="delete" param="ctrl/b"/>
          <rosparam command="delete" param="never_set"/>
          <rosparam ns="empty"/>
        </launch>""",
    )
    params = load_launch(path).params
    assert params.get("/ctrl") == {"a": 1, "raw": "$(arg rate)", "substituted": 25, "single": [1, 2]}
    assert params.source_of("/ctrl/a") == f"{path}:4"


def test_bad_inline_yaml_names_the_launch_file_line(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <rosparam>
            a: [1,
          </rosparam>
        </launch>""",
    )
    assert error_of(path).startswith(f"{path}:4:")


@pytest.mark.parametrize(
    "element, expected",
    [
        ('<param name="p" binfile="x.bin"/>', "'binfile' is not supported; use 'textfile'"),
        (
            '<param name="p" command="cat /etc/hostname"/>',
            "param command 'cat /etc/hostname': 'command' runs only xacro (in-process",
        ),
        ('<param name="p" value="1" textfile="t"/>', "needs exactly one of 'value', 'textfile' or 'command'"),
        ('<rosparam command="dump" file="x.yaml"/>', "rosparam 'dump' is not supported"),
        ('<param name="p" valeu="1"/>', "unknown attribute 'valeu' in param (did you mean 'value'?)"),
        (
            "<nodes/>",
            "unknown element 'nodes' (did you mean 'node'?); allowed elements: arg, env, "
            "group, include, machine, node, param, remap, rosparam, test",
        ),
        (
            '<node pkg="p" type="t" name="n"><arg name="x"/></node>',
            "unknown element 'arg' in node; allowed elements: env, param, remap, rosparam",
        ),
        ('<node pkg="p" type="t" name="n" respawn_delay="soon"/>', "'respawn_delay' must be a number"),
    ],
)
def test_refused_with_file_line_and_column(tmp_path, element, expected):
    path = write(tmp_path, f"<launch>\n  {element}\n</launch>\n")
    message = error_of(path)
    assert message.startswith(f"{path}:2:3"), message
    assert expected in message


def test_param_command_runs_xacro_in_process(tmp_path):
    (tmp_path / "robot.urdf.xacro").write_text(
        '<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:arg name="width" default="1"/><link name="base_$(arg width)"/></robot>'
    )
    path = write(
        tmp_path,
        """
        <launch>
          <param name="robot_description"
                 command="$(find xacro)/xacro --inorder $(dirname)/robot.urdf.xacro width:=3"/>
          <param name="second" command="xacro.py $(dirname)/robot.urdf.xacro"/>
        </launch>""",
    )
    params = load_launch(path).params
    assert '<link name="base_3"/>' in params.get("/robot_description")
    assert '<link name="base_1"/>' in params.get("/second")


# --------------------------------------------------------------------------------------
# nodes
# --------------------------------------------------------------------------------------


def test_node_attributes_reach_the_node_spec(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <node pkg="p" type="t" name="n" ns="robot" args="--a 1 'two words'" output="screen"
                respawn="true" respawn_delay="2.5" required="false"/>
          <node pkg="p" type="t" name="$(anon worker)" required="true"/>
        </launch>""",
    )
    plan = load_launch(path)
    n = plan.node("/robot/n")
    assert (n.args, n.output, n.respawn, n.respawn_delay, n.required) == (
        ["--a", "1", "two words"],
        "screen",
        True,
        2.5,
        False,
    )
    assert plan.nodes[1].name == "worker_1" and plan.nodes[1].required


def test_in_process_features_are_warned_once_each_and_refused_in_yaml(tmp_path, caplog):
    path = write(
        tmp_path,
        """
        <launch>
          <machine name="m" address="robot.local"/>
          <env name="A" value="1"/>
          <env name="B" value="2"/>
          <node pkg="p" type="t" name="a" cwd="node" launch-prefix="gdb -ex run" machine="m">
            <env name="C" value="3"/>
          </node>
          <node pkg="p" type="t" name="b" cwd="ROS_HOME"/>
          <test test-name="t" pkg="p" type="t"/>
        </launch>""",
    )
    with caplog.at_level(logging.WARNING, logger="twil_control.launch"):
        plan = load_launch(path)
    assert [n.fqn for n in plan.nodes] == ["/a", "/b"]  # a <test> is rostest's, not run
    warned = [r.getMessage() for r in caplog.records]
    assert len(warned) == 6
    for feature in (
        ": machine accepted",
        ": env accepted",
        ": node cwd accepted",
        ": node launch-prefix accepted",
        ": node machine accepted",
        ": test accepted",
    ):
        assert sum(feature in w for w in warned) == 1, feature
    assert any(
        w.startswith(
            f"{path}:5:3: node launch-prefix accepted and ignored: 'launch-prefix' wraps a node process"
        )
        for w in warned
    )
    caplog.clear()
    old = write(tmp_path, '<launch deprecated="use new.launch"/>', "old.launch")
    with caplog.at_level(logging.WARNING, logger="twil_control.launch"):
        load_launch(old)
    assert caplog.records[0].getMessage() == (
        f"{old}:1:1: launch deprecated accepted and ignored: the launch file says it is "
        f"deprecated: use new.launch (warned once per launch)"
    )
    yaml_path = write(tmp_path, "launch:\n  - node: {pkg: p, type: t, name: n, cwd: node}\n", "x.launch.yaml")
    assert (
        "node: 'cwd' sets a node process's working directory; nodes run in this process "
        "(roslaunch XML accepts it with a warning)"
    ) in error_of(yaml_path)
    env_yaml = write(tmp_path, "launch:\n  - env: {name: A, value: '1'}\n", "e.launch.yaml")
    assert "(roslaunch XML accepts it with a warning)" in error_of(env_yaml)


def test_every_unknown_node_type_is_named_in_one_error(tmp_path):
    path = write(
        tmp_path,
        """
        <launch>
          <node pkg="cartographer_ros" type="cartographer_node" name="cartographer"/>
          <node pkg="map_server" type="map_server" name="map_server" args="m.yaml"/>
          <node pkg="pointcloud_to_laserscan" type="pointcloud_to_laserscan_node" name="p2l"/>
          <node pkg="hector_mapping" type="hector_mapping" name="hector"/>
        </launch>""",
    )
    with pytest.raises(NodeTypeError) as err:
        Launch(load_launch(path))
    message = str(err.value)
    assert message.startswith(
        "3 unsupported node types in this launch:\n"
        f"  cartographer_ros/cartographer_node (node /cartographer, {path}:2:3)\n"
        f"  pointcloud_to_laserscan/pointcloud_to_laserscan_node (node /p2l, {path}:4:3)\n"
        f"  hector_mapping/hector_mapping (node /hector, {path}:5:3)\n"
        f"known types: "
    )
    assert "gmapping/slam_gmapping" in message and "map_server/map_server" in message


def test_a_rosbag_record_node_is_the_recording(tmp_path, caplog):
    path = write(
        tmp_path,
        """
        <launch>
          <group ns="qbot">
            <node pkg="rosbag" type="record" name="rec" args="-O run.bag scan /tf"/>
          </group>
        </launch>""",
    )
    with caplog.at_level(logging.WARNING, logger="twil_control.launch"):
        plan = load_launch(path)
    assert plan.record_topics == ["/qbot/scan", "/tf"] and plan.nodes == []
    assert (plan.record_output.name, plan.record_output.prefix) == ("run.bag", False)  # the run's bag
    everything = write(
        tmp_path,
        '<launch><node pkg="rosbag" type="record" name="r" args="-a"/>'
        '<node pkg="rosbag" type="record" name="s" args="/tf"/></launch>',
        "all.launch",
    )
    assert load_launch(everything).record_topics is None
    regex = write(
        tmp_path, '<launch><node pkg="rosbag" type="record" name="r" args="-e .*"/></launch>', "regex.launch"
    )
    assert "rosbag record option '-e' is not supported" in error_of(regex)


# --------------------------------------------------------------------------------------
# $(eval)
# --------------------------------------------------------------------------------------


def test_eval_as_roslaunch_users_write_it(tmp_path, monkeypatch):
    monkeypatch.setenv("TWIL_TEST_ROBOT", "qbot")
    path = write(
        tmp_path,
        """
        <launch>
          <arg name="x" default="1.5"/>
          <arg name="n" default="3"/>
          <arg name="robot" default="qbot"/>
          <param name="sum" value="$(eval x * 2 + n)"/>
          <param name="bare_and_call" value="$(eval arg('n') ** 2 == n * n)"/>
          <param name="text" value="$(eval robot.upper() + '_' + str(n))"/>
          <param name="choice" value="$(eval 'fast' if x &gt; 1 else 'slow')"/>
          <param name="env" value="$(eval env('TWIL_TEST_ROBOT') == robot)"/>
          <param name="opt" value="$(eval optenv('TWIL_NOT_SET', 'dflt'))"/>
          <param name="math" value="$(eval round(degrees(pi / 2)))"/>
          <param name="pkg" value="$(eval find('twil_control') + '/sim')"/>
          <node pkg="p" type="t" name="n" if="$(eval n &gt;= 3 and robot in ['qbot', 'twil'])"/>
        </launch>""",
    )
    plan = load_launch(path)
    assert plan.params.get("/") == {
        "sum": 6.0,
        "bare_and_call": True,
        "text": "QBOT_3",
        "choice": "fast",
        "env": True,
        "opt": "dflt",
        "math": 90,
        "pkg": f"{PACKAGE_ROOT}/sim",
    }
    assert [n.name for n in plan.nodes] == ["n"]


@pytest.mark.parametrize(
    "expression, expected",
    [
        ("__import__('os').system('true')", "double underscores are not allowed"),
        ("open('/etc/passwd').read()", "calling 'open' is not allowed"),
        ("eval('1')", "calling 'eval' is not allowed"),
        ("robot.encode()", "the method 'encode' of a str is not allowed"),
        ("[c for c in robot]", "ListComp is not allowed"),
        ("(lambda: 1)()", "this call is not allowed"),
        ("robot.__class__", "double underscores are not allowed"),
        ("x.real", "Attribute is not allowed"),
        ("9 ** 9 ** 9", "is too large"),
        ("'a' * 10 ** 8", "result longer than 100000 items"),
        ("'%0999999d' % 1", "string formatting with % is not allowed"),
        ("undeclared + 1", "name 'undeclared' is not a declared arg"),
        ("1 +", "not a valid expression"),
    ],
)
def test_eval_outside_the_whitelist_is_an_error_naming_the_expression(tmp_path, expression, expected):
    from xml.sax.saxutils import quoteattr

    path = write(
        tmp_path,
        f"""
        <launch>
          <arg name="robot" default="qbot"/>
          <arg name="x" default="1"/>
          <param name="p" value={quoteattr(f"$(eval {expression})")}/>
        </launch>""",
    )
    message = error_of(path)
    assert message.startswith(f"{path}:4:3: $(eval {expression}): "), message
    assert expected in message


def test_eval_must_be_the_whole_value_and_works_in_yaml_too(tmp_path):
    path = write(tmp_path, '<launch><param name="p" value="a $(eval 1)"/></launch>')
    assert "$(eval ...) must be the whole value, as in roslaunch" in error_of(path)
    yaml_path = write(
        tmp_path,
        'launch:\n  - arg: {name: n, default: "2"}\n  - param: {name: p, value: "$(eval n * 21)"}\n',
        "e.launch.yaml",
    )
    assert load_launch(yaml_path).params.get("/p") == 42


# --------------------------------------------------------------------------------------
# hardened parsing
# --------------------------------------------------------------------------------------

BILLION_LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE launch [
  <!ENTITY lol "lol">
  <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
  <!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">
]>
<launch><param name="p" value="&lol3;"/></launch>
"""

EXTERNAL_ENTITY = """<?xml version="1.0"?>
<!DOCTYPE launch [<!ENTITY secret SYSTEM "file:///etc/passwd">]>
<launch><param name="p" value="&secret;"/></launch>
"""

EXTERNAL_DTD = """<?xml version="1.0"?>
<!DOCTYPE launch SYSTEM "http://127.0.0.1:9/launch.dtd">
<launch/>
"""


@pytest.mark.parametrize(
    "text, expected",
    [
        (BILLION_LAUGHS, ":3:16: XML entity declaration 'lol' refused: entities can expand without bound"),
        (EXTERNAL_ENTITY, ":2:62: XML entity declaration 'secret' refused"),
        (EXTERNAL_DTD, ":2:56: external XML reference refused"),
        ("<launch>\n  <node pkg='p' type='t' name='n'>\n</launch>\n", ":3:3: malformed XML: mismatched tag"),
        ("", ":1:1: malformed XML: no element found"),
        ("<launch><a/></launch><extra/>", ":1:22: malformed XML: junk after document element"),
        ("<robot name='r'/>", ":1:1: the root element must be <launch>, got <robot>"),
        (
            '<launch><node children="x" pkg="p" type="t" name="n"/></launch>',
            ":1:9: <node> has an attribute 'children'",
        ),
    ],
)
def test_hostile_or_malformed_xml_is_refused_with_line_and_column(tmp_path, text, expected):
    path = tmp_path / "bad.launch"
    path.write_text(text)
    message = error_of(path)
    assert message.startswith(f"{path}{expected}"), message


def test_an_included_malformed_file_names_its_includer(tmp_path):
    write(tmp_path, "<launch><oops></launch>", "inc.launch")
    path = write(tmp_path, '<launch>\n  <include file="$(dirname)/inc.launch"/>\n</launch>')
    assert error_of(path) == (
        f"{tmp_path}/inc.launch:1:17: malformed XML: mismatched tag (included from {path}:2:3)"
    )


# --------------------------------------------------------------------------------------
# relative paths
# --------------------------------------------------------------------------------------


def test_relative_files_resolve_from_the_working_directory_then_the_launch_files_dir(
    tmp_path, monkeypatch, caplog
):
    launch_dir = tmp_path / "pkg" / "launch"
    write(launch_dir, "rate: 1\n", "params/here.yaml")
    write(launch_dir, "rate: 2\n", "params/both.yaml")
    write(tmp_path / "cwd", "rate: 3\n", "params/both.yaml")
    path = write(
        launch_dir,
        """
        <launch>
          <rosparam file="params/here.yaml" ns="here"/>
          <rosparam file="params/both.yaml" ns="both"/>
        </launch>""",
    )
    monkeypatch.chdir(tmp_path / "cwd")
    with caplog.at_level(logging.DEBUG, logger="twil_control.launch"):
        plan = load_launch(path)
    assert plan.params.get("/") == {"here": {"rate": 1}, "both": {"rate": 3}}
    assert f"rosparam file 'params/both.yaml' found as {tmp_path}/cwd/params/both.yaml" in caplog.text
    missing = write(
        launch_dir, '<launch>\n  <rosparam file="params/none.yaml"/>\n</launch>', "missing.launch"
    )
    assert error_of(missing) == (
        f"{missing}:2:3: rosparam file not found: params/none.yaml (tried "
        f"{tmp_path}/cwd/params/none.yaml, {launch_dir}/params/none.yaml, "
        f"{PACKAGE_ROOT}/params/none.yaml: a relative path is looked up in the working "
        f"directory, then next to the launch file, then in the package root)"
    )
