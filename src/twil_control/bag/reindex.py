"""``reindex``: recover a bag without index (rosbag reindex's role).

A crashed recorder's ``.active`` file has complete chunks and no index (an MCAP file, no summary);
a copy cut short may end inside a chunk. Every complete message, with its connection, is copied
into a new indexed file; the damaged file is not modified. An MCAP chunk that fails its CRC is
left out whole and counted, as ``mcap recover`` does: corrupt bytes are never written again under
a fresh CRC (docs/bags.md, docs/mcap.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from . import format as fmt
from .bag_errors import BagError
from .mcap_format import is_mcap, md5_of
from .mcap_format import scan as mcap_scan
from .output import check_new_output, written_beside
from .writer import ChunkedWriter

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
    dropped: int  # messages whose connection record was lost
    corrupt: list = field(default_factory=list)  # MCAP chunks left out (mcap_format.CorruptChunk)

    @property
    def corrupt_messages(self) -> int:
        return sum(c.messages for c in self.corrupt)


def reindex(path, out, compression: str = "lz4", force: bool = False) -> ReindexResult:
    """Copy the recoverable messages of `path` into the new file `out` (replaced only with
    force). For a bag, what is recoverable is format.scan's rule, the count bag info reports."""
    path, out = Path(path), Path(out)
    check_new_output(out, "reindex output", force)
    if out.exists() and out.resolve() == path.resolve():
        raise BagError("the output must be a new file, not the file being recovered")
    if path.is_file() and is_mcap(path):
        return _reindex_mcap(path, out, force)
    if compression not in COMPRESSIONS:
        raise BagError(f"compression must be one of {', '.join(COMPRESSIONS)} (got {compression!r})")
    with written_beside(out, force) as part:
        writer = ChunkedWriter(part, chunk_seconds=0)
        if compression != "none":
            writer.set_compression(ChunkedWriter.CompressionFormat[compression.upper()])
        writer.open()
        conns: dict[int, object] = {}

        def on_chunk(recs: fmt.ChunkRecords, data: bytes, known: dict[int, fmt.ConnectionInfo]) -> None:
            for cid, t, o, n in zip(recs.conn, recs.time, recs.offset, recs.length):
                cid = int(cid)
                if cid not in conns:
                    if cid not in known:
                        continue  # its connection record was lost (counted in res.orphans)
                    conns[cid] = _connection(writer, known[cid])
                writer.write(conns[cid], int(t), data[int(o) : int(o) + int(n)])

        try:
            res = fmt.scan(path, on_chunk=on_chunk)
        except BaseException:
            writer.abort()
            raise
        writer.close()
    topics = {res.connections[cid].topic for cid in conns}
    return ReindexResult(
        out,
        writer.messages_written,
        len(topics),
        res.chunks,
        res.partial_chunk,
        res.valid_end,
        res.size,
        res.orphans,
    )


def _connection(writer: ChunkedWriter, c: fmt.ConnectionInfo):
    from ..core.messages import full_type_name

    latching = int(c.latching) if c.latching not in (None, "") else None
    try:
        return writer.add_connection(
            c.topic,
            full_type_name(c.msgtype),
            msgdef=c.msgdef,
            md5sum=c.md5sum,
            callerid=c.callerid,
            latching=latching,
        )
    except Exception:
        # the same topic/type/callerid twice (two publishers of one bag connection): reuse it
        for existing in writer.connections:
            if existing.topic == c.topic and existing.msgtype == full_type_name(c.msgtype):
                return existing
        raise


def _reindex_mcap(path: Path, out: Path, force: bool) -> ReindexResult:
    """The complete chunks of an MCAP file, in file order, into a new MCAP file."""
    if out.suffix != ".mcap":
        raise BagError(
            f"{out}: an MCAP file is recovered into a new .mcap file (convert it to a bag afterwards)"
        )
    with written_beside(out, force) as part:
        return _copy_mcap_records(path, out, part)


def _copy_mcap_records(path: Path, out: Path, part: Path) -> ReindexResult:
    from .mcap_writer import McapWriter

    writer = McapWriter(part, chunk_seconds=0)
    writer.open()
    conns = {}

    def on_message(channel, schema, message) -> None:
        conn = conns.get(channel.id)
        if conn is None:
            meta, msgdef = channel.metadata, schema.data.decode()
            conn = conns[channel.id] = writer.add_connection(
                channel.topic,
                schema.name,
                msgdef=msgdef,
                md5sum=meta.get("md5sum") or md5_of(schema.name, msgdef),
                callerid=meta.get("callerid"),
                latching=meta.get("latching") in ("true", "1"),
            )
        writer.write(conn, message.log_time, message.data)

    try:
        found = mcap_scan(path, on_message)
    except BaseException:
        writer.abort()
        raise
    writer.close()
    size = path.stat().st_size
    return ReindexResult(
        out,
        writer.messages_written,
        len({c.topic for c in conns.values()}),
        found.chunks,
        found.cut,
        size,
        size,
        found.orphans,
        found.corrupt,
    )
