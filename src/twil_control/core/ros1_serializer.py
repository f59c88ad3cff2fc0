"""ROS 1 wire bytes of typestore messages, from one generated function per message type.

rosbags' serialize_ros1 calls a function per nested message and packs every number with a
struct call of its own: a nav_msgs/Path of 200 poses is some 3,000 calls. Here each type gets
one function (generated from the typestore's field definitions, nested types inlined) that packs
every run of fixed-size fields, across nested messages, with one precompiled struct, and copies
numeric arrays as their bytes. The output is rosbags' byte for byte (tests/test_ros1_serializer.py
compares them on every type of the store). Anything unusual (a big-endian or non-numpy array, a
type with float128) falls back to rosbags, which then serialises it or raises its own error.
"""

from __future__ import annotations

import keyword
import struct
import sys
from collections.abc import Callable

import numpy as np
from rosbags.interfaces import Nodetype

#: struct codes of ROS 1 base types, as rosbags packs them (byte signed, char unsigned)
CODES = {
    "bool": "?",
    "byte": "b",
    "char": "B",
    "int8": "b",
    "int16": "h",
    "int32": "i",
    "int64": "q",
    "uint8": "B",
    "uint16": "H",
    "uint32": "I",
    "uint64": "Q",
    "float32": "f",
    "float64": "d",
}


class Unsupported(Exception):
    """A value or type the generated code leaves to rosbags."""


class _Generator:
    """Python source of one type's serialiser: `lines` append to `parts`, `run` holds the
    fixed-size fields (struct code, expression) not packed yet."""

    def __init__(self, typestore) -> None:
        self.store = typestore
        self.lines: list[str] = []
        self.structs: dict[str, str] = {}  # format -> the name its packer has in the code
        self.run: list[tuple[str, str]] = []
        self.names = 0

    def name(self, prefix: str) -> str:
        self.names += 1
        return f"{prefix}{self.names}"

    def flush(self, indent: str) -> None:
        if not self.run:
            return
        fmt = "<" + "".join(code for code, _ in self.run)
        name = self.structs.setdefault(fmt, f"pack{len(self.structs)}")
        self.lines.append(f"{indent}a({name}({', '.join(expr for _, expr in self.run)}))")
        self.run = []

    def message(self, typename: str, expr: str, indent: str) -> None:
        fields = [
            f for f in self.store.fielddefs[typename][1] if f[0] != "structure_needs_at_least_one_member"
        ]
        if len(fields) > 1 and "." in expr:  # a nested message: look it up once
            var = self.name("m")
            self.lines.append(f"{indent}{var} = {expr}")
            expr = var
        for field, desc in fields:
            name = f"{field}_" if keyword.iskeyword(field) else field  # rosbags' attribute name
            self.field(desc, f"{expr}.{name}", indent)

    def field(self, desc, expr: str, indent: str) -> None:
        kind = desc[0]
        if kind == Nodetype.NAME:
            self.message(desc[1], expr, indent)
        elif kind == Nodetype.BASE:
            self.base(desc[1][0], expr, indent)
        elif kind == Nodetype.ARRAY:
            sub, length = desc[1]
            var = self.name("v")
            self.lines.append(f"{indent}{var} = {expr}")
            self.lines.append(f"{indent}if len({var}) != {length}: raise Unsupported")
            self.items(sub, var, indent)
        else:
            sub = desc[1][0]
            var = self.name("v")
            self.lines.append(f"{indent}{var} = {expr}")
            self.run.append(("I", f"len({var})"))
            self.items(sub, var, indent)

    def base(self, basetype: str, expr: str, indent: str) -> None:
        if basetype == "string":
            var = self.name("s")
            self.lines.append(f"{indent}{var} = {expr}.encode()")
            self.run.append(("I", f"len({var})"))
            self.flush(indent)
            self.lines.append(f"{indent}a({var})")
        elif basetype in CODES:
            self.run.append((CODES[basetype], expr))
        else:
            raise Unsupported(basetype)

    def items(self, sub, var: str, indent: str) -> None:
        """The elements of array or sequence `var` (its length already checked or queued)."""
        if sub[0] == Nodetype.BASE and sub[1][0] in CODES:
            self.flush(indent)
            size = struct.calcsize(CODES[sub[1][0]])
            self.lines.append(f"{indent}a(numeric({var}, {size}))")
            return
        self.flush(indent)
        item = self.name("e")
        self.lines.append(f"{indent}for {item} in {var}:")
        self.field(sub, item, indent + "  ")
        self.flush(indent + "  ")


def numeric(array, itemsize: int):
    """A numeric array's bytes as rosbags writes them (its buffer, little-endian)."""
    if type(array) is not np.ndarray or array.ndim != 1 or array.dtype.itemsize != itemsize:
        raise Unsupported
    if array.dtype.byteorder == ">" or not array.flags.c_contiguous:
        raise Unsupported
    return array.view(np.uint8)


def generate(typestore, typename: str) -> Callable[[object], bytes]:
    """A function msg -> bytes for `typename`; Unsupported if the type needs rosbags."""
    if sys.byteorder != "little":
        raise Unsupported("big-endian host")
    gen = _Generator(typestore)
    gen.message(typename, "msg", "  ")
    gen.flush("  ")
    body = "\n".join(gen.lines)
    source = f"def serialize(msg):\n  parts = []\n  a = parts.append\n{body}\n  return b''.join(parts)\n"
    namespace: dict[str, object] = {"Unsupported": Unsupported, "numeric": numeric}
    namespace.update({name: struct.Struct(fmt).pack for fmt, name in gen.structs.items()})
    exec(compile(source, f"<ros1 serializer of {typename}>", "exec"), namespace)
    return namespace["serialize"]  # pyright: ignore[reportReturnType]


class Serializers:
    """One generated serialiser per type, made on first use; rosbags for the rest."""

    def __init__(self, typestore) -> None:
        self.store = typestore
        #: typename -> its generated function, or None when rosbags serialises the type
        self._functions: dict[str, Callable[[object], bytes] | None] = {}
        self.fallbacks = 0  # messages left to rosbags

    def serialize(self, msg, typename: str) -> bytes:
        if typename in self._functions:
            function = self._functions[typename]
        else:
            try:
                function = generate(self.store, typename)
            except Unsupported:
                function = None
            self._functions[typename] = function
        if function is not None:
            try:
                return function(msg)
            except Exception:  # anything unusual: rosbags serialises it or raises its own error
                pass
        self.fallbacks += 1
        return bytes(self.store.serialize_ros1(msg, typename))
