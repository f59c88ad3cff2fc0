"""Test node types that end a run from inside at an exact simulated time, and the launch CLI
run in a child process with them registered (``python tests/support/stop_nodes.py LAUNCH ARGS...``
runs ``python -m twil_control.launch LAUNCH ARGS...``).

A node acting at a simulated time makes a signal or a file's appearance land at the same point
of every run, where a signal sent from outside after a wall-clock delay would not.
"""

from __future__ import annotations

import argparse
import os
import runpy
import signal
import sys
from pathlib import Path

from twil_control.core.ros_node import RosNode
from twil_control.launch import node_types as registry

TYPES = {
    "test_pkg/self_signal": "support.stop_nodes:SelfSignal",
    "test_pkg/file_maker": "support.stop_nodes:FileMaker",
}


class _AtTime(RosNode):
    """args "--at T ...": act() once, at simulated time T (checked at 100 Hz)."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        p = argparse.ArgumentParser()
        p.add_argument("--at", type=float, required=True)
        self.add_args(p)
        self.opts = self.parse_args(p)
        self.create_timer(0.01, self.tick)

    def tick(self, event):
        if event.current_expected >= self.opts.at - 1e-9:
            self.opts.at = float("inf")
            self.act()


class SelfSignal(_AtTime):
    """args "--at T --signal NAME": the process sends itself the signal (SIGKILL: a hard kill at
    exactly T)."""

    def add_args(self, p):
        p.add_argument("--signal", required=True)

    def act(self):
        os.kill(os.getpid(), signal.Signals[self.opts.signal])


class FileMaker(_AtTime):
    """args "--at T --path P": a file P appears, holding 'precious'."""

    def add_args(self, p):
        p.add_argument("--path", required=True)

    def act(self):
        Path(self.opts.path).write_text("precious")


def register(monkeypatch=None) -> None:
    for key, target in TYPES.items():
        if monkeypatch is not None:
            monkeypatch.setitem(registry.BUILTIN, key, target)
        else:
            registry.BUILTIN[key] = target


def child_command(*args: str) -> list[str]:
    """The command line running the launch CLI with these node types known."""
    return [sys.executable, str(Path(__file__).resolve()), *args]


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: support.stop_nodes
    register()
    sys.argv = ["python -m twil_control.launch", *sys.argv[1:]]
    runpy.run_module("twil_control.launch", run_name="__main__", alter_sys=True)
