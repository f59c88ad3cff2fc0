"""ROS 1 wire bytes of typestore messages, by a Python function generated once per type.

rosbags' serialize_ros1 is generic: each message first walks its type to compute the size,
then writes field by field, fetching every nested type's serializer from the typestore and
calling one ``struct.pack_into`` per primitive. For the recorder's hot types (Odometry,
TFMessage, JointState at 100-200 Hz) that is most of the recording cost.

Here each type gets its own function, generated from the typestore's field definitions the
first time the type is serialised:

- nested messages are flattened into the one function (``m.pose.pose.position.x``), so no
  definition is looked up per message;
- every run of consecutive fixed-size primitives, across nested messages, together with the
  uint32 length prefixes of the strings and sequences that follow it, is packed by one
  precompiled ``struct.Struct``;
- primitive arrays are numpy's ``tobytes()`` when the array has exactly the field's
  little-endian dtype, and ``struct.pack`` of the items for lists and tuples;
- strings are their utf-8 bytes after a uint32 byte count; sequences are a uint32 element
  count then the elements; fixed-length arrays have no count;
- the pieces are joined once with ``b"".join``.

The byte layout is the typestore's ROS 1 layout, which is what rosbags writes; in particular
the Noetic store maps ROS 1 ``time``/``duration`` to builtin_interfaces Time/Duration with an
int32 ``sec`` and uint32 ``nanosec`` (4 + 4 bytes, as ROS 1's uint32 secs/nsecs for times
before 2038), and rosbags' placeholder field of empty messages is not written.

Never a wrong byte: a value the generated code does not take as it is (a numpy array of
another dtype or byte order, a fixed array of the wrong length, an out-of-range integer, a
type without a generator such as float128) makes ``Ros1Serializer.serialize`` hand the
message to rosbags' serializer, which either writes it or raises its own error, exactly as
before.
"""
from __future__ import annotations

import struct
from typing import Callable

import numpy as np
from rosbags.interfaces import Nodetype

# struct codes of the ROS 1 primitives (little-endian, no padding; '<' is in every format)
STRUCT_CODES = {
    "bool": "?", "byte": "b", "char": "B", "int8": "b", "uint8": "B",
    "int16": "h", "uint16": "H", "int32": "i", "uint32": "I",
    "int64": "q", "uint64": "Q", "float32": "f", "float64": "d",
}
# numpy dtypes of primitive arrays as rosbags deserialises them (byte is int8, char uint8)
ARRAY_DTYPES = {name: np.dtype("<" + code) if code not in "?bB" else np.dtype(code)
                for name, code in STRUCT_CODES.items()}

# rosbags' stand-in member of messages with no fields (std_msgs/Empty); ROS 1 writes nothing
_PLACEHOLDER = "structure_needs_at_least_one_member"
_MAX_DEPTH = 32  # ROS 1 types cannot nest themselves; deeper means a malformed store

Serializer = Callable[[object], bytes]


class UnsupportedType(ValueError):
    """A message type the generator has no code for; rosbags serialises it instead."""


class _NotFastPath(Exception):
    """A value the generated code does not take as it is (raised inside generated code)."""


def primitive_array_bytes(val, dtype: np.dtype, code: str) -> bytes:
    """Little-endian bytes of a 1-D primitive array: a numpy array of exactly ``dtype``, or a
    list/tuple of Python numbers. Anything else is left to rosbags."""
    if type(val) is np.ndarray:
        if val.ndim == 1 and (val.dtype is dtype or val.dtype == dtype):
            return val.tobytes()
        raise _NotFastPath
    if type(val) is list or type(val) is tuple:
        return struct.pack(f"<{len(val)}{code}", *val)
    raise _NotFastPath


class _Generator:
    """Writes the source of one type's serializer: ``def serialize(m): ... return bytes``.

    Output pieces are kept pending (``_chunks``: expressions, in wire order) and written out
    as one tuple before any loop and at the end of each loop body; primitives pending in
    ``_run_codes``/``_run_values`` become one ``struct.Struct.pack`` piece when a piece of
    another kind (string bytes, array bytes) or a flush comes. Statements (locals for nested
    messages, encoded strings, length checks) are written at once; the pieces only read
    locals that are never reassigned, so evaluating them later gives the same values.
    """

    def __init__(self, store) -> None:
        self._store = store
        self.namespace: dict[str, object] = {
            "_array_bytes": primitive_array_bytes, "_NotFastPath": _NotFastPath,
            "_ndarray": np.ndarray}
        self._lines: list[str] = []
        self._chunks: list[str] = []
        self._run_codes: list[str] = []
        self._run_values: list[str] = []
        self._counter = 0
        self.has_loops = False

    def source(self, typename: str) -> str:
        body_start = len(self._lines)
        self._message(typename, "m", indent=1, depth=0)
        self._close_run()
        if self.has_loops:
            self._flush(indent=1)
            self._lines.insert(body_start, "    _out = []")
            self._lines.append("    return b''.join(_out)")
        elif not self._chunks:
            self._lines.append("    return b''")
        elif len(self._chunks) == 1:
            self._lines.append(f"    return {self._chunks[0]}")
        else:
            self._lines.append(f"    return b''.join(({', '.join(self._chunks)},))")
        return "\n".join(["def serialize(m):", *self._lines]) + "\n"

    # -- names, statements and pieces -------------------------------------------------------

    def _name(self, stem: str) -> str:
        self._counter += 1
        return f"_{stem}{self._counter}"

    def _const(self, stem: str, value: object) -> str:
        name = self._name(stem)
        self.namespace[name] = value
        return name

    def _statement(self, indent: int, text: str) -> None:
        self._lines.append("    " * indent + text)

    def _primitive(self, code: str, expr: str) -> None:
        self._run_codes.append(code)
        self._run_values.append(expr)

    def _close_run(self) -> None:
        if self._run_codes:
            packer = self._const("S", struct.Struct("<" + "".join(self._run_codes)))
            self._chunks.append(f"{packer}.pack({', '.join(self._run_values)})")
            self._run_codes, self._run_values = [], []

    def _piece(self, expr: str) -> None:
        self._close_run()
        self._chunks.append(expr)

    def _flush(self, indent: int) -> None:
        """Write the pending pieces to ``_out`` (before a loop, at the end of a loop body)."""
        self._close_run()
        if self._chunks:
            self._statement(indent, f"_out += ({', '.join(self._chunks)},)")
            self._chunks = []

    # -- fields -----------------------------------------------------------------------------

    def _message(self, typename: str, expr: str, indent: int, depth: int) -> None:
        if depth > _MAX_DEPTH:
            raise UnsupportedType(f"{typename}: message nesting deeper than {_MAX_DEPTH}")
        fields = [(n, d) for n, d in self._store.get_msgdef(typename).fields if n != _PLACEHOLDER]
        if len(fields) > 2 and expr.count(".") > 0:
            # a local for a nested message read more than twice saves the attribute chain
            local = self._name("v")
            self._statement(indent, f"{local} = {expr}")
            expr = local
        for fieldname, desc in fields:
            self._field(typename, fieldname, desc, f"{expr}.{fieldname}", indent, depth)

    def _field(self, typename: str, fieldname: str, desc, expr: str, indent: int,
               depth: int) -> None:
        kind = desc[0]
        if kind == Nodetype.NAME:
            self._message(desc[1], expr, indent, depth + 1)
        elif kind == Nodetype.BASE:
            self._scalar(typename, fieldname, desc[1][0], expr, indent)
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            element, length = desc[1]
            self._array(typename, fieldname, element, length if kind == Nodetype.ARRAY else None,
                        expr, indent, depth)
        else:
            raise UnsupportedType(f"{typename}.{fieldname}: field kind {kind!r}")

    def _scalar(self, typename: str, fieldname: str, base: str, expr: str, indent: int) -> None:
        if base == "string":
            encoded = self._name("s")
            self._statement(indent, f"{encoded} = {expr}.encode()")
            self._primitive("I", f"len({encoded})")
            self._piece(encoded)
        elif base in STRUCT_CODES:
            self._primitive(STRUCT_CODES[base], expr)
        else:
            raise UnsupportedType(f"{typename}.{fieldname}: primitive type {base}")

    def _array(self, typename: str, fieldname: str, element, length: int | None, expr: str,
               indent: int, depth: int) -> None:
        """``length`` None: a sequence (uint32 count first); else a fixed-length array."""
        values = self._name("a")
        self._statement(indent, f"{values} = {expr}")
        if length is None:
            self._primitive("I", f"len({values})")
        else:
            self._statement(indent, f"if len({values}) != {length}: raise _NotFastPath")
        if element[0] == Nodetype.BASE and element[1][0] in STRUCT_CODES:
            base = element[1][0]
            dtype = self._const("D", ARRAY_DTYPES[base])
            # the common case inline (a call costs as much as tobytes() itself); the helper
            # takes lists and refuses the rest
            self._piece(f"({values}.tobytes() if {values}.__class__ is _ndarray and "
                        f"{values}.dtype is {dtype} and {values}.ndim == 1 else "
                        f"_array_bytes({values}, {dtype}, {STRUCT_CODES[base]!r}))")
            return
        if element[0] == Nodetype.BASE and element[1][0] != "string":
            raise UnsupportedType(f"{typename}.{fieldname}: array of {element[1][0]}")
        # strings and messages: one loop, its body flattened like the message itself
        self.has_loops = True
        self._flush(indent)
        item = self._name("e")
        self._statement(indent, f"for {item} in {values}:")
        if element[0] == Nodetype.NAME:
            self._message(element[1], item, indent + 1, depth + 1)
        else:
            self._scalar(typename, fieldname, "string", item, indent + 1)
        self._flush(indent + 1)
        if self._lines[-1].endswith(":"):  # an element that writes nothing (empty message)
            self._statement(indent + 1, "pass")


def generate_source(store, typename: str) -> tuple[str, dict[str, object]]:
    """(source of ``serialize(m) -> bytes`` for ``typename``, the namespace it runs in).
    Raises UnsupportedType for types with a field the generator has no code for."""
    gen = _Generator(store)
    return gen.source(typename), gen.namespace


def generate(store, typename: str) -> Serializer:
    """The compiled serializer of one type (see generate_source)."""
    source, namespace = generate_source(store, typename)
    code = compile(source, f"<ros1 serializer {typename}>", "exec")
    exec(code, namespace)  # noqa: S102 - source built above from the typestore's definitions
    return namespace["serialize"]


class Ros1Serializer:
    """ROS 1 bytes of any message of a typestore: generated functions where there are
    some, rosbags' serializer for the rest (and for values the generated code refuses)."""

    def __init__(self, store) -> None:
        self._store = store
        self._functions: dict[str, Serializer | None] = {}

    def function(self, typename: str) -> Serializer | None:
        """The generated function of a type (cached), or None if the type is unsupported."""
        try:
            return self._functions[typename]
        except KeyError:
            pass
        try:
            func = generate(self._store, typename)
        except UnsupportedType:
            func = None
        self._functions[typename] = func
        return func

    def serialize(self, msg) -> bytes:
        typename = msg.__msgtype__
        func = self._functions.get(typename) or self.function(typename)
        if func is not None:
            try:
                return func(msg)
            except Exception:  # noqa: BLE001 - any refusal: rosbags serialises or raises
                pass
        return bytes(self._store.serialize_ros1(msg, typename))
