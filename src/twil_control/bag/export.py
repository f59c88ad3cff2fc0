"""``export``: one topic as a table (CSV or Parquet), one row per message.

Columns come from rosbags-dataframe's ``get_dataframe``, reading through the bag tools' own
reader in AnyReader's place (bags and MCAP files alike): every non-message leaf in
dotted form (``pose.pose.position.x``, ``header.stamp.sec``). Then, for a flat table:
numeric arrays whose length is the same in every row become one column per element
(``position[0]`` ...), other arrays (varying lengths, arrays of messages) one JSON text
column. ``time`` (s) and ``time_ns`` (the bag's record time) come first.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
from rosbags.dataframe import get_dataframe
from rosbags.interfaces import Nodetype

from .bag_errors import BagError, did_you_mean, listing
from .output import check_new_output, open_new
from .reader import Bag

FORMATS = (".csv", ".parquet")


def leaf_keys(store, msgtype: str, prefix: str = "") -> list[str]:
    """Dotted names of a type's fields down to non-message leaves (arrays are leaves)."""
    out = []
    for name, (kind, spec) in store.get_msgdef(msgtype).fields:
        key = f"{prefix}{name}"
        if kind == Nodetype.NAME:
            out += leaf_keys(store, spec, key + ".")
        else:
            out.append(key)
    return out


def _plain(v):
    """A message value as JSON-able data."""
    if hasattr(v, "__msgtype__"):
        return {k: _plain(getattr(v, k)) for k in v.__dataclass_fields__ if k != "__msgtype__"}
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


class _BagAsReader:
    """What get_dataframe reads from an AnyReader, over reader.Bag: a bag or an MCAP file of
    ROS 1 messages read as the bag tools read them (AnyReader opens ROS 2 MCAP files only), each
    message decoded by Bag.deserialize, so bytes that are not their type are one line."""

    def __init__(self, bag: Bag) -> None:
        self._bag = bag
        self._at: tuple[str, int, int] = ("", 0, 0)  # topic, index, time of the message read last
        self.typestore = bag.store
        self.topics = {
            name: SimpleNamespace(msgtype=t.msgtype, connections=[name]) for name, t in bag.topics.items()
        }

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        pass

    def messages(self, connections):
        for i, (topic, t_ns, raw) in enumerate(self._bag.raw_messages(list(connections))):
            self._at = (topic, i, t_ns)
            yield topic, t_ns, raw

    def deserialize(self, raw, msgtype: str):
        topic, index, t_ns = self._at
        return self._bag.deserialize(topic, raw, index, t_ns)


def topic_table(path, topic: str, fields: list[str] | None = None) -> pd.DataFrame:
    bag = Bag(path)  # checks the bag (index, errors) and the topic with a did-you-mean
    t = bag.topic(topic)
    with _BagAsReader(bag) as reader:
        keys = leaf_keys(reader.typestore, t.msgtype)
        if fields:
            bad = [f for f in fields if f not in keys]
            if bad:
                raise BagError(
                    f"{topic} ({t.ros1_type}) has no field '{bad[0]}'{did_you_mean(bad[0], keys)}; "
                    f"its fields: {listing(keys)}"
                )
            keys = fields
        df = get_dataframe(reader, topic, keys)
    time_ns = df.index.asi8 if len(df) else np.zeros(0, np.int64)
    out = {"time": time_ns * 1e-9, "time_ns": time_ns}
    for key in keys:
        col = df[key].tolist()
        if col and isinstance(col[0], (np.ndarray, list, tuple)):
            lens = {len(v) for v in col}
            numeric = isinstance(col[0], np.ndarray) and col[0].dtype.kind in "biuf"
            if numeric and len(lens) == 1:
                arr = np.stack(col) if lens != {0} else np.zeros((len(col), 0))
                for i in range(arr.shape[1]):
                    out[f"{key}[{i}]"] = arr[:, i]
                continue
            out[key] = [json.dumps(_plain(v)) for v in col]
        else:
            out[key] = col
    return pd.DataFrame(out)


def export_topic(
    path, topic: str, out, fields: list[str] | None = None, force: bool = False
) -> tuple[Path, int]:
    """Write the topic's table; an existing file is replaced only with force."""
    out = Path(out)
    if out.suffix.lower() not in FORMATS:
        raise BagError(f"output {out}: the extension must be .csv or .parquet (got '{out.suffix or 'none'}')")
    check_new_output(out, "output", force)
    df = topic_table(path, topic, fields)
    if out.suffix.lower() == ".csv":
        with open_new(out, force, "w") as f:
            df.to_csv(f, index=False)
    else:
        with open_new(out, force) as f:
            df.to_parquet(f, index=False)
    return out, len(df)
