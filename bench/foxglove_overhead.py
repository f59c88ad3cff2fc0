"""What the Foxglove bridge costs the simulation: the qbot navigation launch (gmapping, move_base,
two goals there and back) run as fast as possible, recording its bag, without the bridge and with
the bridge and one client subscribed to every topic (the tests' protocol client, in this process,
receiving everything), alternately, `--repeats` times each; prints both real-time factors, their
ratio, the launch process's CPU seconds per simulated second (user + system, all its threads,
the bridge's server included: less sensitive than the wall time to a shared host) and how many
messages the client received, and writes its result to bench/results/.

    .venv/bin/python bench/foxglove_overhead.py --duration 10 --repeats 3
"""

from __future__ import annotations

import argparse
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

from _common import BenchResult, host_steal_seconds

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from support.foxglove_client import FoxgloveClient

SUMMARY = re.compile(r"simulated ([\d.]+) s in ([\d.]+) s.*with (\d+) messages")
PORT = re.compile(r"foxglove: serving ws://[\d.]+:(\d+)")


def launch(args: list[str], cwd: Path, client: bool) -> dict:
    """One run; with `client`, a client subscribes to every channel as soon as the server is up."""
    cpu0 = _children_cpu()
    proc = subprocess.Popen(
        [sys.executable, "-m", "twil_control.launch", *args],
        cwd=cwd,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
    )
    lines, fox = [], None
    for line in proc.stderr:
        lines.append(line)
        m = PORT.search(line)
        if client and m:
            fox = FoxgloveClient(f"ws://127.0.0.1:{m.group(1)}")
            fox.wait(lambda: "/tf" in fox.channels, what="the channels")
            with fox.lock:
                topics = sorted(fox.channels)
            fox.subscribe(topics)
            rest = threading.Thread(target=lambda: lines.extend(proc.stderr), daemon=True)
            rest.start()
            break
    proc.wait()
    cpu = _children_cpu() - cpu0
    if fox is not None:
        rest.join()
        fox.close()
    m = SUMMARY.search("".join(lines))
    if proc.returncode != 0 or not m:
        raise SystemExit(f"launch failed ({proc.returncode}):\n{''.join(lines)[-2000:]}")
    sim, wall, recorded = float(m.group(1)), float(m.group(2)), int(m.group(3))
    received = sum(len(v) for v in fox.messages.values()) if fox else 0
    return {
        "sim": sim,
        "wall": wall,
        "rtf": sim / wall,
        "cpu_per_sim_s": cpu / sim,
        "recorded": recorded,
        "received": received,
    }


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=10.0, help="simulated seconds per run")
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args()
    result = BenchResult(
        "foxglove_overhead",
        "the qbot navigation launch (gmapping, move_base, two goals there and "
        "back) as fast as possible with its bag, without the Foxglove bridge and with the bridge and "
        "one client subscribed to every topic, alternated",
    )
    runs = {"without": [], "with": []}
    steal0 = host_steal_seconds()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        base = [
            str(ROOT / "launch/qbot_navigation.launch.yaml"),
            "goal:=2 0 0; 0 0 3.14; 2 0 0; 0 0 3.14",
            "--duration",
            str(a.duration),
            "--realtime",
            "0",
        ]
        for k in range(a.repeats):
            off = launch(base + ["--bag", str(tmp / f"off{k}.bag")], tmp, client=False)
            on = launch(base + ["--bag", str(tmp / f"on{k}.bag"), "--foxglove", "0"], tmp, client=True)
            runs["without"].append(off)
            runs["with"].append(on)
            print(
                f"pair {k}: without the bridge {off['rtf']:.3f}x real time, {off['cpu_per_sim_s']:.3f} CPU s per "
                f"simulated s; with it and a client {on['rtf']:.3f}x, {on['cpu_per_sim_s']:.3f} CPU s (client "
                f"received {on['received']} of {on['recorded']} recorded messages); ratio {on['rtf'] / off['rtf']:.3f}",
                flush=True,
            )
    steal = host_steal_seconds() - steal0
    ratios = [w["rtf"] / o["rtf"] for o, w in zip(runs["without"], runs["with"])]
    rtf_off = statistics.median(r["rtf"] for r in runs["without"])
    rtf_on = statistics.median(r["rtf"] for r in runs["with"])
    cpu_off = statistics.median(r["cpu_per_sim_s"] for r in runs["without"])
    cpu_on = statistics.median(r["cpu_per_sim_s"] for r in runs["with"])
    print(
        f"median real-time factor: without {rtf_off:.3f}, with the bridge and a client {rtf_on:.3f}: "
        f"{100 * rtf_on / rtf_off:.1f}% kept (pair ratios {', '.join(f'{r:.3f}' for r in ratios)}; "
        f"host steal {steal:.1f} CPU s during the bench)"
    )
    print(
        f"median CPU seconds per simulated second: without {cpu_off:.3f}, with {cpu_on:.3f} "
        f"({100 * (cpu_on / cpu_off - 1):+.1f}%)"
    )
    result.add("simulated_s", a.duration, "s per run")
    result.add("pairs", a.repeats)
    result.add("rtf_without", rtf_off, "x real time (median)")
    result.add("rtf_with", rtf_on, "x real time (median)")
    result.add(
        "kept",
        rtf_on / rtf_off,
        "with / without, medians",
        target=">= 0.9",
        headline="navigation launch with Foxglove and a client / without",
    )
    result.add("median_pair_ratio", statistics.median(ratios), "with / without, per pair")
    result.add("pair_ratios", ", ".join(f"{r:.3f}" for r in ratios))
    result.add("cpu_per_sim_s_without", cpu_off, "CPU s per simulated s (median)")
    result.add("cpu_per_sim_s_with", cpu_on, "CPU s per simulated s (median)")
    result.records["runs"] = runs
    result.write()


if __name__ == "__main__":
    main()
