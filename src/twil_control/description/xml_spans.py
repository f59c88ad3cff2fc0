"""An XML file as a tree of elements that know where they are in its bytes (expat, no Drake).

The Gazebo world normaliser (description.gazebo_world) edits a user's file by replacing byte
spans of it, so that everything it leaves alone keeps its bytes and its line; this tree says
where each element's start tag and whole text begin and end, and `SpanFile` applies the edits. Entities are not expanded: a
DOCTYPE is refused (SDF files have none). Comments are read as Gazebo's and Drake's XML reader
(tinyxml2) reads them, "--" inside one allowed (`lenient`).
"""

from __future__ import annotations

import bisect
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from .urdf import DescriptionError

__all__ = ["Element", "SpanFile", "escape", "lenient", "read_tree", "start_tag"]

_COMMENT = re.compile(rb"<!--(.*?)-->", re.S)


def lenient(data: bytes) -> bytes:
    """`data` with every "-" inside a comment made a space: strict XML forbids "--" there,
    tinyxml2 does not (a Markdown table in a world's comment). Same length, same offsets."""
    if b"--" not in data:
        return data
    return _COMMENT.sub(lambda m: b"<!--" + m.group(1).replace(b"-", b" ") + b"-->", data)


@dataclass(eq=False, slots=True)
class Element:
    tag: str
    attrs: dict[str, str]
    start: int  # offset of its '<'
    tag_end: int  # just past its start tag's '>'
    end: int  # just past its end tag (tag_end for an empty-element tag)
    line: int  # 1-based line of its start tag
    parent: Element | None = None
    children: list[Element] = field(default_factory=list)
    text: str = ""  # its own character data, stripped

    def find(self, tag: str) -> Element | None:
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list[Element]:
        return [c for c in self.children if c.tag == tag]

    def findtext(self, tag: str, default: str | None = None) -> str | None:
        child = self.find(tag)
        return default if child is None else child.text

    def iter(self, tag: str | None = None):
        if tag is None or self.tag == tag:
            yield self
        for child in self.children:
            yield from child.iter(tag)

    def ancestors(self):
        node = self.parent
        while node is not None:
            yield node
            node = node.parent

    @property
    def empty_tag(self) -> bool:
        return self.tag_end == self.end


#: A start tag: '>' closes it unless it stands inside a quoted attribute value.
_START_TAG = re.compile(rb"""<[^>"']*(?:(?:"[^"]*"|'[^']*')[^>"']*)*>""")


def _tag_end(data: bytes, start: int) -> int:
    """Just past the '>' closing the tag at `start`."""
    match = _START_TAG.match(data, start)
    return match.end() if match else len(data)


def read_tree(data: bytes, source: str) -> Element:
    """The root element of `data`; DescriptionError naming `source` and the line when it is not
    well-formed XML."""
    parser = expat.ParserCreate()
    stack: list[Element] = []
    texts: list[list[str]] = []
    root: list[Element] = []

    def start(tag: str, attrs: dict) -> None:
        index = parser.CurrentByteIndex
        node = Element(tag, attrs, index, _tag_end(data, index), 0, parser.CurrentLineNumber)
        if stack:
            node.parent = stack[-1]
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)
        texts.append([])

    def end(_tag: str) -> None:
        node = stack.pop()
        index = parser.CurrentByteIndex
        empty = data[node.tag_end - 2 : node.tag_end] == b"/>"
        node.end = node.tag_end if empty else data.find(b">", index) + 1
        node.text = "".join(texts.pop()).strip()

    def chars(text: str) -> None:
        if texts:
            texts[-1].append(text)

    def doctype(*_args) -> None:
        raise DescriptionError(
            f"{source}:{parser.CurrentLineNumber}: a DOCTYPE is not read (SDF files have none)"
        )

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(lenient(data), True)
    except expat.ExpatError as error:
        raise DescriptionError(
            f"{source}:{error.lineno}: not well-formed XML ({expat.ErrorString(error.code)})"
        ) from None
    return root[0]


def _newlines(data: bytes, start: int, end: int) -> bytes:
    return b"\n" * data.count(b"\n", start, end)


def escape(value: str) -> str:
    return value.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")


def start_tag(tag: str, attrs: dict[str, str], empty: bool = False) -> str:
    inner = "".join(f' {k}="{escape(v)}"' for k, v in attrs.items())
    return f"<{tag}{inner}{'/' if empty else ''}>"


class SpanFile:
    """One file being rewritten: its bytes, its tree and the edits (spans replaced, each
    keeping the newlines of what it replaces)."""

    def __init__(self, data: bytes, source: str, folder: Path | None) -> None:
        self.data, self.source, self.folder = data, source, folder
        self.root = read_tree(data, source)
        self.edits: list[tuple[int, int, int, bytes]] = []
        self._sorted: list | None = None

    def where(self, el: Element) -> str:
        return f"{self.source}:{el.line}"

    def replace(self, start: int, end: int, text: str | bytes) -> None:
        raw = text.encode() if isinstance(text, str) else text
        self.edits.append((start, end, len(self.edits), raw.replace(b"\n", b" ")))

    def remove(self, el: Element) -> None:
        self.replace(el.start, el.end, b"")

    def insert_into(self, el: Element, text: str) -> None:
        """Insert `text` as the first content of `el` (an element with an end tag)."""
        self.replace(el.tag_end, el.tag_end, text)

    def slice(self, el: Element) -> bytes:
        return self.data[el.start : el.end]

    def render(self, start: int = 0, end: int | None = None) -> bytes:
        """The span [start, end) with the edits inside it applied; every replaced span keeps
        its newlines, so the text after it keeps its lines."""
        end = len(self.data) if end is None else end
        if self._sorted is None or len(self._sorted) != len(self.edits):
            self._sorted = sorted(self.edits)
        edits = self._sorted[bisect.bisect_left(self._sorted, (start,)) :]
        out, at = [], start
        for s, e, _, text in edits:
            if s >= end or e > end:
                break
            if s < at:  # nested in a span already replaced (never planned; kept safe)
                continue
            out += [self.data[at:s], text, _newlines(self.data, s, e)]
            at = e
        out.append(self.data[at:end])
        return b"".join(out)

    def element(self, el: Element) -> ET.Element:
        """`el` (with its original text) as an ElementTree element."""
        wrapped = b'<w xmlns:drake="http://drake.mit.edu">' + self.slice(el) + b"</w>"
        try:
            return ET.fromstring(wrapped)[0]
        except ET.ParseError as error:
            raise DescriptionError(f"{self.where(el)}: <{el.tag}> cannot be read ({error})") from None
