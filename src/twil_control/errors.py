"""The base of the errors this project raises on purpose.

A `TwilControlError` is a problem the user can act on: a file, parameter or value that is not
allowed, a resource that is missing. The command-line tools print it as one line and exit with
its code; any other exception is a bug and prints its traceback (docs/failures.md)."""

from __future__ import annotations


class TwilControlError(Exception):
    """Bad input or an unusable environment, said in one line that names what and what is allowed."""
