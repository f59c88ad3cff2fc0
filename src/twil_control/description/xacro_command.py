"""``$(find xacro)/xacro FILE name:=value ...`` run with the registry's ``xacro`` package (no
shell, no executable), its ``$(find pkg)`` answered by core.packages, in a child process under
core.limited's limits, so a file that would take the machine is one error naming it.

Accepted as ROS 1 users write it (``xacro`` and ``xacro.py``, ``--inorder``, ``name:=value``,
``-q``/``-v``); any other option is refused, naming it. An env_run wrapper adds its file's
variables to xacro's environment.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from twil_control.core import limited, packages
from twil_control.errors import TwilControlError

__all__ = ["XacroError", "is_xacro_executable", "run_xacro"]

_EXECUTABLES = ("xacro", "xacro.py")
_IGNORED = ("--inorder", "-i", "--xacro-ns")
_VERBOSITY = {"-q": 0, "-v": 2}


class XacroError(TwilControlError, ValueError):
    """A xacro command or file that cannot be processed (the message names the file)."""


def is_xacro_executable(word: str) -> bool:
    """Whether a command's first word is xacro (``$(find xacro)/xacro``, ``xacro.py``, ...)."""
    return os.path.basename(word) in _EXECUTABLES


@contextlib.contextmanager
def _find_through_packages():
    """xacro's ``$(find pkg)`` asks ament_index; here it asks core.packages, for the call."""
    from xacro import substitution_args

    def find(pkg: str) -> str:
        return str(packages.find(pkg))

    previous = substitution_args._eval_find
    substitution_args._eval_find = find
    try:
        yield
    finally:
        substitution_args._eval_find = previous


def run_xacro(argv: list[str], env: dict[str, str] | None = None) -> str:
    """The URDF text xacro makes of ``argv`` (xacro's command-line arguments), with `env` added
    to the environment it sees (its $(env) and $(optenv): an env_run file's variables)."""
    words = list(argv)
    if words and is_xacro_executable(words[0]):
        words.pop(0)
    mappings: dict[str, str] = {}
    inputs: list[str] = []
    verbosity = 1
    for word in words:
        name, sep, value = word.partition(":=")
        if sep:
            mappings[name] = value
        elif word in _IGNORED:
            continue
        elif word in _VERBOSITY:
            verbosity = _VERBOSITY[word]
        elif word.startswith("-"):
            raise XacroError(
                f"xacro option {word!r} is not supported; use: xacro FILE [name:=value ...] [--inorder]"
            )
        else:
            inputs.append(word)
    if len(inputs) != 1:
        raise XacroError(
            f"xacro needs exactly one input file, got {inputs or 'none'} (arguments: {' '.join(words)})"
        )
    source = Path(inputs[0]).expanduser()
    if not source.is_file():
        raise XacroError(f"xacro input file not found: {source}")
    extra = [str(p) for p in packages.extra_paths()]
    try:
        return limited.call(
            "twil_control.description.xacro_command:process",
            (str(source), mappings, verbosity, extra, dict(env or {})),
            f"xacro {source}",
        )
    except limited.LimitError as error:
        raise XacroLimitError(str(error)) from None


class XacroLimitError(XacroError, limited.LimitError):
    """xacro went past the child process's memory or time limit."""


def process(
    source_text: str, mappings: dict, verbosity: int, extra_paths: list[str], env: dict | None = None
) -> str:
    """The URDF text of one xacro file (run in the child process, whose environment `env`
    extends)."""
    import xacro

    source = Path(source_text)
    packages.set_extra_paths(extra_paths)
    os.environ.update(env or {})
    with _find_through_packages():
        try:
            doc = xacro.process_file(str(source), mappings=mappings, verbosity=verbosity)
        except packages.PackageNotFoundError as exc:
            raise XacroError(f"xacro {source}: {exc}") from None
        except MemoryError:
            raise
        except Exception as exc:  # xacro's own exceptions and the XML parser's
            if isinstance(getattr(exc, "exc", None), MemoryError):
                raise exc.exc from None
            where = " -> ".join(str(f) for f in (xacro.filestack or []) if f) or str(source)
            cause = getattr(exc, "exc", None)
            if isinstance(cause, packages.PackageNotFoundError):
                raise XacroError(f"xacro {source}: {cause} (in {where})") from None
            raise XacroError(f"xacro {source}: {type(exc).__name__}: {exc} (in {where})") from None
    return doc.toprettyxml(indent="  ")
