"""Does the simulation keep real time with the view on? The qbot navigation launch with --view
(paced to real time), driving goals there and back, first with no browser, then with a headless
Chromium showing the page (Debian's chromium + chromium-driver, as the browser tests use: it
renders WebGL in software, on the same cores). Prints each run's real-time factor, the frames
the view sent and dropped, and the browser's CPU use.

    .venv/bin/python bench/view_rtf.py [--duration 30] [--rate 20]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from _common import BenchResult
from support.view_browser import LaunchProcess, chromium


def browser_cpu_seconds() -> int:
    """CPU seconds used so far by every chromium process (ps's cumulative time)."""
    out = subprocess.run(["ps", "-eo", "cputimes,args"], capture_output=True, text=True).stdout
    return sum(int(line.split(None, 1)[0]) for line in out.splitlines()[1:] if "chromium" in line)


def one_run(tmp: Path, duration: float, rate: float, browser: bool, result) -> str:
    goals = "; ".join(["2 0 0", "0 0 3.14"] * 4)
    launch = LaunchProcess(
        [
            str(ROOT / "launch/qbot_navigation.launch.yaml"),
            "slam:=false",
            f"map:={tmp / 'house.yaml'}",
            f"goal:={goals}",
            "--view",
            "--view-port",
            "0",
            "--view-rate",
            str(rate),
            "--duration",
            str(duration),
            "--no-bag",
        ],
        cwd=tmp,
    )
    driver = None
    try:
        url = launch.wait_for(r"view: open (http://127\.0\.0\.1:\d+/\?token=[\w-]+)", 120).group(
            1
        )  # with its token
        if browser:
            driver = chromium(tmp / "profile")
            driver.get(url)
        cpu0, wall0 = browser_cpu_seconds(), time.monotonic()
        done = launch.wait_for(r"simulated ([\d.]+) s in ([\d.]+) s", 10 * duration + 120)
        cpu = (browser_cpu_seconds() - cpu0) / (time.monotonic() - wall0)
    finally:
        if driver is not None:
            driver.quit()
        launch.interrupt()
    sim, wall = float(done.group(1)), float(done.group(2))
    frames = re.search(r"(\d+) frames sent, (\d+) dropped", "\n".join(launch.lines))
    sent, dropped = (frames.group(1), frames.group(2)) if frames else (f"{rate * sim:.0f}", "0")
    who = "headless Chromium" if browser else "no browser"
    result.add(
        "rtf",
        sim / wall,
        "x real time",
        target=">= 0.99",
        row=who,
        headline=f"paced view launch, {who}: real-time factor",
    )
    result.add("frames", float(sent) + float(dropped), row=who)
    result.add("frames_dropped", float(dropped), row=who)
    return (
        f"  {who:18s} {sim:5.1f} s in {wall:5.1f} s: real-time factor {sim / wall:5.3f}; "
        f"frames sent {sent}, dropped {dropped}; browser {cpu:4.2f} cores"
    )


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--duration", type=float, default=30.0, help="simulated seconds per run")
    p.add_argument("--rate", type=float, default=20.0, help="--view-rate (frames per second at most)")
    a = p.parse_args()
    result = BenchResult(
        "view_rtf",
        "the qbot navigation launch with --view paced to real time, without a browser "
        "and with headless Chromium showing the page (software WebGL on the same cores)",
    )
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run(
            [
                sys.executable,
                "-m",
                "twil_control.tools.rasterize",
                str(ROOT / "sim/worlds/house.sdf"),
                "-o",
                str(tmp / "house"),
            ],
            check=True,
            capture_output=True,
        )
        print(
            f"qbot navigation with --view --view-rate {a.rate:g}, paced to real time, {a.duration:g} s each:"
        )
        for browser in (False, True):
            print(one_run(tmp, a.duration, a.rate, browser, result), flush=True)
    import os

    print(f"  load average: {' '.join(f'{v:.2f}' for v in os.getloadavg())} on {os.cpu_count()} cores")
    result.write()


if __name__ == "__main__":
    main()
