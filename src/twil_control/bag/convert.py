"""``convert``: ROS 1 bag <-> MCAP (ROS 1 profile), and either to a ROS 2 bag (docs/mcap.md).

Bag to MCAP and back keeps every connection (topic, type, definition, md5sum, callerid,
latching) and every message's time and bytes. A ROS 2 bag is written by rosbags' converter, which
turns the messages into their ROS 2 form. The output is written under a temporary name and named
at the end without replacing anything, so a failed conversion leaves no output (bag/output.py).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from .bag_errors import BagError
from .mcap_format import is_mcap
from .mcap_writer import McapWriter
from .output import check_new_output, folder_beside, written_beside

FORMATS = ("bag", "mcap", "ros2")


@dataclass
class Conversion:
    out: Path
    to: str
    messages: int
    connections: int
    corrupt: list = field(default_factory=list)  # MCAP chunks left out (mcap_format.CorruptChunk)

    @property
    def dropped(self) -> int:
        return sum(c.messages for c in self.corrupt)


def output_format(out: Path, to: str | None) -> str:
    """The output's format: `to`, or its suffix (.bag, .mcap)."""
    if to is None:
        to = {".bag": "bag", ".mcap": "mcap"}.get(out.suffix)
        if to is None:
            raise BagError(f"output {out}: name it .bag or .mcap, or say --to ros2 for a ROS 2 bag folder")
    if to not in FORMATS:
        raise BagError(f"--to {to}: use one of {', '.join(FORMATS)}")
    if to in ("bag", "mcap") and out.suffix != f".{to}":
        raise BagError(f"output {out}: a {to} file is named .{to}")
    return to


def convert(
    src: Path | str, out: Path | str, to: str | None = None, compression: str = "zstd", force: bool = False
) -> Conversion:
    src, out = Path(src), Path(out)
    if not src.is_file():
        raise BagError(f"input {src} is not a file")
    to = output_format(out, to)
    if to == "ros2" and out.exists():
        raise BagError(
            f"output {out} exists; a ROS 2 bag folder is never replaced, even with --force: "
            "choose another name"
        )
    check_new_output(out, "output", force)
    if out.exists() and out.resolve() == src.resolve():
        raise BagError("the output must be another file than the input")
    source_mcap = is_mcap(src)
    if to == "ros2":
        return _to_ros2(src, out, source_mcap)
    if (to == "mcap") == source_mcap:
        raise BagError(
            f"{src} is already {'an MCAP file' if source_mcap else 'a ROS 1 bag'}; convert it to "
            f"{'a .bag' if source_mcap else 'an .mcap'} file or --to ros2"
        )
    corrupt: list = []
    with written_beside(out, force) as part:
        n, c = _mcap_to_bag(src, part, corrupt) if source_mcap else _bag_to_mcap(src, part, compression)
    return Conversion(out, to, n, c, corrupt)


def _bag_to_mcap(src: Path, out: Path, compression: str) -> tuple[int, int]:
    from rosbags.rosbag1 import Reader, ReaderError

    writer = McapWriter(out, chunk_seconds=0, compression=compression)
    writer.open()
    n = 0
    try:
        with Reader(src) as reader:
            conns = {
                c.id: writer.add_connection(
                    c.topic,
                    c.msgtype,
                    msgdef=c.msgdef.data,
                    md5sum=c.digest,
                    callerid=c.ext.callerid,
                    latching=c.ext.latching,
                )
                for c in reader.connections
            }
            for c, t, raw in reader.messages():
                writer.write(conns[c.id], t, raw)
                n += 1
    except ReaderError as error:
        writer.abort()
        raise BagError(f"{src}: {error}") from None
    writer.close()
    return n, len(conns)


def _mcap_to_bag(src: Path, out: Path, corrupt: list | None = None) -> tuple[int, int]:
    """Every message of the chunks that match their CRC; the others are appended to `corrupt`."""
    from .mcap_format import corrupt_chunks, messages_in_time_order, read_index
    from .writer import ChunkedWriter

    index = read_index(src, verify=False)  # the connections as the bag tools read them (md5sum, latching)
    bad = corrupt_chunks(index)
    if corrupt is not None:
        corrupt.extend(bad)
    skip = {index.chunks[c.number - 1].pos for c in bad}
    writer = ChunkedWriter(out, chunk_seconds=0)
    writer.set_compression(ChunkedWriter.CompressionFormat.LZ4)
    writer.open()
    conns = {
        cid: writer.add_connection(
            c.topic,
            c.msgtype.replace("/", "/msg/", 1),
            msgdef=c.msgdef,
            md5sum=c.md5sum,
            callerid=c.callerid,
            latching=1 if c.latching == "1" else None,
        )
        for cid, c in index.connections.items()
    }
    n = 0
    try:
        for cid, t, raw in messages_in_time_order(index, skip):
            writer.write(conns[cid], t, raw)
            n += 1
    except BaseException:
        writer.abort()
        raise
    writer.close()
    return n, len(conns)


def _to_ros2(src: Path, out: Path, source_mcap: bool) -> Conversion:
    from rosbags.convert import convert as rosbags_convert
    from rosbags.convert.converter import ConverterError

    from ..core import messages

    corrupt: list = []
    with folder_beside(out) as tmp:
        ros1 = src
        if source_mcap:
            ros1 = Path(tmp) / "ros1.bag"
            _mcap_to_bag(src, ros1, corrupt)
        part = Path(tmp) / out.name
        try:
            rosbags_convert([ros1], part, "mcap", 8, None, "file", messages.typestore(), None, [], [], [], [])
        except ConverterError as error:
            raise BagError(f"{src}: {error}") from None
        from rosbags.rosbag2 import Reader

        with Reader(part) as reader:
            n, c = reader.message_count, len(reader.connections)
        os.rename(part, out)  # a folder: rename fails if out appeared meanwhile and is not empty
    return Conversion(out, "ros2", n, c, corrupt)
