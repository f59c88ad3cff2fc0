"""Byte layout of a ROS 1 message, for reading numeric fields of many messages at once.

ROS 1 serialisation is little-endian and unpadded, so where a topic's strings and array lengths
do not change between messages, every numeric field sits at the same offset in every message:
``layout`` walks the definition along the first message's bytes, and a column becomes a strided
numpy view of the stacked messages, with no per-message deserialisation. Leaf names are
rqt_plot's (``pose.pose.position.x``, ``position[3]``).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import numpy as np
from rosbags.interfaces import Nodetype

from twil_control.errors import InputError

_SCALARS = {
    "bool": "<u1",
    "byte": "<u1",
    "char": "<u1",
    "int8": "<i1",
    "uint8": "<u1",
    "int16": "<i2",
    "uint16": "<u2",
    "int32": "<i4",
    "uint32": "<u4",
    "int64": "<i8",
    "uint64": "<u8",
    "float32": "<f4",
    "float64": "<f8",
}


@dataclass
class Layout:
    size: int  # bytes of the first message
    leaves: dict[str, tuple[int, str]] = field(default_factory=dict)  # name -> (offset, dtype)
    prefixes: list[int] = field(default_factory=list)  # offsets of u32 length prefixes
    strings: list[str] = field(default_factory=list)  # names of string leaves (not numeric)
    complete: bool = True  # False if the walk did not use every byte


def layout(store, msgtype: str, data: bytes) -> Layout:
    """Walk msgtype's definition over one serialised message."""
    out = Layout(size=len(data))
    end = _walk(store, msgtype, data, 0, "", out)
    out.complete = end == len(data)
    return out


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def _walk(store, msgtype: str, data: bytes, pos: int, prefix: str, out: Layout) -> int:
    for name, (kind, spec) in store.get_msgdef(msgtype).fields:
        path = _join(prefix, name)
        if kind == Nodetype.BASE:
            pos = _base(spec[0], data, pos, path, out)
        elif kind == Nodetype.NAME:
            pos = _walk(store, spec, data, pos, path, out)
        elif kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):
            (item_kind, item_spec), count = spec
            if kind == Nodetype.SEQUENCE:
                out.prefixes.append(pos)
                (count,) = struct.unpack_from("<I", data, pos)
                pos += 4
            for i in range(count):
                item = f"{path}[{i}]"
                if item_kind == Nodetype.BASE:
                    pos = _base(item_spec[0], data, pos, item, out)
                else:
                    pos = _walk(store, item_spec, data, pos, item, out)
        else:  # pragma: no cover - rosbags' ROS 1 definitions have no other kinds
            raise InputError(f"unsupported field kind {kind} in {msgtype}")
    return pos


def _base(typ: str, data: bytes, pos: int, path: str, out: Layout) -> int:
    if typ == "string":
        out.prefixes.append(pos)
        out.strings.append(path)
        (n,) = struct.unpack_from("<I", data, pos)
        return pos + 4 + n
    if typ in ("time", "duration"):  # ROS 1 builtins (rosbags maps them to messages normally)
        out.leaves[path + ".sec"] = (pos, "<u4" if typ == "time" else "<i4")
        out.leaves[path + ".nanosec"] = (pos + 4, "<u4" if typ == "time" else "<i4")
        return pos + 8
    dtype = _SCALARS.get(typ)
    if dtype is None:
        raise InputError(f"unsupported scalar type {typ}")
    out.leaves[path] = (pos, dtype)
    return pos + np.dtype(dtype).itemsize
