"""Ctrl-C while numba compiles (launch/interrupt.py): llvmlite calls Python back through ctypes
while it compiles, and an exception raised there is printed as "Exception ignored on calling
ctypes callback function" with a traceback, and lost. The start-up handler waits until the JIT
work is left, then stops the launch. Deterministic: the SIGINT is raised from inside llvmlite's
object-cache callback itself (numba's hook there is wrapped to raise it)."""

from __future__ import annotations

import subprocess
import sys

SCRIPT = """
import signal, time
from twil_control.launch.interrupt import StopSignal, on_stop_while_starting
signal.signal(signal.SIGINT, on_stop_while_starting)
import numpy as np
from numba import njit
from numba.core.registry import cpu_target

engine = cpu_target.target_context.codegen()._engine._ee  # llvmlite's ExecutionEngine
hook, raised = engine._object_cache_notify, []


def raising_inside_the_callback(module, buf):  # called by llvmlite from C, through ctypes
    if not raised:
        raised.append(1)
        signal.raise_signal(signal.SIGINT)  # its handler runs here, inside the callback
    return hook(module, buf)


engine._object_cache_notify = raising_inside_the_callback


@njit(cache=False)
def twice(a):
    return a.sum() * 2.0


try:
    twice(np.ones(3))
    end = time.monotonic() + 10
    while time.monotonic() < end:  # a deferred signal comes back within RETRY seconds
        time.sleep(0.01)
    print("not stopped", len(raised))
except StopSignal:
    print("stopped", len(raised))
"""


def test_ctrl_c_inside_the_jits_callback_stops_the_launch_after_it_without_output(tmp_path):
    script = tmp_path / "jit_interrupt.py"  # a file: code run by exec ("<string>") defers anyway
    script.write_text(SCRIPT)
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert proc.stdout.strip() == "stopped 1", (proc.stdout, proc.stderr)
    assert "Exception ignored" not in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
