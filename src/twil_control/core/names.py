"""ROS 1 graph names: validation, namespaces, resolution and remapping.

The rules are those of http://wiki.ros.org/Names and rospy's ``rosgraph.names`` (what roslaunch
uses), so a name means here exactly what it means to a ROS node: global, relative and private
names, remappings applied once after resolution. Names come back canonical (docs/runtime.md).
"""

from __future__ import annotations

from collections.abc import Mapping

from twil_control.errors import TwilControlError

SEP = "/"
PRIV = "~"

_ALPHA = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ")
_BODY = _ALPHA | frozenset("0123456789_/")
_RULE = "a ROS name starts with a letter, '/' or '~' and continues with letters, digits, '_' and '/'"


class GraphNameError(TwilControlError, ValueError):
    """A name that ROS would refuse, or a name that cannot be resolved."""


def validate(name: str) -> str:
    """Return ``name`` if ROS accepts it as a graph name, else raise GraphNameError.

    Same rule as rospy's ``is_legal_name`` (``[~/A-Za-z][A-Za-z0-9_/]*`` without
    ``//``), restricted to ASCII like roscpp. The empty name is refused here: ROS
    reads it as "the namespace itself", which in a file is always a mistake.
    """
    if not isinstance(name, str):
        raise GraphNameError(f"a ROS name must be a string, got {name!r}")
    if not name:
        raise GraphNameError(f"the empty string is not a ROS name; {_RULE}")
    if name[0] not in _ALPHA and name[0] not in (SEP, PRIV):
        raise GraphNameError(f"invalid ROS name {name!r}: it cannot start with {name[0]!r}; {_RULE}")
    for i, ch in enumerate(name[1:], start=1):
        if ch not in _BODY:
            raise GraphNameError(
                f"invalid ROS name {name!r}: character {ch!r} at position {i} is not allowed; {_RULE}"
            )
    if "//" in name:
        raise GraphNameError(f"invalid ROS name {name!r}: '//' is not allowed")
    return name


def validate_base(name: str) -> str:
    """Return ``name`` if it is a legal *base* name (one token: no '/', no '~').

    Node names are base names; roslaunch refuses ``<node name="a/b">`` because the
    namespace belongs in ``ns=``.
    """
    validate(name)
    if SEP in name or name.startswith(PRIV):
        raise GraphNameError(
            f"invalid base name {name!r}: a node name is a single token without '/' "
            f"or '~' (put the namespace in 'ns')"
        )
    return name


def is_global(name: str) -> bool:
    return name.startswith(SEP)


def is_private(name: str) -> bool:
    return name.startswith(PRIV)


def canonical(name: str) -> str:
    """Drop empty tokens: ``/a//b/`` -> ``/a/b``; ``/`` and ``""`` stay as they are."""
    if not name or name == SEP:
        return name
    body = SEP.join(token for token in name.split(SEP) if token)
    return SEP + body if name.startswith(SEP) else body


def join(ns: str, name: str) -> str:
    """rospy's ``ns_join``: global and private names ignore ``ns``; the rest go under it."""
    if not name:
        return canonical(ns)
    if is_global(name) or is_private(name):
        return canonical(name)
    if ns == PRIV:
        return PRIV + canonical(name)
    if not ns:
        return canonical(name)
    return canonical(ns + SEP + name)


def namespace_of(name: str) -> str:
    """The parent namespace: ``/a/b`` -> ``/a``, ``/a`` -> ``/``, ``a/b`` -> ``a``."""
    name = canonical(name)
    head, sep, _ = name.rpartition(SEP)
    if not sep or not head:
        return SEP
    return head


def basename(name: str) -> str:
    """The last token: ``/a/b`` -> ``b``, ``/`` -> ``""``."""
    return canonical(name).rpartition(SEP)[2]


def node_fqn(namespace: str, node_name: str) -> str:
    """The fully qualified name of node ``node_name`` started in ``namespace``."""
    return join(_global_ns(namespace), validate_base(node_name))


def resolve(
    name: str, namespace: str = SEP, node_name: str | None = None, remappings: Mapping[str, str] | None = None
) -> str:
    """Resolve ``name`` as a node named ``node_name`` in ``namespace`` would.

    ``remappings`` maps resolved names to resolved names (see resolve_remappings);
    it is applied once, to the resolved name, exactly like roscpp/rospy. Like
    roscpp, a ``//`` is cleaned here rather than refused.
    """
    ns = _global_ns(namespace)
    validate(name if "//" not in name else canonical(name))  # roscpp cleans '//' here
    if is_global(name):
        resolved = canonical(name)
    elif is_private(name):
        if node_name is None:
            raise GraphNameError(
                f"private name {name!r} needs a node to resolve against "
                f"('~' means the node's own namespace), but no node name was given"
            )
        resolved = canonical(node_fqn(ns, node_name) + SEP + name[1:])
    else:
        resolved = canonical(ns + SEP + name)
    if remappings and resolved in remappings:
        return remappings[resolved]
    return resolved


def resolve_remappings(mapping: Mapping[str, str], namespace: str, node_name: str | None) -> dict[str, str]:
    """Resolve both sides of a node's ``from:=to`` remappings in the node's context.

    roscpp's ``names::init`` does this when the node starts: ``from`` and ``to`` are
    each resolved in the node's namespace (``~`` meaning the node itself), and
    later entries win when two ``from`` names resolve to the same name.
    """
    resolved: dict[str, str] = {}
    for source, target in mapping.items():
        resolved[resolve(source, namespace, node_name)] = resolve(target, namespace, node_name)
    return resolved


def _global_ns(namespace: str) -> str:
    """A namespace as roscpp stores it: validated, global, canonical."""
    if not namespace:
        return SEP
    validate(namespace)
    if is_private(namespace):
        raise GraphNameError(f"a namespace cannot be private: {namespace!r}")
    return canonical(namespace if is_global(namespace) else SEP + namespace)
