"""The base of the errors this project raises on purpose, and how the command-line tools end on one.

A `TwilControlError` is a problem the user can act on: a file, parameter or value that is not
allowed, a resource that is missing. The command-line tools print it as one line and exit with
its `exit_code`; any other exception is a bug and prints its traceback, exit 1 (docs/failures.md).
"""

from __future__ import annotations

import sys
from collections.abc import Callable


class TwilControlError(Exception):
    """Bad input or an unusable environment, said in one line that names what and what is allowed."""

    #: the exit code of a command-line tool that stops on this error (2: bad input, nothing done)
    exit_code: int = 2

    def __str__(self) -> str:  # a KeyError or OSError base would print its repr or "[Errno ...]"
        return str(self.args[0]) if len(self.args) == 1 else super().__str__()


class InputError(TwilControlError, ValueError):
    """A value (an option, a parameter, a field of an input file) outside what is allowed."""


def exit_on_error(main: Callable[[], int], debug: bool = False) -> int:
    """Run a command's `main`: a TwilControlError becomes one ``error:`` line on stderr and its exit
    code (its traceback too with `debug`); any other exception propagates, so Python prints its
    traceback and exits 1."""
    try:
        return main()
    except TwilControlError as error:
        if debug:
            raise
        print(f"error: {error}", file=sys.stderr)
        return error.exit_code
