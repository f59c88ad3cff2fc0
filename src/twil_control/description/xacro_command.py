"""xacro, run in this process (the ``xacro`` package) instead of as roslaunch's subprocess.

roslaunch sets ``<param name="robot_description" command="$(find xacro)/xacro FILE a:=1"/>``
to the output of that command. xacro_argv recognises such a command (``xacro``, ``xacro.py``,
``rosrun xacro xacro``, with or without ``--inorder``), and run_xacro turns its arguments into
the URDF text, with the same options and ``name:=value`` mappings as the xacro program.
"""
from __future__ import annotations

import shlex
from pathlib import Path

_PROGRAMS = ("xacro", "xacro.py")


class XacroError(ValueError):
    """A xacro run that failed; the message names the file and xacro's reason."""


def xacro_argv(command: str) -> list[str] | None:
    """The arguments after the program if ``command`` runs xacro, else None.

    ValueError if the command cannot be split like a shell would.
    """
    tokens = shlex.split(command)
    if len(tokens) >= 3 and tokens[0] == "rosrun" and tokens[1] == "xacro":
        tokens = tokens[2:]
    if not tokens or Path(tokens[0]).name not in _PROGRAMS:
        return None
    return tokens[1:]


def run_xacro(argv: list[str]) -> str:
    """The XML text xacro prints for command-line arguments ``argv`` (the program excluded)."""
    import xacro
    from xacro import cli

    # in-order processing is xacro's only mode since Melodic; the flag would only print so
    argv = [arg for arg in argv if arg not in ("--inorder", "-i")]
    try:
        options, input_file = cli.process_args(argv)
    except SystemExit:  # optparse's way of saying the arguments are wrong
        raise XacroError(f"xacro {' '.join(argv)}: bad arguments; expected "
                         f"[--inorder] FILE [name:=value ...]") from None
    if options.just_deps or options.output:
        raise XacroError(f"xacro {' '.join(argv)}: --deps and -o are not supported here: the "
                         f"output is the parameter's value")
    if not Path(input_file).is_file():
        raise XacroError(f"xacro: input file not found: {input_file}")
    try:
        document = xacro.process_file(input_file, mappings=options.mappings,
                                      in_order=True, verbosity=0)
    except Exception as exc:  # xacro raises XacroException, XML and substitution errors
        raise XacroError(f"xacro {input_file}: {exc}") from None
    return document.toprettyxml(indent="  ")
