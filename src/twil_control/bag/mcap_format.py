"""MCAP files of ROS 1 messages, read as the bag tools read a rosbag: an index, then chunks.

``read_index`` gives the same ``BagIndex`` as format.read_index: connections from the
summary's channels and schemas (topic, ``pkg/Type``, the ros1msg definition, md5sum and
latching from the channel's metadata, the md5sum computed from the definition where the
file has none), one ``ChunkInfo`` per chunk index with its per-channel counts and the
messages' times from the message indexes (no chunk is decompressed). ``read_chunk``
decompresses one chunk and lists its message records as ``format.ChunkRecords``, so
reader.Bag slices numeric fields out of MCAP chunks as out of rosbag chunks.

The summary is read by the ``mcap`` package; the records inside a chunk and the message
indexes are walked here, by their offsets, to give the data as one buffer with offsets.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

import lz4.frame
import numpy as np

from . import format as fmt
from .errors import BagError

MAGIC = b"\x89MCAP0\r\n"
OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX = 0x05, 0x06, 0x07
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


def read_index(path) -> McapIndex:
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
    chunks: int = 0  # complete chunks
    orphans: int = 0  # complete messages whose channel or schema record was lost
    complete: bool = False  # the file ends with its footer


def scan(path, on_message=None) -> McapScan:
    """Walk an MCAP file's records in file order (the ``mcap`` package's stream reader, inside
    chunks too) up to the first incomplete one, as a crash leaves it. A message is recoverable
    if its channel and schema records came before it; on_message(channel, schema, message) is
    called for each, so reindex copies exactly what bag info counts."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Chunk, Footer, Message, Schema
    from mcap.stream_reader import StreamReader, breakup_chunk

    out = McapScan()
    schemas, channels = {}, {}
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, emit_chunks=True).records:
                inner = breakup_chunk(record) if isinstance(record, Chunk) else [record]
                out.chunks += isinstance(record, Chunk)
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
            pass  # the file ends inside a record: everything before it counts
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


def read_chunk(f, ci) -> tuple[bytes, fmt.ChunkRecords]:
    """The decompressed records of the chunk `ci` (an mcap ChunkIndex) and its messages."""
    f.seek(ci.chunk_start_offset)
    raw = f.read(ci.chunk_length)
    data = chunk_records_data(raw, ci.chunk_start_offset, f.name)
    return data, message_records(data)


def chunk_records_data(raw: bytes, pos: int, name: str) -> bytes:
    """The decompressed records of a Chunk record (opcode, length, then its fields)."""
    if len(raw) < 9 or raw[0] != OP_CHUNK:
        raise BagError(f"{name}: no MCAP chunk at byte {pos}")
    p = 1 + 8 + 8 + 8  # opcode, length, start time, end time
    (size,) = struct.unpack_from("<Q", raw, p)
    p += 8 + 4  # uncompressed size, crc
    (n,) = struct.unpack_from("<I", raw, p)
    compression = raw[p + 4 : p + 4 + n].decode()
    p += 4 + n
    (length,) = struct.unpack_from("<Q", raw, p)
    records = raw[p + 8 : p + 8 + length]
    if compression == "":
        return bytes(records)
    if compression == "zstd":
        import zstandard

        return zstandard.ZstdDecompressor().decompress(records, max_output_size=size)
    if compression == "lz4":
        return lz4.frame.decompress(records)
    raise BagError(f"{name}: chunk at byte {pos} is compressed with '{compression}' (readable: zstd, lz4)")


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
