"""What a launch records: YAML's ``record`` element, or a ``rosbag record`` node (XML's way),
whose command line is read for its topics; the bag itself is the one --bag names."""

from __future__ import annotations

import logging
from typing import Any

from twil_control.bag.recorder import FORMATS as RECORD_FORMATS
from twil_control.bag.recorder import MCAP_COMPRESSIONS
from twil_control.core import names
from twil_control.launch.scope import Scope, kind
from twil_control.launch.scoping import ScopedLoader

log = logging.getLogger("twil_control.launch")


class RecordElements(ScopedLoader):
    """The recorded topics (None: every topic), and the bag's format and compression."""

    def __init__(self) -> None:
        super().__init__()
        self.record: list[str] | None = None
        self.record_all = False
        self.record_format: str | None = None
        self.record_compression: str | None = None

    def record_node(self, scope: Scope, body: dict, path: tuple, ns: str) -> None:
        """``rosbag record``: what the launch records (the bag itself is --bag's)."""
        args = self.node_args(scope, body.get("args"), path + ("args",))
        topics, ignored, refused = _rosbag_record_args(args)
        if refused:
            self.fail(
                scope,
                path + ("args",),
                f"rosbag record option {refused!r} is not "
                f"supported; supported: topic names, -a/--all "
                f"(and -O/-o/--lz4/--bz2/-j, which are ignored)",
            )
        if ignored:
            log.warning(
                "%s: rosbag record %s ignored: the bag is the one --bag names",
                self.where(scope, path),
                " ".join(ignored),
            )
        if topics is None:
            self.record_all = True
            return
        self.add_record(scope, [(topic, path + ("args",)) for topic in topics], ns)

    def on_record(self, body: dict, path: tuple, scope: Scope) -> None:
        if "format" in body:
            self.record_format = self.choice(
                scope, body["format"], path + ("format",), "record format", RECORD_FORMATS
            )
        if "compression" in body:
            self.record_compression = self.choice(
                scope,
                body["compression"],
                path + ("compression",),
                "record compression (of MCAP chunks)",
                MCAP_COMPRESSIONS,
            )
        if "topics" not in body and ("format" in body or "compression" in body):
            return  # options only: every topic is recorded (or the topics other records name)
        topics = body.get("topics")
        if not isinstance(topics, list):
            self.fail(
                scope,
                path + ("topics",) if "topics" in body else path,
                f"record needs 'topics', a list of topic names, got {kind(topics)}",
            )
        self.add_record(
            scope,
            [
                (self.scalar(scope, raw, path + ("topics", i), "topic"), path + ("topics", i))
                for i, raw in enumerate(topics)
            ],
            scope.ns,
        )

    def choice(self, scope: Scope, value: Any, path: tuple, what: str, allowed: tuple) -> str:
        text = self.scalar(scope, value, path, what)
        if text not in allowed:
            self.fail(scope, path, f"{what} '{text}' is not one of {', '.join(allowed)}")
        return text

    def add_record(self, scope: Scope, topics: list[tuple[str, tuple]], ns: str) -> None:
        record = self.record if self.record is not None else []
        for topic, here in topics:
            try:
                resolved = names.resolve(topic, ns)
            except names.GraphNameError as exc:
                self.fail(scope, here, str(exc))
            if resolved not in record:
                record.append(resolved)
        self.record = record


#: rosbag record options: ignored (the bag is the launcher's) and taking a value.
_RECORD_IGNORED = {
    "-O": True,
    "-o": True,
    "--output-name": True,
    "--output-prefix": True,
    "--lz4": False,
    "--bz2": False,
    "-j": False,
}


def _rosbag_record_args(args: list[str]) -> tuple[list[str] | None, list[str], str | None]:
    """(topics, or None for -a; options ignored; the first unsupported option) of rosbag
    record's command line."""
    topics: list[str] = []
    ignored: list[str] = []
    record_all = False
    tokens = iter(args)
    for token in tokens:
        option, _, inline = token.partition("=")
        if token in ("-a", "--all"):
            record_all = True
        elif option in _RECORD_IGNORED:
            value = inline or (next(tokens, "") if _RECORD_IGNORED[option] and not inline else "")
            ignored.append(f"{option} {value}".strip())
        elif token.startswith("-"):
            return topics, ignored, token
        else:
            topics.append(token)
    return (None if record_all else topics), ignored, None
