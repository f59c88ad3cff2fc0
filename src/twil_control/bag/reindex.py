"""``reindex``: recover a bag without index (rosbag reindex's role).

A recorder's ``NAME.bag.active`` left by a crash has complete chunks but no index; a copy cut
short may also end inside a chunk. The records are read in file order (format.scan); every
complete message, including those of a chunk cut by the end of the file as far as its
compressed blocks are complete, is written with its connection (topic, type, definition,
md5sum, callerid, latching) into a new bag with an index. The damaged file is not modified.

An MCAP file left by a crash (``NAME.mcap.active``: complete chunks, no summary) is read
record by record by the ``mcap`` package's stream reader, up to the end of its last complete
chunk; its schemas, channels and messages are written into a new MCAP file with a summary.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rosbags.rosbag1 import Writer

from . import format as fmt
from .errors import BagError
from .mcap_format import is_mcap, md5_of

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
    if path.is_file() and is_mcap(path):
        return _reindex_mcap(path, out)
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


def _reindex_mcap(path: Path, out: Path) -> ReindexResult:
    """The complete chunks of an MCAP file, in file order, into a new MCAP file."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Chunk, Footer, Message, Schema
    from mcap.stream_reader import StreamReader, breakup_chunk

    from .mcap_writer import McapWriter
    if out.suffix != ".mcap":
        raise BagError(f"{out}: an MCAP file is recovered into a new .mcap file (convert it to a bag afterwards)")
    if out.exists() or not out.parent.is_dir() or out.resolve() == path.resolve():
        raise BagError(f"{out} must be a new file in an existing folder, not the file being recovered")
    writer = McapWriter(out, chunk_seconds=0)
    writer.open()
    schemas, channels, conns = {}, {}, {}
    n = chunks = dropped = 0
    complete = False
    size = path.stat().st_size
    try:
        with path.open("rb") as f:
            try:
                for record in StreamReader(f, skip_magic=False, emit_chunks=True).records:
                    inner = breakup_chunk(record) if isinstance(record, Chunk) else [record]
                    chunks += isinstance(record, Chunk)
                    for r in inner:
                        if isinstance(r, Schema):
                            schemas[r.id] = r
                        elif isinstance(r, Channel):
                            channels[r.id] = r
                        elif isinstance(r, Message):
                            conn = conns.get(r.channel_id)
                            if conn is None:
                                ch = channels.get(r.channel_id)
                                schema = schemas.get(ch.schema_id) if ch else None
                                if schema is None:
                                    dropped += 1
                                    continue
                                meta = ch.metadata
                                conn = conns[r.channel_id] = writer.add_connection(
                                    ch.topic, schema.name, msgdef=schema.data.decode(),
                                    md5sum=meta.get("md5sum") or md5_of(schema.name, schema.data.decode()), callerid=meta.get("callerid"),
                                    latching=meta.get("latching") in ("true", "1"))
                            writer.write(conn, r.log_time, r.data)
                            n += 1
                    if isinstance(record, Footer):
                        complete = True
            except (McapError, EOFError, ValueError):
                pass   # the file ends inside a record: everything before it is kept
    except BaseException:
        writer.abort()
        out.unlink(missing_ok=True)
        raise
    writer.close()
    topics = len({c.topic for c in conns.values()})
    return ReindexResult(out, n, topics, chunks, not complete, size, size, dropped)
