"""ros_control on the WAM: real-time factors and the controller manager's per-update cost.

In ONE process, one after the other, for the same simulated time:
1. the bare plant: wam_fixed in the default world, zero effort, no Python systems;
2. launch/wam_computed_torque.launch.yaml (1 kHz controller manager running
   joint_state_controller at 100 Hz and the computed-torque controller, a timed reference
   sequence, bag recording of every topic), with ControllerManagerSystem.cost_log on.
Prints both real-time factors, their ratio, and the median / p99 wall time of one
read -> controller_manager.update -> write cycle (targets: p99 < 100 us, launch >= 0.5 x bare),
the same cycles' thread CPU time (immune to other processes taking the core: on a shared
machine the wall-time p99 shows the OS scheduler's time slices), the machine's load, and the
cost of the control model's Drake calls alone.

Note: with zero effort the bare arm falls and its links hit the floor and each other, so the
"bare" plant pays for contact the controlled arm never makes; the ratio can exceed 1.

    .venv/bin/python bench/ros_control_bench.py [--duration 5]
"""
from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from twil_control import PACKAGE_ROOT
from twil_control.bag.recorder import BagRecorder
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import SLICE, Launch
from _common import bare_plant_rtf

LAUNCH = PACKAGE_ROOT / "launch/wam_computed_torque.launch.yaml"
WORLD = PACKAGE_ROOT / "sim/worlds/default.sdf"


def _cpu_time_probe(hw) -> list[float]:
    """Per-cycle thread CPU seconds of read -> update -> write, measured by wrapping the
    RobotHW's read_state and write: unlike the wall time of cost_log it excludes the time the
    OS gives other processes (this machine's 2 cores are shared)."""
    cpu: list[float] = []
    read_state, write, start = hw.read_state, hw.write, [0.0]

    def timed_read(x):
        start[0] = time.thread_time()
        read_state(x)

    def timed_write(t, period):
        write(t, period)
        cpu.append(time.thread_time() - start[0])

    hw.read_state, hw.write = timed_read, timed_write
    return cpu


def launch_rtf(duration: float) -> tuple[float, np.ndarray, np.ndarray, int, float]:
    """(RTF, per-update wall seconds, per-update CPU seconds, messages recorded,
    control-model seconds per call)."""
    launch = Launch(load_launch(LAUNCH, {}))
    launch.build()
    launch.start()
    hw_node = next(n for n in launch.nodes if getattr(n, "system", None) is not None)
    hw_node.system.cost_log = []
    cpu = _cpu_time_probe(hw_node.hw)
    with tempfile.TemporaryDirectory() as tmp:
        recorder = BagRecorder(Path(tmp) / "bench.bag", launch.master.bus, launch.plan.record_topics)
        try:
            start = time.perf_counter()
            t = 0.0
            while t < duration - 1e-12:  # the runner's slices
                t = min(t + SLICE, duration)
                launch.simulator.AdvanceTo(t)
                launch.master.clock.set(t)
                recorder.flush()
            wall = time.perf_counter() - start
            controller = hw_node.manager.get_controller("computed_torque_controller")
            model_cost = controller.model.measure_cost()
        finally:
            launch.shutdown()
            recorder.close()
    return duration / wall, np.array(hw_node.system.cost_log), np.array(cpu), recorder.count, model_cost


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per run")
    args = parser.parse_args()
    bare = bare_plant_rtf("wam_fixed", "wam", args.duration)
    full, cost, cpu, messages, model_cost = launch_rtf(args.duration)
    us, cpu_us = cost * 1e6, cpu * 1e6
    median, p99 = np.median(us), np.percentile(us, 99)
    print(f"ros_control bench (WAM, computed torque), {args.duration:g} s simulated each")
    print(f"  bare plant (wam_fixed, world, zero effort):      {bare:7.2f}x real time")
    print(f"  wam_computed_torque launch (recording {messages} msgs): {full:7.2f}x real time")
    print(f"  ratio launch / bare plant:                       {full / bare:7.3f}   (target >= 0.5)")
    print(f"  controller manager update ({len(us)} cycles): median {median:6.1f} us, p99 {p99:6.1f} us, "
          f"max {us.max():7.1f} us   (target p99 < 100 us)")
    print(f"  same cycles, thread CPU time:                     median {np.median(cpu_us):6.1f} us, "
          f"p99 {np.percentile(cpu_us, 99):6.1f} us, max {cpu_us.max():7.1f} us")
    print(f"  load average during the run: {' '.join(f'{v:.2f}' for v in os.getloadavg())} on {os.cpu_count()} cores")
    print(f"  of which control model M, C qd, tau_g (Drake):   {model_cost * 1e6:6.1f} us per call (median)")


if __name__ == "__main__":
    main()
