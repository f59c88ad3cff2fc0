"""An SDF world cut into its top-level models, as written (XML only, no Drake).

Drake's parser takes time that grows with the square of a world's size (each model added costs
time proportional to the bodies already in the plant; measured: 1,000 static boxes 2.0 s,
5,000 boxes 77 s, and Finalize() 0.6 s against 37 s). When the models of a world do not refer
to one another, each can be parsed alone, so a world is read in pieces of a few hundred models
and the cost stays proportional to its size. The world is the normalised text Drake reads
(description.gazebo_world: includes inlined, planes as boxes), whose lines are the file's.

`split_world` finds each top-level ``<model>``'s bytes in the file with expat's byte offsets,
so a piece is the file's own text (namespaces, comments and all), re-joined under the file's own
``<sdf>`` and ``<world>`` tags with blank lines that keep every model on its original line (a
Drake message about a piece names the line of the file). A world is not split (`SplitWorld`
is None) when a piece could mean something else alone: an ``<include>`` (the normaliser
leaves none; mesh URIs it makes absolute), a world-level ``<frame>`` or ``<joint>``, a model posed
``relative_to`` another, a DOCTYPE, or two models of the same name.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ..description.xml_spans import lenient

#: Default of the collision geometries a simulated world may hold (world/static_world.py):
#: a world of 1,990 boxes builds in 11 s and 0.85 GB, SceneGraph's pair table most of it
#: (quadratic: 1,000 boxes 3.5 s and 0.32 GB; bench/world_build_bench.py). Here, without
#: Drake, so that node parameters can name it.
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
    scan = WorldScan()
    parser = expat.ParserCreate()
    stack: list[str] = []
    models: list[dict] = []
    state: dict = {"world_tag": None, "whole": "", "worlds": 0, "static_text": None}
    current: dict | None = None

    def keep_whole(reason: str) -> None:
        if not state["whole"]:
            state["whole"] = reason

    def start(name: str, attrs: dict) -> None:
        nonlocal current
        depth = len(stack)
        index = parser.CurrentByteIndex
        stack.append(name)
        if name == "include":
            keep_whole("it has an <include> (resolved against the file's folder)")
        if depth == 0 and name != "sdf":
            keep_whole(f"its root element is <{name}>, not <sdf>")
        elif depth == 1 and name == "world":
            state["worlds"] += 1
            state["world_tag"] = index
        elif depth == 1:
            keep_whole(f"it has a top-level <{name}> outside a <world>")
        elif depth == 2 and stack[1] == "world":
            if name == "model":
                current = {
                    "name": attrs.get("name", ""),
                    "start": index,
                    "static": False,
                    "line": parser.CurrentLineNumber,
                }
                if attrs.get("placement_frame"):
                    keep_whole(f"model {current['name']!r} has a placement_frame")
            elif name in _LINKING:
                keep_whole(f"it has a world-level <{name}>")
        elif depth == 3 and current is not None:
            if name == "static":
                state["static_text"] = []
            elif name == "pose" and attrs.get("relative_to", "world") not in ("", "world"):
                keep_whole(f"model {current['name']!r} is posed relative_to {attrs['relative_to']!r}")
        if name == "collision":
            scan.collisions += 1

    def end(name: str) -> None:
        nonlocal current
        stack.pop()
        depth = len(stack)
        if depth == 3 and name == "static" and state["static_text"] is not None and current:
            current["static"] = "".join(state["static_text"]).strip().lower() in ("true", "1")
            state["static_text"] = None
        elif depth == 2 and name == "model" and current is not None:
            index = parser.CurrentByteIndex
            current["end"] = data.index(b">", index) + 1
            models.append(current)
            current = None

    def text(chars: str) -> None:
        if state["static_text"] is not None:
            state["static_text"].append(chars)

    def doctype(*_args) -> None:
        keep_whole("it has a DOCTYPE")
        raise _Abort

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(lenient(data), True)
    except _Abort:
        scan.why_whole = state["whole"]
        return scan
    except expat.ExpatError as error:  # Drake's parser gives the user its own message
        scan.why_whole = f"it is not well-formed XML ({error})"
        return scan
    if state["worlds"] != 1:
        keep_whole(f"it has {state['worlds']} <world> elements")
    names = [m["name"] for m in models]
    if len(set(names)) != len(names):
        keep_whole("two of its models have the same name")
    if state["whole"]:
        scan.why_whole = state["whole"]
        return scan
    head_end = data.index(b">", state["world_tag"]) + 1
    split = SplitWorld(head=data[:head_end], head_lines=data.count(b"\n", 0, head_end))
    for m in models:
        split.models.append(ModelText(m["name"], m["static"], data[m["start"] : m["end"]], m["line"]))
    scan.split = split
    return scan
