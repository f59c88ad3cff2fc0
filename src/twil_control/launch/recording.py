"""What a launch records: YAML's ``record`` element, or a ``rosbag record`` node (XML's way),
whose command line is read for its topics (``-a``: every topic) and its ``-O NAME`` or ``-o
PREFIX``, which name the run's bag itself (there is one recording: --bag on the command line
wins over them); the compression options are ignored with a warning."""

from __future__ import annotations

import logging
from typing import Any

from twil_control.bag.recorder import FORMATS as RECORD_FORMATS
from twil_control.bag.recorder import MCAP_COMPRESSIONS
from twil_control.core import names
from twil_control.launch.plan import RecordOutput
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
        self.record_output: RecordOutput | None = None

    def record_node(self, scope: Scope, body: dict, path: tuple, ns: str) -> None:
        """``rosbag record``: what the launch records, and the bag's name (-O/-o)."""
        args = self.node_args(scope, body.get("args"), path + ("args",))
        topics, ignored, refused, output = _rosbag_record_args(args)
        if refused:
            self.fail(
                scope,
                path + ("args",),
                f"rosbag record {refused}; supported: topic names, -a/--all, -O NAME, -o PREFIX "
                f"(and --lz4/--bz2/-j, which are ignored)",
            )
        if ignored:
            log.warning(
                "%s: rosbag record %s ignored: the bag's chunks are LZ4-compressed (docs/bags.md)",
                self.where(scope, path),
                " ".join(ignored),
            )
        if output is not None:
            self.set_output(scope, path, output)
        if topics is None:
            self.record_all = True
            return
        self.add_record(scope, [(topic, path + ("args",)) for topic in topics], ns)

    def set_output(self, scope: Scope, path: tuple, given: tuple[str, bool]) -> None:
        name, prefix = given
        output = RecordOutput(name, prefix, self.where(scope, path))
        if not name:
            self.fail(scope, path + ("args",), f"rosbag record {output.option.strip()}: the bag needs a name")
        first = self.record_output
        if first is not None and (first.name, first.prefix) != (name, prefix):
            self.fail(
                scope,
                path + ("args",),
                f"rosbag record {output.option} names another bag than {first.option} at "
                f"{first.source}; a launch records one bag",
            )
        self.record_output = first or output

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


#: rosbag record's compression options, ignored (a bag's chunks are LZ4-compressed)
_RECORD_IGNORED = ("--lz4", "--bz2", "-j")
#: rosbag record's options naming the bag: -O/--output-name NAME, -o/--output-prefix PREFIX
_RECORD_OUTPUT = {"-O": False, "--output-name": False, "-o": True, "--output-prefix": True}


def _rosbag_record_args(
    args: list[str],
) -> tuple[list[str] | None, list[str], str | None, tuple[str, bool] | None]:
    """(topics, or None for -a; options ignored; what is refused, or None; (name, is a prefix)
    of -O/-o, or None) of rosbag record's command line."""
    topics: list[str] = []
    ignored: list[str] = []
    output: tuple[str, bool] | None = None
    record_all = False
    tokens = iter(args)
    for token in tokens:
        option, eq, inline = token.partition("=")
        if token in ("-a", "--all"):
            record_all = True
        elif token in _RECORD_IGNORED:
            ignored.append(token)
        elif option in _RECORD_OUTPUT:
            value = inline if eq else next(tokens, None)
            if value is None:
                return topics, ignored, f"{option} needs a value", output
            if output is not None:
                return topics, ignored, 'takes one of -O and -o, once (rosbag: "Can\'t set both")', output
            output = (value, _RECORD_OUTPUT[option])
        elif token.startswith("-"):
            return topics, ignored, f"option {token!r} is not supported", output
        else:
            topics.append(token)
    return (None if record_all else topics), ignored, None, output
