"""``info``: what ``rosbag info`` prints (and ``rosbag info -y`` as YAML), from the index only.

Counts come from the chunk infos, per-topic rates from the index data records' message times
(12 bytes a message; no chunk is decompressed), so a bag of a million messages answers at
once. The rate is rosbag's: 1 / median of the intervals between a topic's messages.
"""

from __future__ import annotations

import time

import numpy as np
import yaml

from . import format as fmt
from .bag_errors import size_text
from .reader import Bag


def bag_info(path) -> dict:
    """The figures of `rosbag info -y`, as a dict (times in seconds)."""
    bag = Bag(path)
    idx = bag.index
    times = idx.times if bag.is_mcap else fmt.index_times(idx)
    compressed = idx.compressed if bag.is_mcap else sum(_chunk_bytes(idx))
    start, end = bag.start_ns * 1e-9, bag.end_ns * 1e-9
    topics = []
    for t in bag.topics.values():
        ts = np.sort(np.concatenate([times.get(c, np.zeros(0, np.int64)) for c in t.connections]))
        entry = {"topic": t.name, "type": t.ros1_type, "messages": t.count}
        dt = np.diff(ts)
        dt = dt[dt > 0]
        if len(dt):
            entry["frequency"] = float(1e9 / np.median(dt))
        if t.latching:
            entry["latching"] = True
        if len(t.connections) > 1:
            entry["connections"] = len(t.connections)
        topics.append(entry)
    types = sorted({(t.ros1_type, t.md5sum) for t in bag.topics.values()})
    kinds = idx.compression or {"none": 0}
    main = max(kinds, key=kinds.get)
    return {
        "path": str(bag.path),
        "version": f"MCAP ({idx.profile} profile)" if bag.is_mcap else 2.0,
        "duration": end - start,
        "start": start,
        "end": end,
        "size": idx.size,
        "messages": bag.message_count,
        "indexed": True,
        "chunks": len(idx.chunks),
        "compression": main,
        "compression_chunks": dict(kinds),
        "uncompressed": idx.uncompressed,
        "compressed": compressed,
        "types": [{"type": t, "md5": m} for t, m in types],
        "topics": topics,
    }


def _chunk_bytes(idx):
    """Compressed data size of each chunk (read from the chunk record headers)."""
    with idx.path.open("rb") as f:
        for chunk in idx.chunks:
            f.seek(chunk.pos)
            _, _, n = fmt._read_record(f, idx.size)
            yield n


def _stamp(s: float) -> str:
    return f"{time.strftime('%b %d %Y %H:%M:%S', time.gmtime(s))}.{int(round((s % 1) * 100)) % 100:02d} ({s:.2f})"


def _duration(s: float) -> str:
    h, rem = divmod(s, 3600)
    m, sec = divmod(rem, 60)
    if h:
        return f"{int(h)}:{int(m):02d}:{sec:05.2f}s ({s:.0f}s)"
    if m:
        return f"{int(m)}:{sec:05.2f}s ({s:.0f}s)"
    return f"{s:.2f}s"


def format_info(info: dict) -> str:
    """rosbag info's layout (times in UTC, sizes in KB/MB)."""
    ratio = 100.0 * info["compressed"] / info["uncompressed"] if info["uncompressed"] else 100.0
    kinds = ", ".join(f"{k} [{n}/{info['chunks']} chunks]" for k, n in info["compression_chunks"].items())
    lines = [
        f"path:        {info['path']}",
        f"version:     {info['version'] if isinstance(info['version'], str) else format(info['version'], '.1f')}",
        f"duration:    {_duration(info['duration'])}",
        f"start:       {_stamp(info['start'])}",
        f"end:         {_stamp(info['end'])}",
        f"size:        {size_text(info['size'])}",
        f"messages:    {info['messages']}",
        f"compression: {kinds}; {ratio:.1f}% of {size_text(info['uncompressed'])}",
    ]
    tw = max((len(t["type"]) for t in info["types"]), default=0)
    for i, t in enumerate(info["types"]):
        lines.append(f"{'types:' if i == 0 else '':13s}{t['type']:{tw}s} [{t['md5']}]")
    nw = max((len(t["topic"]) for t in info["topics"]), default=0)
    cw = max((len(str(t["messages"])) for t in info["topics"]), default=0)
    for i, t in enumerate(info["topics"]):
        rate = f" @ {_rate(t['frequency'])}" if "frequency" in t else ""
        extra = " (latched)" if t.get("latching") else ""
        lines.append(
            f"{'topics:' if i == 0 else '':13s}{t['topic']:{nw}s} {t['messages']:{cw}d} msgs"
            f"{rate:12s} : {t['type']}{extra}"
        )
    return "\n".join(lines)


def _rate(hz: float) -> str:
    if hz >= 1000:
        return f"{hz / 1000:.1f} kHz"
    return f"{hz:.1f} Hz" if hz >= 1 else f"{hz:.3g} Hz"


def format_yaml(info: dict) -> str:
    return yaml.safe_dump(info, sort_keys=False, default_flow_style=False)
