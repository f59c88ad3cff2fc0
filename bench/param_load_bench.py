"""Loading parameters: seconds to load a rosparam YAML of N keys (100 per namespace) and a
roslaunch file of N ``<param>`` elements, for growing N, and the cost per key at the largest N
against the smallest (1.0: linear). The issue it guards: each set scanned every source, so
150k keys did not load in 300 s.

    .venv/bin/python bench/param_load_bench.py [--yaml 10000 30000 150000] [--launch 4000 16000 64000]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _result import BenchResult


def yaml_file(folder: Path, n: int) -> Path:
    path = folder / f"params_{n}.yaml"
    path.write_text(
        "".join((f"ns{i // 100}:\n" if i % 100 == 0 else "") + f"  key_{i}: {i}.5\n" for i in range(n))
    )
    return path


def launch_file(folder: Path, n: int) -> Path:
    path = folder / f"params_{n}.launch"
    body = "".join(f'  <param name="group{i // 100}/p{i}" value="{i}.25"/>\n' for i in range(n))
    path.write_text(f"<launch>\n{body}</launch>\n")
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--yaml", type=int, nargs="+", default=[10000, 30000, 150000])
    ap.add_argument("--launch", type=int, nargs="+", default=[4000, 16000, 64000])
    a = ap.parse_args()
    from twil_control.core.params import ParamServer
    from twil_control.launch.loader import load_launch

    r = BenchResult("param_load_bench", "seconds to load rosparam YAML and roslaunch <param> files of N keys")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        per_key = {}
        for n in a.yaml:
            path = yaml_file(folder, n)
            server = ParamServer()
            t, c = time.perf_counter(), time.process_time()
            server.load_file(path, "/robot")
            s, cpu = time.perf_counter() - t, time.process_time() - c
            assert len(server.names()) == n
            per_key[n] = cpu / n
            print(
                f"yaml {n:>7} keys ({path.stat().st_size / 1e6:.1f} MB): {s:.2f} s wall, {cpu:.2f} s CPU, "
                f"{cpu / n * 1e6:.1f} us CPU a key"
            )
            r.add(
                "cpu_seconds",
                cpu,
                "s",
                row=f"YAML, {n} keys",
                headline=f"{n}-key YAML, load (CPU)" if n == max(a.yaml) else False,
            )
            r.add("seconds", s, "s", row=f"YAML, {n} keys")
        ratio = per_key[max(a.yaml)] / per_key[min(a.yaml)]
        r.add("per_key_ratio_yaml", ratio, "x", target="< 2")
        print(f"cost per key, {max(a.yaml)} against {min(a.yaml)} keys: {ratio:.2f}x (1.0 = linear)")
        per_key = {}
        for n in a.launch:
            path = launch_file(folder, n)
            t, c = time.perf_counter(), time.process_time()
            plan = load_launch(path, {})
            s, cpu = time.perf_counter() - t, time.process_time() - c
            assert len(plan.params.names()) == n
            per_key[n] = cpu / n
            print(
                f"launch {n:>6} <param> ({path.stat().st_size / 1e6:.1f} MB): {s:.2f} s wall, {cpu:.2f} s CPU, "
                f"{cpu / n * 1e6:.1f} us CPU a param"
            )
            r.add("cpu_seconds", cpu, "s", row=f"launch, {n} <param>")
            r.add("seconds", s, "s", row=f"launch, {n} <param>")
        ratio = per_key[max(a.launch)] / per_key[min(a.launch)]
        r.add("per_key_ratio_launch", ratio, "x", target="< 2")
        print(f"cost per <param>, {max(a.launch)} against {min(a.launch)}: {ratio:.2f}x (1.0 = linear)")
    print(r.write())


if __name__ == "__main__":
    main()
