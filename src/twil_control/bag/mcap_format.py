"""MCAP files of ROS 1 messages, read as the bag tools read a rosbag: an index, then chunks.

``read_index`` gives the same ``BagIndex`` as format.read_index from the summary (no chunk
decompressed); ``read_chunk`` gives a chunk's messages as ``format.ChunkRecords``, so reader.Bag
slices numeric fields out of MCAP chunks as out of rosbag chunks. Every read checks CRCs, and a
corrupt chunk is a CorruptMcapError naming its number, time range and message count
(docs/mcap.md).
"""

from __future__ import annotations

import heapq
import struct
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import lz4.frame
import numpy as np

from ..errors import TwilControlError
from . import format as fmt
from .bag_errors import BagError

MAGIC = b"\x89MCAP0\r\n"
OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX, OP_DATA_END, OP_FOOTER = 0x05, 0x06, 0x07, 0x0F, 0x02
_MESSAGE_HEAD = 2 + 4 + 8 + 8  # channel id, sequence, log time, publish time


def is_mcap(path) -> bool:
    with open(path, "rb") as f:
        return f.read(len(MAGIC)) == MAGIC


@dataclass
class McapIndex(fmt.BagIndex):
    times: dict[int, np.ndarray] = field(default_factory=dict)  # channel id -> message times (ns)
    compressed: int = 0  # bytes of compressed chunk data
    chunk_index: dict[int, object] = field(default_factory=dict)  # chunk offset -> mcap ChunkIndex
    profile: str = ""


def md5_of(msgtype: str, msgdef: str) -> str:
    """ROS 1 md5sum of a type from its definition (for MCAP files that do not store it)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    full = msgtype.replace("/", "/msg/", 1)
    store.register(get_types_from_msg(msgdef, full))
    return store.generate_msgdef(full)[1]


@dataclass(frozen=True)
class CorruptChunk:
    """A chunk whose records do not match its CRC (or do not decompress)."""

    number: int  # 1-based, in file order
    of: int
    start_ns: int
    end_ns: int
    messages: int  # as its message indexes count them
    why: str

    def describe(self) -> str:
        return (
            f"chunk {self.number} of {self.of} (t = {self.start_ns / 1e9:.3f} .. {self.end_ns / 1e9:.3f} s, "
            f"{self.messages} messages): {self.why}"
        )


class CorruptMcapError(BagError, TwilControlError):
    """An MCAP file with corrupt bytes: its chunks, or its data section outside them."""

    def __init__(self, path, chunks: list[CorruptChunk], why: str = "") -> None:
        self.path, self.chunks = path, chunks
        what = "; ".join(c.describe() for c in chunks[:3]) + (
            f"; and {len(chunks) - 3} more" if len(chunks) > 3 else ""
        )
        if chunks:
            text = (
                f"{path}: corrupt {what}; python -m twil_control.bag reindex {path} -o NEW.mcap "
                "copies every other chunk"
            )
        else:
            text = f"{path}: {why}"
        super().__init__(text)


def read_index(path, verify: bool = True) -> McapIndex:
    """The file's index; with verify, CorruptMcapError when its CRCs do not match."""
    index = _read_index(path)
    if verify:
        check_crcs(index)
    return index


def check_crcs(index: McapIndex) -> None:
    """The data section's CRC, else every chunk's (a file written without a data CRC)."""
    stored, end = _data_section_crc(index.path, index.size)
    crc = 0
    if stored:
        with open(index.path, "rb") as f:
            left = end
            while left > 0:
                block = f.read(min(left, 1 << 22))
                if not block:
                    break
                crc = zlib.crc32(block, crc)
                left -= len(block)
        if crc == stored:
            return
    corrupt = corrupt_chunks(index)
    if corrupt or stored:
        raise CorruptMcapError(
            index.path,
            corrupt,
            f"its data section's CRC is 0x{crc:08x}, the file says 0x{stored:08x} (corrupt bytes outside "
            "the chunks: a message index or a record between chunks)",
        )


def _data_section_crc(path: Path, size: int) -> tuple[int, int]:
    """(the DataEnd record's CRC, the byte where the record starts): (0, 0) when there is none."""
    footer_len = 1 + 8 + 8 + 8 + 4
    if size < 2 * len(MAGIC) + footer_len + 13:
        return 0, 0
    with open(path, "rb") as f:
        f.seek(size - len(MAGIC) - footer_len)
        op, _, summary_start = struct.unpack("<BQQ", f.read(17))
        if op != OP_FOOTER:
            return 0, 0
        at = (summary_start or size - len(MAGIC) - footer_len) - 13
        f.seek(at)
        op, length, crc = struct.unpack("<BQI", f.read(13))
    return (crc, at) if op == OP_DATA_END and length == 4 else (0, 0)


def corrupt_chunks(index: McapIndex) -> list[CorruptChunk]:
    """Every chunk of the index whose records do not match its CRC, or do not decompress."""
    out = []
    with open(index.path, "rb") as f:
        for chunk in index.chunks:
            try:
                read_chunk(f, index.chunk_index[chunk.pos], index)
            except CorruptMcapError as error:
                out.extend(error.chunks)
    return out


def _corrupt(index: McapIndex, pos: int, why: str) -> CorruptChunk:
    number = next(i for i, c in enumerate(index.chunks, 1) if c.pos == pos)
    chunk = index.chunks[number - 1]
    return CorruptChunk(number, len(index.chunks), chunk.start, chunk.end, sum(chunk.counts.values()), why)


def messages_in_time_order(index: McapIndex, skip: set[int] = frozenset()):
    """(channel id, log time, bytes) of every message of the chunks not in `skip` (chunk
    offsets), in log-time order, decompressing only the chunks that overlap in time at once."""
    chunks = sorted((c for c in index.chunks if c.pos not in skip), key=lambda c: (c.start, c.pos))
    heap: list = []
    with open(index.path, "rb") as f:

        def records(chunk):
            data, recs = read_chunk(f, index.chunk_index[chunk.pos], index)
            for i in sorted(range(len(recs.time)), key=lambda i: recs.time[i]):
                o = int(recs.offset[i])
                yield int(recs.time[i]), int(recs.conn[i]), data[o : o + int(recs.length[i])]

        def push(n: int, it) -> None:
            item = next(it, None)
            if item is not None:
                heapq.heappush(heap, (item[0], n, item, it))

        i = 0
        while i < len(chunks) or heap:
            while i < len(chunks) and (not heap or chunks[i].start <= heap[0][0]):
                push(i, records(chunks[i]))
                i += 1
            _, n, (t, cid, raw), it = heapq.heappop(heap)
            yield cid, t, raw
            push(n, it)


def _read_index(path) -> McapIndex:
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    path = Path(path)
    size = path.stat().st_size
    with path.open("rb") as f:
        try:
            reader = make_reader(f)
            header = reader.get_header()
            summary = reader.get_summary()
        except (McapError, struct.error, EOFError, ValueError) as error:
            raise _unindexed(path, f"without a readable summary ({error})") from None
        if (
            summary is None
            or not summary.chunk_indexes
            and summary.statistics
            and summary.statistics.message_count
        ):
            raise _unindexed(path, "with no summary (not closed, or written without chunk indexes)")
        connections = {}
        for cid, ch in sorted(summary.channels.items()):
            schema = summary.schemas.get(ch.schema_id)
            if ch.message_encoding != "ros1" or schema is None or schema.encoding != "ros1msg":
                raise BagError(
                    f"{path}: channel {ch.topic} is {ch.message_encoding} with a "
                    f"{schema.encoding if schema else 'missing'} schema; the bag tools read ROS 1 "
                    "messages (ros1 encoding, ros1msg schemas)"
                )
            msgdef = schema.data.decode()
            md5 = ch.metadata.get("md5sum") or md5_of(schema.name, msgdef)
            latching = "1" if ch.metadata.get("latching") in ("true", "1") else None
            connections[cid] = fmt.ConnectionInfo(
                cid, ch.topic, schema.name, md5, msgdef, ch.metadata.get("callerid"), latching
            )
        chunks, times, kinds = [], {}, {}
        uncompressed = compressed = 0
        by_offset = {}
        for ci in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
            counts = {}
            for cid, t in _message_index_times(f, ci).items():
                counts[cid] = len(t)
                times.setdefault(cid, []).append(t)
            chunks.append(
                fmt.ChunkInfo(ci.chunk_start_offset, ci.message_start_time, ci.message_end_time, counts)
            )
            by_offset[ci.chunk_start_offset] = ci
            kinds[ci.compression or "none"] = kinds.get(ci.compression or "none", 0) + 1
            uncompressed += ci.uncompressed_size
            compressed += ci.compressed_size
    return McapIndex(
        path,
        size,
        0,
        connections,
        chunks,
        kinds,
        uncompressed,
        {cid: np.sort(np.concatenate(v)) for cid, v in times.items()},
        compressed,
        by_offset,
        header.profile,
    )


def _unindexed(path: Path, reason: str) -> BagError:
    """The error for an MCAP file without a usable summary: what reindex would recover."""
    found = scan(path)
    return BagError(
        f"{path} is an MCAP file {reason}; {found.messages} complete messages in {found.chunks} "
        f"complete chunks are recoverable; recover them with: python -m twil_control.bag "
        f"reindex {path} -o NEW.mcap"
    )


@dataclass
class McapScan:
    messages: int = 0  # recoverable: complete messages whose channel and schema came before
    chunks: int = 0  # complete chunks, corrupt ones included
    orphans: int = 0  # complete messages whose channel or schema record was lost
    complete: bool = False  # the file ends with its footer
    cut: bool = False  # the file ends inside a record (not at the boundary of one)
    corrupt: list[CorruptChunk] = field(default_factory=list)  # left out, with their messages

    @property
    def dropped(self) -> int:
        """Messages of the corrupt chunks, as their message indexes count them."""
        return sum(c.messages for c in self.corrupt)


def scan(path, on_message=None) -> McapScan:
    """Walk an MCAP file's records in file order (the ``mcap`` package's stream reader, inside
    chunks too) up to the first incomplete one, as a crash leaves it. A message is recoverable
    if its channel and schema records came before it and its chunk matches its CRC; a corrupt
    chunk is left out whole (McapScan.corrupt). on_message(channel, schema, message) is called
    for each recoverable message, so reindex copies exactly what bag info counts."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Chunk, Footer, Message, MessageIndex, Schema
    from mcap.stream_reader import StreamReader, breakup_chunk

    out = McapScan()
    schemas, channels = {}, {}
    bad: list[list] = []  # [number, start, end, messages, why] of the corrupt chunks
    size = Path(path).stat().st_size
    end = 0
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, emit_chunks=True).records:
                end = f.tell()
                inner = [record]
                if isinstance(record, Chunk):
                    out.chunks += 1
                    try:
                        _decompressed(
                            record.compression,
                            record.data,
                            record.uncompressed_size,
                            record.uncompressed_crc,
                            f"{path}: chunk {out.chunks}",
                        )
                        inner = breakup_chunk(record)
                    except ChunkCrcError as error:
                        bad.append(
                            [out.chunks, record.message_start_time, record.message_end_time, 0, str(error)]
                        )
                        inner = []
                elif isinstance(record, MessageIndex) and bad and bad[-1][0] == out.chunks:
                    bad[-1][3] += len(record.records)  # a corrupt chunk's messages, indexed after it
                for r in inner:
                    if isinstance(r, Schema):
                        schemas[r.id] = r
                    elif isinstance(r, Channel):
                        channels[r.id] = r
                    elif isinstance(r, Message):
                        channel = channels.get(r.channel_id)
                        schema = schemas.get(channel.schema_id) if channel else None
                        if schema is None:
                            out.orphans += 1
                            continue
                        out.messages += 1
                        if on_message is not None:
                            on_message(channel, schema, r)
                out.complete |= isinstance(record, Footer)
        except (McapError, EOFError, ValueError, struct.error):
            out.cut = end < size  # the file ends inside a record: everything before it counts
    out.corrupt = [CorruptChunk(n, out.chunks, s, e, m, why) for n, s, e, m, why in bad]
    return out


def _message_index_times(f, ci) -> dict[int, np.ndarray]:
    """{channel: times} of one chunk from its message index records (16 bytes a message)."""
    out = {}
    for cid, offset in ci.message_index_offsets.items():
        f.seek(offset)
        head = f.read(1 + 8 + 2 + 4)
        op, _, channel, n = struct.unpack("<BQHI", head)
        if op != OP_MESSAGE_INDEX or channel != cid:
            raise BagError(f"{f.name}: no message index of channel {cid} at byte {offset}")
        entries = np.frombuffer(f.read(n), dtype=np.dtype([("time", "<u8"), ("offset", "<u8")]))
        out[cid] = entries["time"].astype(np.int64)
    return out


def read_chunk(f, ci, index: McapIndex | None = None) -> tuple[bytes, fmt.ChunkRecords]:
    """The decompressed records of the chunk `ci` (an mcap ChunkIndex) and its messages;
    CorruptMcapError when they do not match the chunk's CRC or do not decompress."""
    f.seek(ci.chunk_start_offset)
    raw = f.read(ci.chunk_length)
    try:
        data = chunk_records_data(raw, ci.chunk_start_offset, f.name)
    except ChunkCrcError as error:
        if index is None:
            index = _read_index(f.name)
        raise CorruptMcapError(f.name, [_corrupt(index, ci.chunk_start_offset, str(error))]) from None
    return data, message_records(data)


class ChunkCrcError(BagError):
    """A chunk whose decompressed records do not match its CRC, or that does not decompress."""


def chunk_records_data(raw: bytes, pos: int, name: str) -> bytes:
    """The decompressed records of a Chunk record (opcode, length, then its fields), checked
    against the chunk's size and CRC (ChunkCrcError)."""
    if len(raw) < 9 or raw[0] != OP_CHUNK:
        raise BagError(f"{name}: no MCAP chunk at byte {pos}")
    p = 1 + 8 + 8 + 8  # opcode, length, start time, end time
    size, crc = struct.unpack_from("<QI", raw, p)
    p += 8 + 4  # uncompressed size, crc
    (n,) = struct.unpack_from("<I", raw, p)
    compression = raw[p + 4 : p + 4 + n].decode("utf-8", "replace")
    p += 4 + n
    (length,) = struct.unpack_from("<Q", raw, p)
    records = raw[p + 8 : p + 8 + length]
    return _decompressed(compression, records, size, crc, f"{name}: chunk at byte {pos}")


def _decompressed(compression: str, records: bytes, size: int, crc: int, where: str) -> bytes:
    """A chunk's records decompressed and checked against its size and CRC (ChunkCrcError)."""
    try:
        if compression == "":
            data = bytes(records)
        elif compression == "zstd":
            import zstandard

            data = zstandard.ZstdDecompressor().decompress(records, max_output_size=size)
        elif compression == "lz4":
            data = lz4.frame.decompress(records)
        else:
            raise BagError(f"{where} is compressed with '{compression}' (readable: zstd, lz4)")
    except BagError:
        raise
    except Exception as error:  # zstandard and lz4 raise their own types on corrupt input
        raise ChunkCrcError(f"it does not decompress ({type(error).__name__}: {error})") from None
    if len(data) != size:
        raise ChunkCrcError(f"it decompresses to {len(data)} bytes, the chunk says {size}")
    if crc and zlib.crc32(data) != crc:
        raise ChunkCrcError(f"its records' CRC is 0x{zlib.crc32(data):08x}, the chunk says 0x{crc:08x}")
    return data


def message_records(data: bytes) -> fmt.ChunkRecords:
    """The message records of decompressed chunk data, as format.ChunkRecords (stops at the
    first incomplete record)."""
    conn, tm, off, ln = [], [], [], []
    unpack = struct.unpack_from
    p, n = 0, len(data)
    while p + 9 <= n:
        op, length = unpack("<BQ", data, p)
        body = p + 9
        if body + length > n:
            break
        if op == OP_MESSAGE:
            channel, _, log_time = unpack("<HIQ", data, body)
            conn.append(channel)
            tm.append(log_time)
            off.append(body + _MESSAGE_HEAD)
            ln.append(length - _MESSAGE_HEAD)
        p = body + length
    a = lambda v: np.array(v, dtype=np.int64)  # noqa: E731
    return fmt.ChunkRecords(a(conn), a(tm), a(off), a(ln), [])
