"""ROS 1 graph names resolve exactly as rospy/roscpp resolve them (wiki.ros.org/Names)."""

import pytest

from twil_control.core import names
from twil_control.core.names import GraphNameError


@pytest.mark.parametrize("name", ["a", "/a", "~a", "/a/b_2/c", "a/b", "~", "/", "A1_b", "~a/b"])
def test_legal_names_validate(name):
    assert names.validate(name) == name


@pytest.mark.parametrize(
    "name, fragment",
    [
        ("", "empty string is not a ROS name"),
        ("1abc", "cannot start with '1'"),
        ("_a", "cannot start with '_'"),
        ("a-b", "character '-' at position 1 is not allowed"),
        ("a b", "character ' ' at position 1"),
        ("a~b", "character '~' at position 1"),
        ("a//b", "'//' is not allowed"),
        ("/é", "character 'é'"),
    ],
)
def test_illegal_names_are_refused_naming_the_name_and_rule(name, fragment):
    with pytest.raises(GraphNameError) as err:
        names.validate(name)
    assert fragment in str(err.value)
    if name:
        assert repr(name) in str(err.value)
        assert "letters, digits, '_' and '/'" in str(err.value) or "//" in fragment


def test_node_names_must_be_base_names():
    assert names.validate_base("driver") == "driver"
    for bad in ("a/b", "/a", "~a"):
        with pytest.raises(GraphNameError, match="put the namespace in 'ns'"):
            names.validate_base(bad)


@pytest.mark.parametrize(
    "name, expected",
    [
        ("/a//b/", "/a/b"),
        ("a/b/", "a/b"),
        ("/", "/"),
        ("", ""),
        ("~/a", "~/a"),
        ("//a", "/a"),
    ],
)
def test_canonical_drops_empty_tokens(name, expected):
    assert names.canonical(name) == expected


@pytest.mark.parametrize(
    "ns, name, expected",
    [
        ("/a", "b", "/a/b"),
        ("/a/", "b", "/a/b"),
        ("/", "b", "/b"),
        ("", "b", "b"),
        ("/a", "/b", "/b"),  # global names ignore the namespace
        ("/a", "~b", "~b"),  # private names too
        ("~", "b", "~b"),
        ("/a", "", "/a"),
    ],
)
def test_join_follows_rospy_ns_join(ns, name, expected):
    assert names.join(ns, name) == expected


@pytest.mark.parametrize(
    "name, parent, base",
    [
        ("/a/b/c", "/a/b", "c"),
        ("/a", "/", "a"),
        ("/a/b/", "/a", "b"),
        ("/", "/", ""),
    ],
)
def test_namespace_of_and_basename(name, parent, base):
    assert names.namespace_of(name) == parent
    assert names.basename(name) == base


@pytest.mark.parametrize(
    "name, ns, node, expected",
    [
        ("/chatter", "/ns", "talker", "/chatter"),  # global stays
        ("chatter", "/", "talker", "/chatter"),  # relative in the root
        ("chatter", "/wg", "talker", "/wg/chatter"),  # relative in a namespace
        ("a/chatter", "/wg", None, "/wg/a/chatter"),
        ("chatter", "wg", None, "/wg/chatter"),  # namespaces are always global
        ("~chatter", "/", "talker", "/talker/chatter"),  # private: under the node's name
        ("~chatter", "/wg", "talker", "/wg/talker/chatter"),  # ... including its namespace
        ("~a/b", "/x/y", "n", "/x/y/n/a/b"),
        ("~", "/wg", "talker", "/wg/talker"),
        ("/a//b/", "/", None, "/a/b"),  # results are canonical
    ],
)
def test_resolve_matches_the_ros_wiki_table(name, ns, node, expected):
    assert names.resolve(name, ns, node) == expected


def test_private_name_without_a_node_is_an_error():
    with pytest.raises(GraphNameError, match="private name '~rate' needs a node"):
        names.resolve("~rate", "/wg")


def test_remapping_applies_to_the_resolved_name_only_once():
    remaps = {"/wg/chatter": "/other/chatter", "/other/chatter": "/third"}
    assert names.resolve("chatter", "/wg", "talker", remaps) == "/other/chatter"
    assert names.resolve("/wg/chatter", "/", None, remaps) == "/other/chatter"
    # the same relative name in another namespace resolves elsewhere: no remap
    assert names.resolve("chatter", "/", "talker", remaps) == "/chatter"


def test_resolve_remappings_resolves_both_sides_in_the_node_context():
    mapping = {"scan": "base_scan", "~out": "/global_out", "/abs": "~mine"}
    resolved = names.resolve_remappings(mapping, "/robot", "laser")
    assert resolved == {
        "/robot/scan": "/robot/base_scan",
        "/robot/laser/out": "/global_out",
        "/abs": "/robot/laser/mine",
    }
    # and resolve() then applies them as a node would
    assert names.resolve("scan", "/robot", "laser", resolved) == "/robot/base_scan"
    assert names.resolve("~out", "/robot", "laser", resolved) == "/global_out"


def test_resolve_remappings_refuses_illegal_names():
    with pytest.raises(GraphNameError, match="'bad name'"):
        names.resolve_remappings({"bad name": "x"}, "/", "n")


def test_node_fqn():
    assert names.node_fqn("/twil/ros_control", "spawner") == "/twil/ros_control/spawner"
    assert names.node_fqn("/", "spawner") == "/spawner"
    with pytest.raises(GraphNameError):
        names.node_fqn("/", "a/b")
