"""An SDF world cut into its top-level models, as written (XML only, no Drake).

Drake's parser takes time that grows with the square of a world's size, so a world whose models
do not refer to one another is read a few hundred models at a time (docs/inputs.md, "Large
worlds"). A piece is the file's own bytes, re-joined under its ``<sdf>`` and ``<world>`` tags with
blank lines that keep every model on its line, so Drake's messages name the file's lines. A
world stays whole when a piece alone could mean something else (`why_whole` says why).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ..description.xml_spans import lenient

#: Default of the collision geometries a simulated world may hold (world/static_world.py):
#: SceneGraph's pair table grows with their square (docs/inputs.md; bench/world_build_bench.py
#: measures it). Here, without Drake, so that node parameters can name it.
MAX_COLLISION_GEOMETRIES = 2000

#: World-level elements that tie models together: their presence keeps a world whole.
_LINKING = {"frame", "joint", "include"}


@dataclass
class ModelText:
    """One top-level model of a world file."""

    name: str
    static: bool
    text: bytes  # the <model> element as written
    line: int  # its first line in the file (1-based)


@dataclass
class SplitWorld:
    head: bytes  # the file up to and including the <world ...> start tag
    head_lines: int  # newlines in head
    tail: bytes = b"\n</world>\n</sdf>\n"
    models: list[ModelText] = field(default_factory=list)

    def text(self, models: list[ModelText]) -> bytes:
        """A world file holding `models` (in file order), each on its original line."""
        out, line = [self.head], 1 + self.head_lines
        for model in models:
            out.append(b"\n" * max(0, model.line - line))
            line = max(line, model.line) + model.text.count(b"\n")
            out.append(model.text)
        out.append(self.tail)
        return b"".join(out)


@dataclass
class WorldScan:
    """What the file holds, whether or not it can be split."""

    collisions: int = 0  # <collision> elements in the whole file
    split: SplitWorld | None = None
    why_whole: str = ""  # why split is None


class _Abort(Exception):
    pass


def scan_world(world: str | Path | bytes) -> WorldScan:
    """Scan an SDF world's XML, a file or its text (it is not validated here: Drake's parser
    does that)."""
    data = world if isinstance(world, bytes) else Path(world).read_bytes()
    scanner = _WorldScanner(data)
    try:
        scanner.parser.Parse(lenient(data), True)
    except _Abort:
        return WorldScan(scanner.collisions, why_whole=scanner.whole)
    except expat.ExpatError as error:  # Drake's parser gives the user its own message
        return WorldScan(scanner.collisions, why_whole=f"it is not well-formed XML ({error})")
    scanner.check_whole_file()
    if scanner.whole:
        return WorldScan(scanner.collisions, why_whole=scanner.whole)
    return WorldScan(scanner.collisions, split=scanner.split())


class _WorldScanner:
    """expat's handlers for scan_world: the top-level models' byte spans, the <collision>
    count, and the first reason found to keep the world whole."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.parser = expat.ParserCreate()
        self.parser.StartElementHandler = self.start
        self.parser.EndElementHandler = self.end
        self.parser.CharacterDataHandler = self.text
        self.parser.StartDoctypeDeclHandler = self.doctype
        self.stack: list[str] = []
        self.models: list[dict] = []
        self.current: dict | None = None  # the top-level model being read
        self.static_text: list[str] | None = None  # its <static>'s text, while inside it
        self.world_tag = 0  # byte offset of the <world> start tag
        self.worlds = 0
        self.collisions = 0
        self.whole = ""

    def keep_whole(self, reason: str) -> None:
        if not self.whole:
            self.whole = reason

    def start(self, name: str, attrs: dict) -> None:
        depth = len(self.stack)
        index = self.parser.CurrentByteIndex
        self.stack.append(name)
        if name == "include":
            self.keep_whole("it has an <include> (resolved against the file's folder)")
        if depth <= 1:
            self._start_top_level(depth, name, index)
        elif depth == 2 and self.stack[1] == "world":
            self._start_world_child(name, attrs, index)
        elif depth == 3 and self.current is not None:
            self._start_model_child(name, attrs, self.current["name"])
        if name == "collision":
            self.collisions += 1

    def _start_top_level(self, depth: int, name: str, index: int) -> None:
        if depth == 0:
            if name != "sdf":
                self.keep_whole(f"its root element is <{name}>, not <sdf>")
        elif name == "world":
            self.worlds += 1
            self.world_tag = index
        else:
            self.keep_whole(f"it has a top-level <{name}> outside a <world>")

    def _start_world_child(self, name: str, attrs: dict, index: int) -> None:
        if name == "model":
            self.current = {
                "name": attrs.get("name", ""),
                "start": index,
                "static": False,
                "line": self.parser.CurrentLineNumber,
            }
            if attrs.get("placement_frame"):
                self.keep_whole(f"model {self.current['name']!r} has a placement_frame")
        elif name in _LINKING:
            self.keep_whole(f"it has a world-level <{name}>")

    def _start_model_child(self, name: str, attrs: dict, model: str) -> None:
        if name == "static":
            self.static_text = []
        elif name == "pose" and attrs.get("relative_to", "world") not in ("", "world"):
            self.keep_whole(f"model {model!r} is posed relative_to {attrs['relative_to']!r}")

    def end(self, name: str) -> None:
        self.stack.pop()
        depth = len(self.stack)
        if depth == 3 and name == "static" and self.static_text is not None and self.current:
            self.current["static"] = "".join(self.static_text).strip().lower() in ("true", "1")
            self.static_text = None
        elif depth == 2 and name == "model" and self.current is not None:
            self.current["end"] = self.data.index(b">", self.parser.CurrentByteIndex) + 1
            self.models.append(self.current)
            self.current = None

    def text(self, chars: str) -> None:
        if self.static_text is not None:
            self.static_text.append(chars)

    def doctype(self, *_args) -> None:
        self.keep_whole("it has a DOCTYPE")
        raise _Abort

    def check_whole_file(self) -> None:
        """The reasons to keep the world whole that need the whole file read."""
        if self.worlds != 1:
            self.keep_whole(f"it has {self.worlds} <world> elements")
        names = [m["name"] for m in self.models]
        if len(set(names)) != len(names):
            self.keep_whole("two of its models have the same name")

    def split(self) -> SplitWorld:
        data = self.data
        head_end = data.index(b">", self.world_tag) + 1
        split = SplitWorld(head=data[:head_end], head_lines=data.count(b"\n", 0, head_end))
        for m in self.models:
            split.models.append(ModelText(m["name"], m["static"], data[m["start"] : m["end"]], m["line"]))
        return split
