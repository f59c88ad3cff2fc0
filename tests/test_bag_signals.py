"""A signal during `bag convert` or `bag reindex` (bag/__main__.py): one line saying which signal
stopped which command and that the output was not made, exit 128 + the signal's number, and no
temporary left beside the output. Each signal is sent once the command's temporary folder exists
(so while it converts), and the command is given enough messages to still be converting then.
"""

from __future__ import annotations

import signal
import struct
import subprocess
import sys
import time

import pytest

from twil_control.bag.writer import ChunkedWriter
from twil_control.core import messages

MESSAGES = 100_000


@pytest.fixture(scope="module")
def big_bag(tmp_path_factory):
    path = tmp_path_factory.mktemp("signals") / "big.bag"
    w = ChunkedWriter(path, chunk_seconds=1.0)
    w.open()
    definition, md5 = messages.definition("std_msgs/Float64")
    conn = w.add_connection("/x", "std_msgs/msg/Float64", msgdef=definition, md5sum=md5)
    raw = struct.pack("<d", 0.5)
    for i in range(MESSAGES):
        w.write(conn, int(1e9 + i * 1e6), raw)
    w.close()
    return path


def _default_signals() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)  # a shell's background job would ignore SIGINT


@pytest.mark.parametrize(
    "command,signum",
    [
        ("convert", signal.SIGINT),
        ("convert", signal.SIGTERM),
        ("convert", signal.SIGHUP),
        ("reindex", signal.SIGINT),
        ("reindex", signal.SIGTERM),
    ],
)
def test_a_signal_stops_the_command_in_one_line_and_leaves_no_temporary(big_bag, tmp_path, command, signum):
    out = tmp_path / ("out.mcap" if command == "convert" else "out.bag")
    argv = [str(big_bag), str(out)] if command == "convert" else [str(big_bag), "-o", str(out)]
    proc = subprocess.Popen(
        [sys.executable, "-m", "twil_control.bag", command, *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_default_signals,
    )
    deadline = time.monotonic() + 120
    while not list(tmp_path.glob(f".{out.name}.*")):  # the command is writing
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.005)
    proc.send_signal(signum)
    stdout, stderr = proc.communicate(timeout=120)
    name = signal.Signals(signum).name
    assert proc.returncode == 128 + signum, (stdout, stderr)
    assert stderr == f"bag {command}: stopped by {name}; {out} was not made\n"
    assert list(tmp_path.iterdir()) == []
