"""Reading a bag by topic: the index for counts, columns of numeric fields, messages.

``Bag`` opens only the index (``format.read_index``); reading a topic decompresses just the
chunks that hold it. ``columns`` returns numeric fields as numpy arrays: for topics whose
messages share one byte layout (``layout``) it slices the fields straight out of the chunk
bytes, else it deserialises each message. Messages are deserialised with the package's
typestore (ROS Noetic + tf2_msgs/TFMessage + twil_control/msg); a type the store lacks, or
whose definition in the bag differs from the store's (md5sum), is taken from the bag's own
message definition, as rosbag does.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from ..core import messages
from ..errors import TwilControlError
from . import format as fmt
from . import mcap_format
from .bag_errors import BagError, did_you_mean, listing
from .layout import Layout, layout


class MessageDecodeError(BagError, TwilControlError):
    """Bytes of a message that are not the type its connection declares."""


@dataclass
class Topic:
    name: str
    msgtype: str  # typestore form, pkg/msg/Type
    ros1_type: str  # pkg/Type, as rosbag prints it
    count: int
    connections: list[int]
    latching: bool
    md5sum: str


def _typestore_for(connections) -> object:
    base = messages.typestore()
    extra = {}
    for c in connections:
        full = messages.full_type_name(c.msgtype)
        known = full in base.types and base.generate_msgdef(full)[1] == c.md5sum
        if not known and c.msgdef:
            extra.update(get_types_from_msg(c.msgdef, full))
    if not extra:
        return base
    store = get_typestore(Stores.EMPTY)
    types = dict(base.fielddefs)
    types.update(extra)
    store.register(types)
    return store


_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


def field_tokens(name: str) -> list:
    """'pose.pose.position.x' / 'position[3]' -> ['pose', 'pose', 'position', 'x'] / ['position', 3]."""
    out: list = []
    for part in name.split("."):
        m = _TOKEN.fullmatch(part)
        if not m:
            raise BagError(
                f"field '{name}': '{part}' is not a field name (letters, digits, _, with [index] for arrays)"
            )
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return out


def get_field(msg, tokens: list):
    for tok in tokens:
        msg = msg[tok] if isinstance(tok, int) else getattr(msg, tok)
    return msg


class Bag:
    """An indexed bag, opened through its index: a ROS 1 bag (format.read_index) or an MCAP
    file of ROS 1 messages (mcap_format.read_index), told apart by their first bytes."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        self.is_mcap = self.path.is_file() and mcap_format.is_mcap(self.path)
        self.index = mcap_format.read_index(self.path) if self.is_mcap else fmt.read_index(self.path)
        self.store = _typestore_for(self.index.connections.values())
        by_topic: dict[str, list] = {}
        for c in self.index.connections.values():
            by_topic.setdefault(c.topic, []).append(c)
        counts: dict[int, int] = {}
        for chunk in self.index.chunks:
            for cid, n in chunk.counts.items():
                counts[cid] = counts.get(cid, 0) + n
        self.topics: dict[str, Topic] = {}
        for name, conns in sorted(by_topic.items()):
            c0 = conns[0]
            full = messages.full_type_name(c0.msgtype)
            self.topics[name] = Topic(
                name,
                full,
                c0.msgtype,
                sum(counts.get(c.id, 0) for c in conns),
                [c.id for c in conns],
                any(c.latching == "1" for c in conns),
                c0.md5sum,
            )
        self._layouts: dict[str, Layout] = {}
        self._first: dict[str, bytes] = {}
        self._cache: dict[str, tuple[np.ndarray, dict[str, np.ndarray]]] = {}

    # -- summary ---------------------------------------------------------------------
    @property
    def start_ns(self) -> int:
        return min((c.start for c in self.index.chunks if c.counts), default=0)

    @property
    def end_ns(self) -> int:
        return max((c.end for c in self.index.chunks if c.counts), default=0)

    @property
    def message_count(self) -> int:
        return sum(t.count for t in self.topics.values())

    def topic(self, name: str) -> Topic:
        """The topic, or an error listing the bag's topics with a did-you-mean."""
        try:
            return self.topics[name]
        except KeyError:
            raise BagError(
                f"topic '{name}' is not in {self.path}{did_you_mean(name, self.topics)}; "
                f"its topics: {listing(self.topics)}"
            ) from None

    def topics_of_type(self, ros1_type: str) -> list[str]:
        return [t.name for t in self.topics.values() if t.ros1_type == ros1_type]

    # -- raw access ------------------------------------------------------------------
    def _chunks(self, topics: list[str], start_ns: int | None = None, stop_ns: int | None = None):
        """(records, data, topic-of-record array) of each chunk holding one of the topics, in
        time order; only those topics' records are kept."""
        conn_topic = {}
        for name in topics:
            for cid in self.topic(name).connections:
                conn_topic[cid] = name
        wanted = np.array(sorted(conn_topic), dtype=np.int64)
        chunks = [c for c in self.index.chunks if any(cid in conn_topic for cid in c.counts)]
        chunks.sort(key=lambda c: (c.start, c.pos))
        with self.path.open("rb") as f:
            for chunk in chunks:
                if start_ns is not None and chunk.end < start_ns:
                    continue
                if stop_ns is not None and chunk.start >= stop_ns:
                    break
                if self.is_mcap:
                    data, recs = mcap_format.read_chunk(f, self.index.chunk_index[chunk.pos], self.index)
                else:
                    data = fmt.read_chunk_data(f, chunk.pos)
                    recs = fmt.indexed_records(f, chunk, self.index.size, data)
                keep = np.isin(recs.conn, wanted)
                if start_ns is not None:
                    keep &= recs.time >= start_ns
                if stop_ns is not None:
                    keep &= recs.time < stop_ns
                idx = np.nonzero(keep)[0]
                idx = idx[np.argsort(recs.time[idx], kind="stable")]
                yield recs, idx, data, conn_topic

    def raw_messages(self, topics: list[str], start_ns: int | None = None, stop_ns: int | None = None):
        """(topic, time ns, serialised bytes) of the topics' messages in time order."""
        for recs, idx, data, conn_topic in self._chunks(topics, start_ns, stop_ns):
            for i in idx:
                o = int(recs.offset[i])
                yield conn_topic[int(recs.conn[i])], int(recs.time[i]), data[o : o + int(recs.length[i])]

    def deserialize(self, topic: str, data: bytes, index: int = 0, t_ns: int | None = None, store=None):
        """The message of a topic's serialised bytes; MessageDecodeError (one line naming the
        topic, the message's index and time, and the declared type) when they are not one."""
        t = self.topics[topic]
        try:
            return (store or self.store).deserialize_ros1(data, t.msgtype)
        except Exception as error:  # rosbags raises SerdeError, struct.error, IndexError... on such bytes
            when = "" if t_ns is None else f", t = {t_ns / 1e9:.3f} s"
            raise MessageDecodeError(
                f"{self.path}: message {index} of {topic} ({len(data)} bytes{when}) is not a {t.ros1_type}, "
                f"the type its connection declares ({type(error).__name__}: {error})"
            ) from None

    def messages(
        self, topic: str, start_ns: int | None = None, stop_ns: int | None = None
    ) -> list[tuple[int, object]]:
        """[(time ns, message)] of one topic."""
        self.topic(topic)
        return [
            (ts, self.deserialize(topic, raw, i, ts))
            for i, (_, ts, raw) in enumerate(self.raw_messages([topic], start_ns, stop_ns))
        ]

    def first_message(self, topic: str):
        for _, t_ns, raw in self.raw_messages([topic]):
            return self.deserialize(topic, raw, 0, t_ns)
        return None

    # -- numeric columns -------------------------------------------------------------
    def layout(self, topic: str) -> Layout:
        """Byte layout of the topic's first message (its numeric leaves and their offsets)."""
        if topic not in self._layouts:
            t = self.topic(topic)
            first = self._first_bytes(topic) if t.count else None
            if first is None:
                raise BagError(f"topic '{topic}' has no messages in {self.path}")
            self.deserialize(topic, first)  # bytes that are not the declared type: one line, here
            lay = layout(self.store, t.msgtype, first)
            if any(off + np.dtype(dtype).itemsize > len(first) for off, dtype in lay.leaves.values()):
                raise MessageDecodeError(
                    f"{self.path}: message 0 of {topic} ({len(first)} bytes) is shorter than a "
                    f"{t.ros1_type}, the type its connection declares"
                )
            self._layouts[topic] = lay
        return self._layouts[topic]

    def fields(self, topic: str) -> list[str]:
        """Numeric leaf names of the topic's messages (as in its first message)."""
        return list(self.layout(topic).leaves)

    def check_field(self, topic: str, name: str) -> None:
        """An unknown or non-numeric field is an error listing the fields, with a did-you-mean."""
        lay = self.layout(topic)
        if name in lay.leaves:
            return
        ros1 = self.topics[topic].ros1_type
        if name in lay.strings:
            raise BagError(f"field '{name}' of {topic} ({ros1}) is a string, not a number")
        under = [k for k in lay.leaves if k.startswith(name + ".") or k.startswith(name + "[")]
        if under:
            raise BagError(
                f"field '{name}' of {topic} ({ros1}) is not a number; its numeric "
                f"fields: {listing(under, 12)}"
            )
        base = re.sub(r"\[\d+\]$", "", name)
        if base != name and any(k.startswith(base + "[") for k in lay.leaves):
            n = len({k.split("[", 1)[1].split("]")[0] for k in lay.leaves if k.startswith(base + "[")})
            raise BagError(
                f"field '{name}' of {topic}: index out of range ({base} has {n} elements "
                "in the first message)"
            )
        top = sorted(
            {re.split(r"[.\[]", k)[0] for k in lay.leaves} | {re.split(r"[.\[]", s)[0] for s in lay.strings}
        )
        raise BagError(
            f"{topic} ({ros1}) has no field '{name}'{did_you_mean(name, lay.leaves)}; "
            f"its fields: {listing(top)}"
        )

    def columns(
        self,
        topic: str,
        names: list[str] | None = None,
        start_ns: int | None = None,
        stop_ns: int | None = None,
    ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """(times in ns, {field: float64 values}) of numeric fields of every message of a topic
        (names None: every numeric field). Fields prefetched earlier come from memory."""
        self.topic(topic)
        if names is not None and start_ns is None and stop_ns is None:
            cached = self._cache.get(topic)
            if cached is not None and all(n in cached[1] for n in names):
                return cached[0], {n: cached[1][n] for n in names}
        return self.columns_of({topic: names}, start_ns, stop_ns)[topic]

    def prefetch(self, requests: dict[str, list[str]]) -> None:
        """Read the fields of several topics in one pass over the chunks (each chunk is
        decompressed once) and keep them for later columns() calls."""
        requests = {t: f for t, f in requests.items() if t and t in self.topics and self.topics[t].count}
        for topic, (tt, cols) in self.columns_of(requests).items():
            old = self._cache.get(topic)
            if old is not None and len(old[0]) == len(tt):
                old[1].update(cols)
            else:
                self._cache[topic] = (tt, dict(cols))

    def columns_of(
        self, requests: dict[str, list[str] | None], start_ns: int | None = None, stop_ns: int | None = None
    ) -> dict[str, tuple[np.ndarray, dict[str, np.ndarray]]]:
        """columns() of several topics, reading each chunk once.

        Chunk by chunk: if every message of a topic has its first message's layout the fields
        are sliced from the raw bytes (layout.py); otherwise they are deserialised."""
        plan = {}
        for topic, names in requests.items():
            t = self.topic(topic)
            if t.count == 0:
                plan[topic] = None
                continue
            lay = self.layout(topic)
            names = list(lay.leaves) if names is None else list(names)
            for n in names:
                self.check_field(topic, n)
            first = self._first_bytes(topic)
            ref = np.array([list(first[p : p + 4]) for p in lay.prefixes], np.uint8).reshape(-1, 4)
            plan[topic] = (t, lay, names, ref, [], {n: [] for n in names})
        out = {
            topic: (np.zeros(0, np.int64), {n: np.zeros(0) for n in (requests[topic] or [])})
            for topic, p in plan.items()
            if p is None
        }
        live = [topic for topic, p in plan.items() if p is not None]
        if not live:
            return out
        for recs, idx, data, _ in self._chunks(live, start_ns, stop_ns):
            buf = np.frombuffer(data, dtype=np.uint8)
            conns = recs.conn[idx]
            for topic in live:
                t, lay, names, ref, times, cols = plan[topic]
                sel = idx[np.isin(conns, t.connections)] if len(live) > 1 else idx
                if len(sel) == 0:
                    continue
                self._extract(t, lay, names, ref, buf, data, recs, sel, times, cols)
        for topic in live:
            t, lay, names, ref, times, cols = plan[topic]
            tt = np.concatenate(times) if times else np.zeros(0, np.int64)
            out[topic] = (tt, {n: (np.concatenate(v) if v else np.zeros(0)) for n, v in cols.items()})
        return out

    def _extract(self, t, lay, names, ref, buf, data, recs, sel, times, cols) -> None:
        offs, lens = recs.offset[sel], recs.length[sel]
        base = sum(len(x) for x in times)  # the index of this slice's first message in the topic
        times.append(recs.time[sel])
        fixed = bool((lens == lay.size).all())
        if fixed and lay.prefixes:
            pre = buf[
                offs[:, None, None] + np.array(lay.prefixes)[None, :, None] + np.arange(4)[None, None, :]
            ]
            fixed = bool((pre == ref[None]).all())
        if fixed:
            for n in names:
                off, dtype = lay.leaves[n]
                size = np.dtype(dtype).itemsize
                raw = buf[offs[:, None] + off + np.arange(size)[None, :]]
                cols[n].append(np.ascontiguousarray(raw).view(dtype).reshape(-1).astype(np.float64))
        else:
            tokens = {n: field_tokens(n) for n in names}
            msgs = [
                self.deserialize(t.name, data[o : o + n], base + i, int(ts))
                for i, (o, n, ts) in enumerate(zip(offs, lens, recs.time[sel]))
            ]
            for n in names:
                cols[n].append(np.array([_number(m, tokens[n]) for m in msgs], dtype=np.float64))

    def _first_bytes(self, topic: str) -> bytes:
        if topic not in self._first:
            for _, _, raw in self.raw_messages([topic]):
                self._first[topic] = bytes(raw)
                break
        return self._first[topic]


def _number(msg, tokens) -> float:
    """A numeric leaf of a message, NaN where this message lacks it (a shorter array)."""
    try:
        return float(get_field(msg, tokens))
    except (IndexError, AttributeError, TypeError):
        return float("nan")


def resolve_spec(bag: Bag, spec: str) -> tuple[str, str]:
    """rqt_plot's 'TOPIC/field/sub[i]' (or 'TOPIC.field') -> (topic, 'field.sub[i]').

    The topic is the longest of the bag's topics that prefixes the spec."""
    if not spec.startswith("/"):
        spec = "/" + spec
    best = None
    for name in bag.topics:
        if spec == name or spec.startswith(name + "/") or spec.startswith(name + "."):
            if best is None or len(name) > len(best):
                best = name
    if best is None:
        head = spec.rsplit("/", 1)[0] if spec.count("/") > 1 else spec
        raise BagError(
            f"no topic of {bag.path} starts '{spec}'{did_you_mean(head, bag.topics)}; "
            f"its topics: {listing(bag.topics)}"
        )
    rest = spec[len(best) :].lstrip("/.").replace("/", ".")
    if not rest:
        raise BagError(
            f"'{spec}' names topic {best} but no field; its numeric fields: {listing(bag.fields(best), 20)}"
        )
    bag.check_field(best, rest)
    return best, rest
