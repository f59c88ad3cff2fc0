"""Safe YAML loading that remembers where every key came from.

A ``yaml.SafeLoader`` subclass only, so a Python tag is an error, never a call. A duplicate key is
an error and every key's line is kept, so callers can say ``config/x.yaml:12: ...``. Aliases may
add at most `MAX_ALIAS_EXPANSION` nodes once expanded (everything here walks every copy, so a few
hundred bytes of nested aliases would stand for billions of values) and nesting is at most
`MAX_DEPTH` deep (docs/inputs.md). rosparam's ``!degrees`` and ``!radians`` take numbers only:
rosparam evaluates expressions there, which a safe loader must not.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import yaml
import yaml.composer
import yaml.constructor

from twil_control import PACKAGE_ROOT
from twil_control.errors import TwilControlError

#: A key path from the document root (mapping keys as str, list indices as int) -> line.
Lines = dict[tuple[str | int, ...], int]

_MERGE_TAG = "tag:yaml.org,2002:merge"

#: Nodes that aliases may add to a document, counted as if every alias were a copy.
MAX_ALIAS_EXPANSION = 100_000

#: How deep mappings and lists may nest (PyYAML composes recursively; configuration files
#: nest a handful of levels).
MAX_DEPTH = 100


class YamlError(TwilControlError, ValueError):
    """A YAML file that cannot be read, parsed, or that breaks the checks above."""


class _Checks:
    """Notes where each alias is used (the composer keeps only the anchored node) and how deep
    nodes nest: the composer's hook, shared by both loaders below."""

    alias_uses: list
    _depth: int
    check_event: Any  # the parser's, in the loaders this is mixed into
    peek_event: Any

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            node = super().compose_node(parent, index)  # pyright: ignore[reportAttributeAccessIssue]
            self.alias_uses.append((event.start_mark.line + 1, event.anchor, node))
            return node
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise yaml.composer.ComposerError(
                    None,
                    None,
                    f"mappings and lists nest more than {MAX_DEPTH} levels deep",
                    self.peek_event().start_mark,
                )
            return super().compose_node(parent, index)  # pyright: ignore[reportAttributeAccessIssue]
        finally:
            self._depth -= 1


class _SafeLoader(_Checks, yaml.SafeLoader):
    """SafeLoader plus rosparam's angle tags and the checks; nothing that can run code. Pure
    Python: it gives PyYAML's error messages."""

    def __init__(self, stream) -> None:
        super().__init__(stream)
        self.alias_uses: list[tuple[int, str, yaml.Node]] = []  # (line, anchor, node)
        self._depth = 0


try:  # libyaml's scanner and parser, when PyYAML was built with it
    from yaml.cyaml import CParser as _CParser  # pyright: ignore[reportAttributeAccessIssue]
except ImportError:
    _CParser = None


if _CParser is not None:

    class _FastLoader(
        _Checks, yaml.composer.Composer, _CParser, yaml.constructor.SafeConstructor, yaml.resolver.Resolver
    ):
        """The same loader with libyaml's scanner and parser (much faster on a large parameter
        file) under PyYAML's composer, so the checks and the lines are the same."""

        def __init__(self, stream) -> None:
            _CParser.__init__(self, stream)  # pyright: ignore[reportCallIssue]
            yaml.composer.Composer.__init__(self)
            yaml.constructor.SafeConstructor.__init__(self)
            yaml.resolver.Resolver.__init__(self)
            self.alias_uses = []
            self._depth = 0


def _angle(to_radians: bool):
    def construct(loader: yaml.SafeLoader, node: yaml.ScalarNode) -> float:
        text = loader.construct_scalar(node)
        try:
            number = float(text)
        except ValueError:
            raise yaml.constructor.ConstructorError(
                None, None, f"{node.tag} needs a plain number, got {text!r}", node.start_mark
            ) from None
        return math.radians(number) if to_radians else number

    return construct


for _loader in (_SafeLoader, _FastLoader) if _CParser is not None else (_SafeLoader,):
    _loader.add_constructor("!degrees", _angle(to_radians=True))
    _loader.add_constructor("!radians", _angle(to_radians=False))


def display_path(path: str | Path) -> str:
    """How files are named in messages: relative to the package root when inside it."""
    resolved = Path(path).absolute()
    try:
        return resolved.relative_to(PACKAGE_ROOT).as_posix()
    except ValueError:
        return str(resolved)


def load_yaml(path: str | Path) -> Any:
    """Load one YAML document from ``path`` safely (None for an empty file)."""
    return load_yaml_with_lines(path)[0]


def load_yaml_with_lines(path: str | Path) -> tuple[Any, Lines]:
    """Load ``path`` safely; also return the line of every key and list item."""
    return parse_yaml(read_text(path), display_path(path))


def read_text(path: str | Path) -> str:
    """Read a UTF-8 text file, with errors that name it."""
    name = display_path(path)
    try:
        return Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise YamlError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise YamlError(f"{name}: is a directory, not a file") from None
    except UnicodeDecodeError as exc:
        raise YamlError(f"{name}: not UTF-8 text ({exc.reason} at byte {exc.start})") from None


def parse_yaml(text: str, name: str = "<string>") -> tuple[Any, Lines]:
    """Parse one YAML document from ``text``; ``name`` is the file name for messages."""
    if _CParser is not None:
        try:
            return _parse(_FastLoader(text), name)
        except YamlError:
            pass  # parsed again by PyYAML's own parser, whose messages the errors quote
    return _parse(_SafeLoader(text), name)


def _parse(loader, name: str) -> tuple[Any, Lines]:
    try:
        root = loader.get_single_node()
        if root is None:
            return None, {}
        _check_aliases(root, loader.alias_uses, name)
        lines: Lines = {(): root.start_mark.line + 1}
        _index(root, (), lines, name, set())
        return loader.construct_document(root), lines
    except yaml.MarkedYAMLError as exc:
        raise YamlError(_describe(name, exc)) from None
    except yaml.YAMLError as exc:  # errors without a position (e.g. bad characters)
        raise YamlError(f"{name}: YAML error: {exc}") from None
    finally:
        loader.dispose()


def _check_aliases(root: yaml.Node, uses: list[tuple[int, str, yaml.Node | None]], name: str) -> None:
    """Refuse recursive aliases, and aliases that expand the document by more than
    MAX_ALIAS_EXPANSION nodes (sizes counted once per node, so this costs the file's size)."""
    if not uses:
        return
    sizes: dict[int, int] = {}
    active: set[int] = set()

    def size(node: yaml.Node) -> int:
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in active:
            raise _Recursive(node)
        active.add(key)
        total = 1
        if isinstance(node, yaml.MappingNode):
            total += sum(size(k) + size(v) for k, v in node.value)
        elif isinstance(node, yaml.SequenceNode):
            total += sum(size(item) for item in node.value)
        active.discard(key)
        sizes[key] = total
        return total

    try:
        expanded = size(root)
    except _Recursive as exc:
        line, anchor = next((line, anchor) for line, anchor, node in uses if node is exc.node)
        raise YamlError(
            f"{name}:{line}: alias *{anchor} refers to a mapping or list that "
            f"contains it (a recursive alias): no parameter can hold that"
        ) from None
    if expanded - len(sizes) > MAX_ALIAS_EXPANSION:
        line, anchor, node = max(uses, key=lambda use: sizes[id(use[2])])
        raise YamlError(
            f"{name}:{line}: aliases expand this document from {len(sizes):,} to {expanded:,} "
            f"nodes (alias *{anchor} alone stands for {sizes[id(node)]:,}); at most "
            f"{MAX_ALIAS_EXPANSION:,} added nodes are allowed, since every copy is stored and "
            f"walked"
        )


class _Recursive(Exception):
    def __init__(self, node: yaml.Node) -> None:
        super().__init__()
        self.node = node


def _index(node: yaml.Node, path: tuple, lines: Lines, name: str, active: set[int]) -> None:
    """Record the line of each key/item below ``node``; refuse duplicate keys."""
    if id(node) in active:  # a recursive alias; its lines are already recorded
        return
    active.add(id(node))
    if isinstance(node, yaml.MappingNode):
        first_line: dict[tuple[str, str], int] = {}
        for key_node, value_node in node.value:
            if key_node.tag == _MERGE_TAG:  # '<<: *anchor': merged keys may be overridden
                continue
            line = key_node.start_mark.line + 1
            if isinstance(key_node, yaml.ScalarNode):
                ident = (key_node.tag, key_node.value)
                if ident in first_line:
                    raise YamlError(
                        f"{name}:{line}: duplicate key {key_node.value!r} (first defined at "
                        f"line {first_line[ident]}); YAML would silently keep only the last one"
                    )
                first_line[ident] = line
                child = path + (key_node.value,)
                lines[child] = line
                _index(value_node, child, lines, name, active)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            child = path + (i,)
            lines[child] = item.start_mark.line + 1
            _index(item, child, lines, name, active)
    active.discard(id(node))


def _describe(name: str, exc: yaml.MarkedYAMLError) -> str:
    mark = exc.problem_mark or exc.context_mark
    where = f"{name}:{mark.line + 1}:{mark.column + 1}" if mark else name
    problem = exc.problem or "invalid YAML"
    unknown_tag = re.search(r"could not determine a constructor for the tag '([^']*)'", problem)
    if unknown_tag:
        tag = unknown_tag.group(1).replace("tag:yaml.org,2002:", "!!")
        return (
            f"{where}: YAML tag {tag!r} is not allowed: files are loaded with a safe "
            f"loader that builds plain data only (mappings, lists, strings, numbers, "
            f"booleans)"
        )
    if isinstance(exc, (yaml.constructor.ConstructorError, yaml.composer.ComposerError)):
        return f"{where}: YAML error: {problem}"
    if exc.context and exc.context.startswith("expected"):  # "expected X, but found Y"
        problem = f"{exc.context}, {problem}"
    elif exc.context:
        problem = f"{problem} ({exc.context})"
    return f"{where}: YAML syntax error: {problem}"
