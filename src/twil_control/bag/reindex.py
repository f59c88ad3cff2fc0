"""``reindex``: recover a bag without index (rosbag reindex's role).

A recorder's ``NAME.bag.active`` left by a crash has complete chunks but no index; a copy cut
short may also end inside a chunk. The records are read in file order (format.scan); every
complete message, including those of a chunk cut by the end of the file as far as its
compressed blocks are complete, is written with its connection (topic, type, definition,
md5sum, callerid, latching) into a new bag with an index. The damaged file is not modified.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rosbags.rosbag1 import Writer

from . import format as fmt
from .errors import BagError

COMPRESSIONS = ("lz4", "bz2", "none")


@dataclass
class ReindexResult:
    out: Path
    messages: int
    topics: int
    chunks: int
    partial_chunk: bool
    valid_end: int
    size: int
    dropped: int          # messages whose connection record was lost


def reindex(path, out, compression: str = "lz4") -> ReindexResult:
    path, out = Path(path), Path(out)
    if compression not in COMPRESSIONS:
        raise BagError(f"compression must be one of {', '.join(COMPRESSIONS)} (got {compression!r})")
    if out.exists():
        raise BagError(f"{out} exists; reindex never overwrites: choose another -o path")
    if not out.parent.is_dir():
        raise BagError(f"folder {out.parent} for {out} does not exist")
    if out.resolve() == path.resolve():
        raise BagError("the output must be a new file, not the bag being recovered")
    writer = Writer(out)
    if compression != "none":
        writer.set_compression(Writer.CompressionFormat[compression.upper()])
    writer.open()
    conns: dict[int, object] = {}
    written = {"n": 0, "dropped": 0}
    known: dict[int, fmt.ConnectionInfo] = {}

    def on_chunk(recs: fmt.ChunkRecords, data: bytes) -> None:
        # connection records come first in the chunk that first uses them
        for off in recs.connection_offsets:
            hlen = fmt._U32.unpack_from(data, off)[0]
            h = fmt.parse_header(data[off + 4: off + 4 + hlen])
            dlen = fmt._U32.unpack_from(data, off + 4 + hlen)[0]
            c = fmt.connection_from(h, fmt.parse_header(data[off + 8 + hlen: off + 8 + hlen + dlen]))
            known.setdefault(c.id, c)
        for cid, t, o, n in zip(recs.conn, recs.time, recs.offset, recs.length):
            cid = int(cid)
            if cid not in conns:
                c = known.get(cid)
                if c is None:
                    written["dropped"] += 1
                    continue
                conns[cid] = _connection(writer, c)
            writer.write(conns[cid], int(t), data[int(o):int(o) + int(n)])
            written["n"] += 1

    try:
        res = fmt.scan(path, on_chunk=on_chunk)
        # connections known only from a top-level record (e.g. a damaged index) and unused
        # by any message are not written: a bag lists the connections its messages use
    except BaseException:
        writer.abort()
        out.unlink(missing_ok=True)
        raise
    writer.close()
    return ReindexResult(out, written["n"], len({c.topic for c in known.values() if c.id in conns}),
                         res.chunks, res.partial_chunk, res.valid_end, res.size, written["dropped"])


def _connection(writer: Writer, c: fmt.ConnectionInfo):
    from ..core.messages import full_type_name
    latching = int(c.latching) if c.latching not in (None, "") else None
    try:
        return writer.add_connection(c.topic, full_type_name(c.msgtype), msgdef=c.msgdef, md5sum=c.md5sum,
                                     callerid=c.callerid, latching=latching)
    except Exception:
        # the same topic/type/callerid twice (two publishers of one bag connection): reuse it
        for existing in writer.connections:
            if existing.topic == c.topic and existing.msgtype == full_type_name(c.msgtype):
                return existing
        raise
