"""Console logging in rosconsole's shape: ``[LEVEL] [sim time]: message``, node name in front."""

from __future__ import annotations

import logging
import sys


class SimTimeStamp(logging.Filter):
    """Adds the simulated time of the running launch (if any) to each record."""

    def __init__(self) -> None:
        super().__init__()
        self._master = None

    def attach(self, master) -> None:
        self._master = master

    def filter(self, record: logging.LogRecord) -> bool:
        record.simtime = f"{self._master.clock.now():.3f}" if self._master is not None else "-"
        node = record.name.removeprefix("twil_control.node")
        record.origin = node.replace(".", "/") + ": " if record.name.startswith("twil_control.node") else ""
        return True


class CurrentStderrHandler(logging.StreamHandler):
    """Writes to whatever sys.stderr is when a record is emitted, not the stream of the moment it
    was made: a launch run in-process (tests, a notebook) may swap and close its stderr, and a
    later record must still go somewhere open."""

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, _value) -> None:
        pass


def configure_logging(debug: bool = False, quiet: bool = False) -> SimTimeStamp:
    stamp = SimTimeStamp()
    handler = CurrentStderrHandler()
    handler.addFilter(stamp)
    handler.setFormatter(logging.Formatter("[%(levelname)s] [%(simtime)s]: %(origin)s%(message)s"))
    root = logging.getLogger()
    root.handlers[:] = [handler]
    root.setLevel(logging.DEBUG if debug else logging.WARNING if quiet else logging.INFO)
    return stamp
