"""roslaunch XML read into the element tree the launch loader walks (the YAML form).

Each element becomes ``{tag: {attribute: value}}`` with its children under ``children``; a
``<rosparam>``'s text is padded with blank lines so YAML's line numbers are the file's, and every
element's line and column are kept, so messages point into the XML. defusedxml's SAX parser
refuses entity declarations (billion laughs) and external entities or DTDs.
"""

from __future__ import annotations

import xml.sax
from pathlib import Path
from typing import Any

import defusedxml
import defusedxml.sax

from twil_control.core.yaml_io import Lines, display_path
from twil_control.errors import TwilControlError

#: Keys the reader itself adds to an element's body; no attribute may be called so.
SYNTHETIC_KEYS = ("children", "text")


class XmlLaunchError(TwilControlError, ValueError):
    """XML that cannot be read as a launch file; the message names file:line:column."""


class _Handler(xml.sax.ContentHandler):
    def __init__(self, label: str) -> None:
        super().__init__()
        self.label = label
        self.locator = None
        self.lines: Lines = {}
        self.columns: dict[tuple, int] = {}
        # the open elements: (path, body, text chunks, line where text starts)
        self.stack: list[tuple[tuple, dict, list[str], list[int]]] = []
        self.root: dict | None = None

    def setDocumentLocator(self, locator) -> None:
        self.locator = locator

    def position(self) -> tuple[int, int]:
        if self.locator is None:
            return 1, 1
        return self.locator.getLineNumber() or 1, (self.locator.getColumnNumber() or 0) + 1

    def startElement(self, name: str, attrs) -> None:
        line, column = self.position()
        for key in attrs.getNames():
            if key in SYNTHETIC_KEYS:
                raise XmlLaunchError(
                    f"{self.label}:{line}:{column}: <{name}> has an attribute "
                    f"{key!r}, which no roslaunch element has"
                )
        body: dict[str, Any] = {key: attrs.getValue(key) for key in attrs.getNames()}
        if not self.stack:
            if name != "launch":
                raise XmlLaunchError(
                    f"{self.label}:{line}:{column}: the root element must be <launch>, got <{name}>"
                )
            path: tuple = ("launch",)
            self.root = body
        else:
            parent_path, parent, _, _ = self.stack[-1]
            children = parent.setdefault("children", [])
            path = (
                parent_path + ("children", len(children), name)
                if len(parent_path) > 1
                else ("launch", len(children), name)
            )
            children.append({name: body})
        self.lines[path] = line
        self.columns[path] = column
        for key in body:
            self.lines[path + (key,)] = line
            self.columns[path + (key,)] = column
        self.stack.append((path, body, [], []))

    def characters(self, content: str) -> None:
        _, _, chunks, start = self.stack[-1]
        if not start:
            start.append(self.position()[0])
        chunks.append(content)

    def endElement(self, name: str) -> None:
        path, body, chunks, start = self.stack.pop()
        text = "".join(chunks)
        if text.strip():
            body["text"] = "\n" * (start[0] - 1) + text
            self.lines[path + ("text",)] = start[0]


def read_xml_launch(path: Path) -> tuple[dict, Lines, dict[tuple, int]]:
    """``({"launch": [elements]}, lines, columns)`` of a roslaunch XML file."""
    label = display_path(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise XmlLaunchError(f"{label}: cannot read: {exc.strerror}") from None
    handler = _Handler(label)
    try:
        defusedxml.sax.parseString(
            data, handler, forbid_dtd=False, forbid_entities=True, forbid_external=True
        )
    except xml.sax.SAXParseException as exc:
        raise XmlLaunchError(
            f"{label}:{exc.getLineNumber()}:{(exc.getColumnNumber() or 0) + 1}: malformed XML: {exc.getMessage()}"
        ) from None
    except defusedxml.EntitiesForbidden as exc:
        line, column = handler.position()
        raise XmlLaunchError(
            f"{label}:{line}:{column}: XML entity declaration "
            f"{exc.name!r} refused: entities can expand without bound "
            f'("billion laughs") or read other files'
        ) from None
    except (defusedxml.ExternalReferenceForbidden, defusedxml.DTDForbidden) as exc:
        line, column = handler.position()
        raise XmlLaunchError(
            f"{label}:{line}:{column}: external XML reference refused "
            f"({exc}): a launch file cannot pull in other files or URLs "
            f"through its DTD"
        ) from None
    root = handler.root if handler.root is not None else {}
    elements = root.pop("children", [])
    if "text" in root:
        root.pop("text")
    # the <launch> element's own attributes (deprecated=...) travel beside its elements
    return {"launch": elements, "launch_attributes": root}, handler.lines, handler.columns
