"""``$(find xacro)/xacro FILE name:=value ...`` run in-process with the registry's ``xacro``
package (no shell, no subprocess), for roslaunch's ``<param command="...">``.

Accepted as ROS 1 users write it: the ``xacro`` and older ``xacro.py`` executables (a leading
executable path is dropped), ``--inorder``/``-i`` (in-order processing is xacro's only mode
since ROS Melodic; accepted and ignored), ``name:=value`` args. Any other option is refused,
naming it.
"""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["XacroError", "is_xacro_executable", "run_xacro"]

_EXECUTABLES = ("xacro", "xacro.py")
_IGNORED = ("--inorder", "-i")


class XacroError(ValueError):
    """A xacro command or file that cannot be processed (the message names the file)."""


def is_xacro_executable(word: str) -> bool:
    """Whether a command's first word is xacro (``$(find xacro)/xacro``, ``xacro.py``, ...)."""
    return os.path.basename(word) in _EXECUTABLES


def run_xacro(argv: list[str]) -> str:
    """The URDF text xacro makes of ``argv`` (xacro's command line, the executable optional)."""
    import xacro

    words = list(argv)
    if words and is_xacro_executable(words[0]):
        words.pop(0)
    mappings: dict[str, str] = {}
    inputs: list[str] = []
    for word in words:
        name, sep, value = word.partition(":=")
        if sep:
            mappings[name] = value
        elif word in _IGNORED:
            continue
        elif word.startswith("-"):
            raise XacroError(f"xacro option {word!r} is not supported; use: xacro FILE "
                             f"[name:=value ...] [--inorder]")
        else:
            inputs.append(word)
    if len(inputs) != 1:
        raise XacroError(f"xacro needs exactly one input file, got {inputs or 'none'} "
                         f"(arguments: {' '.join(words)})")
    source = Path(inputs[0]).expanduser()
    if not source.is_file():
        raise XacroError(f"xacro input file not found: {source}")
    try:
        doc = xacro.process_file(str(source), mappings=mappings, verbosity=0)
    except Exception as exc:  # xacro's own exceptions and the XML parser's
        raise XacroError(f"xacro {source}: {type(exc).__name__}: {exc}") from None
    return doc.toprettyxml(indent="  ")
