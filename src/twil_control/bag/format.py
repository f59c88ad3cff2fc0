"""ROS bag format 2.0, read record by record (the part of rosbag's C++ reader the tools need).

``read_index`` reads only the bag header and the index (what ``rosbag info`` needs: O(chunks),
not O(messages)); ``indexed_records`` locates a chunk's messages from the index data after it,
read with numpy, so a million messages cost milliseconds; ``scan`` walks the records in file
order for a bag without index, up to the first incomplete record. The records' layout:
docs/bags.md, "How the tools read a bag".
"""

from __future__ import annotations

import bz2
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path

import lz4.frame
import numpy as np

from .bag_errors import BagError, UnindexedBagError

MAGIC = b"#ROSBAG V2.0\n"
OP_MSG_DATA, OP_BAG_HEADER, OP_INDEX_DATA, OP_CHUNK, OP_CHUNK_INFO, OP_CONNECTION = 2, 3, 4, 5, 6, 7
_U32 = struct.Struct("<I")


@dataclass
class ConnectionInfo:
    id: int
    topic: str
    msgtype: str  # ROS 1 form, pkg/Type
    md5sum: str
    msgdef: str
    callerid: str | None = None
    latching: str | None = None


@dataclass
class ChunkInfo:
    pos: int
    start: int  # ns
    end: int  # ns (time of the last message)
    counts: dict[int, int]


@dataclass
class BagIndex:
    path: Path
    size: int
    index_pos: int
    connections: dict[int, ConnectionInfo]
    chunks: list[ChunkInfo]
    compression: dict[str, int] = field(default_factory=dict)  # chunks per compression
    uncompressed: int = 0  # bytes of chunk data


def parse_header(buf: bytes) -> dict[str, bytes]:
    """The fields of a record header."""
    out, i, n = {}, 0, len(buf)
    while i + 4 <= n:
        (flen,) = _U32.unpack_from(buf, i)
        i += 4
        if i + flen > n:
            raise BagError("record header field runs past the header")
        name, eq, value = buf[i : i + flen].partition(b"=")
        if not eq:
            raise BagError("record header field without '='")
        out[name.decode("ascii", "replace")] = value
        i += flen
    return out


def _u32(h: dict, k: str) -> int:
    return _U32.unpack(h[k])[0]


def _u64(h: dict, k: str) -> int:
    return struct.unpack("<Q", h[k])[0]


def _time(h: dict, k: str) -> int:
    sec, nsec = struct.unpack("<II", h[k])
    return sec * 1_000_000_000 + nsec


def _op(h: dict) -> int:
    try:
        return h["op"][0]
    except (KeyError, IndexError):
        raise BagError("record header without an op field") from None


class _Truncated(Exception):
    """A record that runs past the end of the file."""


def _read_record(f, size: int) -> tuple[dict, int, int]:
    """(header, data position, data length) of the record at the file position; the file
    position ends after the record header and its data length (the data is not read)."""
    start = f.tell()
    raw = f.read(4)
    if len(raw) < 4:
        raise _Truncated(start)
    (hlen,) = _U32.unpack(raw)
    if start + 4 + hlen + 4 > size:
        raise _Truncated(start)
    header = parse_header(f.read(hlen))
    (dlen,) = _U32.unpack(f.read(4))
    pos = f.tell()
    if pos + dlen > size:
        raise _Truncated(start)
    return header, pos, dlen


def connection_from(header: dict, data_header: dict) -> ConnectionInfo:
    """A connection record (its header gives id and topic, its data the connection header)."""

    def s(k):
        return data_header[k].decode() if k in data_header else None

    return ConnectionInfo(
        _u32(header, "conn"),
        header["topic"].decode(),
        s("type") or "",
        s("md5sum") or "",
        s("message_definition") or "",
        s("callerid"),
        s("latching"),
    )


def open_bag_file(path: Path):
    """Open a bag, check its magic line; returns (file, size). Errors name the problem."""
    path = Path(path)
    if not path.exists():
        raise BagError(f"{path}: no such file")
    if path.is_dir():
        raise BagError(f"{path} is a folder, not a bag file")
    size = path.stat().st_size
    f = path.open("rb")
    magic = f.read(len(MAGIC))
    if magic != MAGIC:
        f.close()
        if magic.startswith(b"#ROSBAG V"):
            raise BagError(
                f"{path}: bag format {magic[9:].strip().decode(errors='replace')} is "
                "not supported (only ROS bag 2.0)"
            )
        raise BagError(
            f"{path} is not a ROS bag (no '#ROSBAG V2.0' magic line; "
            f"{'empty file' if size == 0 else 'starts with ' + repr(magic[:16])})"
        )
    return f, size


def read_index(path: Path | str) -> BagIndex:
    """Bag header and index: connections, chunk infos, chunk compressions. A bag without an
    index raises UnindexedBagError with how much a reindex would recover."""
    path = Path(path)
    f, size = open_bag_file(path)
    with f:
        try:
            header, pos, dlen = _read_record(f, size)
        except _Truncated:
            raise BagError(
                f"{path}: truncated inside its bag header ({size} bytes): nothing to recover"
            ) from None
        if _op(header) != OP_BAG_HEADER:
            raise BagError(f"{path}: the first record is not a bag header (op {_op(header)})")
        index_pos = _u64(header, "index_pos")
        conn_count, chunk_count = _u32(header, "conn_count"), _u32(header, "chunk_count")
        if index_pos == 0:
            raise _unindexed(path, "index position 0: the bag was never closed")
        if index_pos >= size and chunk_count + conn_count > 0:
            raise _unindexed(path, f"its index at byte {index_pos} lies past the end of the file")
        index = BagIndex(path, size, index_pos, {}, [])
        f.seek(index_pos)
        try:
            for _ in range(conn_count):
                h, p, n = _read_record(f, size)
                if _op(h) != OP_CONNECTION:
                    raise BagError("expected a connection record")
                conn = connection_from(h, parse_header(f.read(n)))
                index.connections[conn.id] = conn
            for _ in range(chunk_count):
                h, p, n = _read_record(f, size)
                if _op(h) != OP_CHUNK_INFO:
                    raise BagError("expected a chunk info record")
                data = f.read(n)
                counts = dict(struct.iter_unpack("<II", data))
                index.chunks.append(
                    ChunkInfo(_u64(h, "chunk_pos"), _time(h, "start_time"), _time(h, "end_time"), counts)
                )
            for chunk in index.chunks:  # compression and uncompressed size: each chunk's header
                f.seek(chunk.pos)
                h, p, n = _read_record(f, size)
                if _op(h) != OP_CHUNK:
                    raise BagError(f"no chunk at byte {chunk.pos}")
                kind = h.get("compression", b"none").decode()
                index.compression[kind] = index.compression.get(kind, 0) + 1
                index.uncompressed += _u32(h, "size")
        except (_Truncated, BagError, KeyError, struct.error) as error:
            raise _unindexed(path, f"its index is damaged ({error or 'truncated'})") from None
    return index


def _unindexed(path: Path, reason: str) -> UnindexedBagError:
    result = scan(path)
    return UnindexedBagError(
        path,
        result.valid_end,
        result.size,
        result.chunks,
        result.messages,
        reason,
        cut=result.valid_end < result.size,
    )


@dataclass
class ScanResult:
    size: int = 0
    valid_end: int = 0  # byte after the last complete record read
    chunks: int = 0  # complete chunks
    partial_chunk: bool = False  # a chunk cut by the end of the file (its complete records count)
    messages: int = 0  # recoverable messages: complete records with a known connection
    orphans: int = 0  # complete message records whose connection record was lost
    connections: dict[int, ConnectionInfo] = field(default_factory=dict)


def _decompress(kind: str, data: bytes, partial: bool = False) -> bytes:
    if kind == "none":
        return data
    if kind == "lz4":
        if not partial:
            return lz4.frame.decompress(data)
        d = lz4.frame.LZ4FrameDecompressor()
        try:
            return d.decompress(data)
        except RuntimeError:
            return b""
    if kind == "bz2":
        if not partial:
            return bz2.decompress(data)
        try:
            return bz2.BZ2Decompressor().decompress(data)
        except (OSError, EOFError):
            return b""
    raise BagError(f"chunk compression '{kind}' is not supported (none, lz4, bz2)")


def scan(path: Path | str, on_chunk=None) -> ScanResult:
    """Walk a bag's records in file order, index or not, up to the first incomplete record.

    Every chunk (and a chunk cut by the end of the file, as far as its compressed blocks are
    complete) is decompressed and its records listed; a message is recoverable if its
    connection record came before it (in its chunk or an earlier one). on_chunk(records, data,
    connections) is called for each chunk with the connections known so far, so the
    recoverable messages can be copied out (reindex): what bag info reports for an unindexed
    bag and what reindex writes are counted by this one rule.
    """
    path = Path(path)
    f, size = open_bag_file(path)
    res = ScanResult(size=size, valid_end=len(MAGIC))
    with f:
        while True:
            start = f.tell()
            try:
                h, pos, n = _read_record(f, size)
            except _Truncated:
                _partial_chunk(f, start, size, res, on_chunk)
                break
            except BagError:
                break  # garbage after the last good record
            op = _op(h)
            if op == OP_CHUNK:
                data = _decompress(h.get("compression", b"none").decode(), f.read(n))
                _add_chunk(chunk_records(data), data, res, on_chunk)
                res.chunks += 1
            elif op == OP_CONNECTION:
                conn = connection_from(h, parse_header(f.read(n)))
                res.connections.setdefault(conn.id, conn)
            f.seek(pos + n)
            res.valid_end = pos + n
            if res.valid_end == size:
                break
    return res


def _add_chunk(recs: ChunkRecords, data: bytes, res: ScanResult, on_chunk) -> None:
    _collect_connections(recs, data, res)
    known = np.isin(recs.conn, np.fromiter(res.connections, np.int64))
    res.messages += int(known.sum())
    res.orphans += int(len(known) - known.sum())
    if on_chunk is not None:
        on_chunk(recs, data, res.connections)


def _partial_chunk(f, start: int, size: int, res: ScanResult, on_chunk) -> None:
    """A chunk cut by the end of the file: its complete records are still recoverable."""
    f.seek(start)
    raw = f.read(4)
    if len(raw) < 4:
        return
    (hlen,) = _U32.unpack(raw)
    if start + 8 + hlen > size:
        return
    try:
        h = parse_header(f.read(hlen))
        if _op(h) != OP_CHUNK:
            return
    except BagError:
        return
    f.read(4)
    data = _decompress(h.get("compression", b"none").decode(), f.read(), partial=True)
    recs = chunk_records(data)
    if recs.count == 0:
        return
    res.partial_chunk = True
    _add_chunk(recs, data, res, on_chunk)


def _collect_connections(recs: ChunkRecords, data: bytes, res: ScanResult) -> None:
    for off in recs.connection_offsets:
        hlen = _U32.unpack_from(data, off)[0]
        h = parse_header(data[off + 4 : off + 4 + hlen])
        dlen = _U32.unpack_from(data, off + 4 + hlen)[0]
        body = data[off + 8 + hlen : off + 8 + hlen + dlen]
        conn = connection_from(h, parse_header(body))
        res.connections.setdefault(conn.id, conn)


@dataclass
class ChunkRecords:
    """The complete message records of a decompressed chunk, in order."""

    conn: np.ndarray  # int64 connection ids
    time: np.ndarray  # int64 ns
    offset: np.ndarray  # int64 offset of the message data in the chunk
    length: np.ndarray  # int64 message data length
    connection_offsets: list[int]

    @property
    def count(self) -> int:
        return len(self.conn)


def chunk_records(data: bytes) -> ChunkRecords:
    """The records of a decompressed chunk, walked in order (stops at the first incomplete
    one): for a chunk without its index data (an unindexed bag); `indexed_records` otherwise."""
    unpack = _U32.unpack_from
    n, p = len(data), 0
    conn, tm, off, ln, coffs = [], [], [], [], []
    while p + 4 <= n:
        (hlen,) = unpack(data, p)
        hend = p + 4 + hlen
        if hend + 4 > n:
            break
        (dlen,) = unpack(data, hend)
        dstart = hend + 4
        if dstart + dlen > n:
            break
        op, c, t, i = -1, -1, 0, p + 4
        while i + 4 <= hend:
            (flen,) = unpack(data, i)
            f0 = i + 4
            if data.startswith(b"op=", f0):
                op = data[f0 + 3]
            elif data.startswith(b"conn=", f0):
                (c,) = unpack(data, f0 + 5)
            elif data.startswith(b"time=", f0):
                sec, nsec = struct.unpack_from("<II", data, f0 + 5)
                t = sec * 1_000_000_000 + nsec
            i = f0 + flen
        if op == OP_MSG_DATA:
            conn.append(c)
            tm.append(t)
            off.append(dstart)
            ln.append(dlen)
        elif op == OP_CONNECTION:
            coffs.append(p)
        p = dstart + dlen
    a = lambda v: np.array(v, dtype=np.int64)  # noqa: E731
    return ChunkRecords(a(conn), a(tm), a(off), a(ln), coffs)


def chunk_index(f, chunk: ChunkInfo, size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(connection ids, times in ns, record offsets in the chunk) of a chunk's messages, from the
    index data records that follow the chunk in the open bag file `f` (12 bytes a message, no
    decompression), connection by connection."""
    f.seek(chunk.pos)
    h, p, n = _read_record(f, size)
    f.seek(p + n)
    conn, tm, rec = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for _ in range(len(chunk.counts)):
        h, p, n = _read_record(f, size)
        if _op(h) != OP_INDEX_DATA:
            raise BagError(f"expected index data after the chunk at byte {chunk.pos}")
        e = np.frombuffer(f.read(n), dtype=_INDEX_ENTRY)
        conn.append(np.full(len(e), _u32(h, "conn"), np.int64))
        tm.append(e["sec"].astype(np.int64) * 1_000_000_000 + e["nsec"].astype(np.int64))
        rec.append(e["offset"].astype(np.int64))
    return np.concatenate(conn), np.concatenate(tm), np.concatenate(rec)


def indexed_records(f, chunk: ChunkInfo, size: int, data: bytes) -> ChunkRecords:
    """The message records of a chunk (`data`, decompressed) located by its index data
    (`chunk_index`): the data offset and length are read at each record's offset (numpy, no
    record walk). Records in time order within each connection."""
    conn, tm, rec_off = chunk_index(f, chunk, size)
    buf = np.frombuffer(data, np.uint8)
    if len(rec_off) and rec_off.max() + 4 > len(buf):
        raise BagError(f"index data of the chunk at byte {chunk.pos} points past its end")
    hlen = _u32_at(buf, rec_off)
    data_off = rec_off + 8 + hlen
    if len(data_off) and data_off.max() > len(buf):
        raise BagError(f"index data of the chunk at byte {chunk.pos} points past its end")
    return ChunkRecords(conn, tm, data_off, _u32_at(buf, data_off - 4), [])


def _u32_at(buf: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Little-endian u32 at each offset of a byte array."""
    b = buf[offsets[:, None] + np.arange(4)].astype(np.int64)
    return b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16) | (b[:, 3] << 24)


def read_chunk_data(f, pos: int) -> bytes:
    """The decompressed data of the chunk record at byte pos of an open bag file."""
    f.seek(pos)
    size = os.fstat(f.fileno()).st_size
    try:
        h, p, n = _read_record(f, size)
    except _Truncated:
        raise BagError(f"chunk at byte {pos} runs past the end of the file") from None
    if _op(h) != OP_CHUNK:
        raise BagError(f"no chunk at byte {pos}")
    return _decompress(h.get("compression", b"none").decode(), f.read(n))


_INDEX_ENTRY = np.dtype([("sec", "<u4"), ("nsec", "<u4"), ("offset", "<u4")])


def index_times(index: BagIndex) -> dict[int, np.ndarray]:
    """{connection id: message times in ns} from the index data records after each chunk
    (`chunk_index`, no decompression): what rosbag info's rates come from."""
    parts: dict[int, list[np.ndarray]] = {}
    with index.path.open("rb") as f:
        for chunk in index.chunks:
            conn, tm, _ = chunk_index(f, chunk, index.size)
            for cid in np.unique(conn):
                parts.setdefault(int(cid), []).append(tm[conn == cid])
    return {cid: np.sort(np.concatenate(v)) for cid, v in parts.items()}
