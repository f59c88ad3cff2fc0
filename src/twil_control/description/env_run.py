"""env_run-style wrappers in front of xacro, read without a shell.

Clearpath's description packages build robot_description as ``.../scripts/env_run CONFIG_FILE
$(find xacro)/xacro FILE ...``, a bash script that exports a file of KEY=VALUE lines and runs the
rest. Here the script is read, not run: it is accepted only when it does exactly that, the file's
lines are parsed as assignments, and the command must be xacro's, which then runs with those
variables. Anything else is refused, naming file and line (docs/ros1.md).
"""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

from .xacro_command import XacroError

_ASSIGN = re.compile(r"^(?:export\s+)?([A-Za-z_][A-Za-z0-9_]*)=(.*)$")
_VAR = re.compile(r"\$(?:\{([A-Za-z_][A-Za-z0-9_]*)\}|([A-Za-z_][A-Za-z0-9_]*))")


def _statements(text: str) -> list[str]:
    lines = []
    for raw in text.splitlines():
        line = raw.strip()
        if line and not line.startswith("#"):
            lines.extend(part.strip() for part in line.split(";") if part.strip())
    return lines


def is_env_run_script(path: Path) -> bool:
    """Whether `path` is a shell script that sources its first argument and runs the rest."""
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return False
    if not text.startswith("#!") or not re.match(r"#!\s*\S*(bash|sh)\b", text.splitlines()[0]):
        return False
    lines = _statements(text)
    if len(lines) != 5:
        return False
    first = re.fullmatch(r'([A-Za-z_][A-Za-z0-9_]*)=("?)\$1\2', lines[0])
    if not first:
        return False
    name = first.group(1)
    sourced = re.fullmatch(r'(?:source|\.)\s+("?)\$(\{?)' + name + r"\}?\1", lines[3])
    return (
        re.fullmatch(r"shift(\s+1)?", lines[1]) is not None
        and lines[2] == "set -a"
        and sourced is not None
        and re.fullmatch(r'(exec\s+)?("?)\$(@|\{@\})\2', lines[4]) is not None
    )


def read_env_file(path: Path) -> dict[str, str]:
    """The variables a KEY=VALUE file sets, as bash's `set -a; source FILE` would export them."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise XacroError(f"env_run: cannot read its configuration file {path}: {exc.strerror}") from None
    env: dict[str, str] = {}
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        match = _ASSIGN.match(line)
        bad = "`" in line or "$(" in line
        if not match or bad:
            raise XacroError(
                f"{path}:{number}: {line!r} is not a KEY=VALUE assignment; an env_run configuration is "
                f"read without a shell, so it may hold only assignments, comments and blank lines"
            )
        try:
            words = shlex.split(match.group(2), comments=True)
        except ValueError as exc:
            raise XacroError(f"{path}:{number}: {line!r}: {exc}") from None
        if len(words) > 1:
            raise XacroError(f"{path}:{number}: {line!r}: a value with spaces must be quoted")
        value = words[0] if words else ""
        if "'" not in match.group(2):  # single quotes keep $ literal, as in bash
            value = _VAR.sub(lambda m: env.get(m[1] or m[2], os.environ.get(m[1] or m[2], "")), value)
        env[match.group(1)] = value
    return env


def split_env_run(words: list[str]) -> tuple[dict[str, str], list[str]] | None:
    """(environment, xacro command) of ``env_run CONFIG xacro ...``, or None when the first word
    is not an env_run script."""
    if len(words) < 3 or not is_env_run_script(Path(words[0])):
        return None
    return read_env_file(Path(words[1])), words[2:]
