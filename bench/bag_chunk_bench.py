"""What capping bag chunks at 1 simulated second costs, against 1 MiB chunks (rosbags' size).

A chunk reaches the file whole when it is closed, so a hard kill loses the open chunk: with
1 MiB chunks that was 4.6 simulated s of twil_sim, with 1 s chunks it is at most 1 s. Two
measurements, each variant alternated with the others in one run:

1. Recording throughput (messages/s): 2 s of real twil_sim messages (joint states, tf,
   odometry) published again and again on a bus for --seconds of simulated time, recorded by
   the BagRecorder (serialisation, LZ4, file writes) with 1 MiB chunks, 1 s chunks, and 1 s
   chunks with an fdatasync after each (in a thread of its own); and by rosbags' plain
   Writer, as the recorder used it.
2. The twil_sim launch's real-time factor (and CPU seconds of the run) with the defaults (1 s
   chunks, fdatasync in a thread), 1 s chunks with --no-fsync, and 1 MiB chunks with
   --no-fsync (the recorder before), each run in a fresh process (pydrake keeps a diagram per
   process), --rounds times.

The host is shared: wall-clock figures carry the other processes' load, CPU figures much less
of it; the load average and the host's steal are recorded. Writes its result to bench/results/.

    .venv/bin/python bench/bag_chunk_bench.py [--seconds 30] [--repeats 9] [--rounds 6] [--duration 10]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import BenchResult
from rosbags.rosbag1 import Writer

from twil_control import PACKAGE_ROOT
from twil_control.bag.reader import Bag
from twil_control.bag.recorder import BagRecorder
from twil_control.core import messages
from twil_control.core.bus import Bus
from twil_control.launch.runner import SLICE

LAUNCH = "launch/twil_sim.launch.yaml"
SAMPLE_SECONDS = 2.0


def sample_messages(tmp: Path) -> list[tuple[float, str, str, object]]:
    """(t, topic, type, message) of a short twil_sim run, in time order."""
    bag = tmp / "sample.bag"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(PACKAGE_ROOT / LAUNCH),
            "--duration",
            str(SAMPLE_SECONDS),
            "--bag",
            str(bag),
            "--quiet",
        ],
        check=True,
    )
    b = Bag(bag)
    out = []
    for topic, info in b.topics.items():
        if info.latching:
            continue
        for t, msg in b.messages(topic):
            out.append((t * 1e-9, topic, msg.__msgtype__, msg))
    out.sort(key=lambda m: m[0])
    return out


def _replay(sample, seconds: float, publish, flush) -> int:
    """Publish the sample shifted by SAMPLE_SECONDS each round, flushing every SLICE."""
    n, next_flush = 0, SLICE
    for k in range(int(round(seconds / SAMPLE_SECONDS))):
        for t, topic, _, msg in sample:
            t += k * SAMPLE_SECONDS
            while t >= next_flush:
                flush(next_flush)
                next_flush += SLICE
            publish(topic, msg, t)
            n += 1
    flush(next_flush)
    return n


def _bus_for(sample):
    bus = Bus()
    pubs = {topic: bus.advertise(topic, typ, node="/bench") for _, topic, typ, _ in sample}

    def publish(topic, msg, t):
        bus.clock.set(t)
        pubs[topic].publish(msg)

    return bus, publish


def _rates(n: int, wall0: float, cpu0: float) -> tuple[float, float]:
    """(messages per wall second, messages per CPU second of this process)."""
    return n / (time.perf_counter() - wall0), n / (time.process_time() - cpu0)


def record_with_recorder(sample, seconds: float, path: Path, **kw) -> tuple[float, float]:
    bus, publish = _bus_for(sample)
    start, cpu = time.perf_counter(), time.process_time()
    recorder = BagRecorder(path, bus, **kw)

    def flush(t):
        bus.clock.set(t)
        recorder.flush()

    n = _replay(sample, seconds, publish, flush)
    recorder.close()
    return _rates(n, start, cpu)


def record_with_rosbags_writer(sample, seconds: float, path: Path) -> tuple[float, float]:
    """The recorder's loop before time-capped chunks: the bus's messages kept until the next
    flush, then serialised into rosbags' Writer as it is (1 MiB chunks, buffered file)."""
    bus, publish = _bus_for(sample)
    start, cpu = time.perf_counter(), time.process_time()
    writer = Writer(path)
    writer.set_compression(Writer.CompressionFormat.LZ4)
    writer.open()
    conns, pending = {}, []

    def on_message(topic, msgtype, msg, t):
        if topic not in conns:
            msgdef, md5 = messages.definition(msgtype)
            conns[topic] = writer.add_connection(topic, msgtype, msgdef=msgdef, md5sum=md5)
        pending.append((conns[topic], int(round(t * 1e9)), msg))

    bus.add_listener(on_message)

    def flush(t):
        bus.clock.set(t)
        for conn, stamp, msg in pending:
            writer.write(conn, stamp, messages.serialize(msg))
        pending.clear()

    n = _replay(sample, seconds, publish, flush)
    writer.close()
    return _rates(n, start, cpu)


LAUNCH_VARIANTS = {
    "--chunk-seconds 1 (default)": {"chunk_seconds": 1.0},
    "--chunk-seconds 1 --no-fsync": {"chunk_seconds": 1.0, "fsync": False},
    "--chunk-seconds 0 --no-fsync": {"chunk_seconds": 0.0, "fsync": False},
}

VARIANTS = {
    "1 MiB chunks": lambda s, sec, p: record_with_recorder(s, sec, p, chunk_seconds=0),
    "1 s chunks": lambda s, sec, p: record_with_recorder(s, sec, p, chunk_seconds=1.0),
    "1 s chunks + fdatasync": lambda s, sec, p: record_with_recorder(
        s, sec, p, chunk_seconds=1.0, fsync=True
    ),
    "rosbags Writer (before)": record_with_rosbags_writer,
}


def launch_rtf_in_child(options: dict, duration: float) -> dict:
    """{'rtf': simulated / wall seconds of the run, 'cpu': CPU seconds of the run call (build
    included, the same for both settings), 'messages'} of the launch in a fresh process."""
    code = (
        f"import json, sys, time; sys.path.insert(0, {str(Path(__file__).resolve().parent)!r}); from _common import launch_rtf; "
        f"c = time.process_time(); rtf, n = launch_rtf({LAUNCH!r}, {duration!r}, **{options!r}); "
        "print(json.dumps({'rtf': rtf, 'cpu': time.process_time() - c, 'messages': n}))"
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--seconds", type=float, default=30.0, help="simulated seconds recorded per throughput run"
    )
    parser.add_argument("--repeats", type=int, default=9, help="rounds of the throughput variants")
    parser.add_argument(
        "--rounds", type=int, default=6, help="rounds of alternated launch runs (one per setting)"
    )
    parser.add_argument("--duration", type=float, default=10.0, help="simulated seconds per launch run")
    args = parser.parse_args()
    result = BenchResult(
        "bag_chunk_bench",
        "bag chunks closed every simulated second against 1 MiB chunks: the "
        "recorder's messages per second, and the twil_sim launch's real-time factor and CPU time",
    )
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        sample = sample_messages(tmp)
        for i, variant in enumerate(VARIANTS.values()):  # warm-up: serialisers generated, caches filled
            variant(sample, 2 * SAMPLE_SECONDS, tmp / f"warm{i}.bag")
        rates = {name: [] for name in VARIANTS}
        for r in range(args.repeats):
            order = list(VARIANTS)[r % len(VARIANTS) :] + list(VARIANTS)[: r % len(VARIANTS)]
            for name in order:
                path = tmp / f"run{r}_{list(VARIANTS).index(name)}.bag"
                rates[name].append(VARIANTS[name](sample, args.seconds, path))
                path.unlink()
    n_msgs = int(len(sample) * round(args.seconds / SAMPLE_SECONDS))
    print(
        f"recording throughput: {n_msgs:,} twil_sim messages ({args.seconds:g} simulated s) per run, "
        f"{args.repeats} rounds alternated; messages per wall s and per CPU s of the process, median "
        "(best), and the medians' ratio to 1 MiB chunks"
    )
    wall = {name: [w for w, _ in v] for name, v in rates.items()}
    cpu = {name: [c for _, c in v] for name, v in rates.items()}
    base_w, base_c = np.median(wall["1 MiB chunks"]), np.median(cpu["1 MiB chunks"])
    for name in VARIANTS:
        print(
            f"  {name:26s} wall {np.median(wall[name]):7,.0f} ({max(wall[name]):7,.0f}) {np.median(wall[name]) / base_w:5.3f}"
            f"   CPU {np.median(cpu[name]):7,.0f} ({max(cpu[name]):7,.0f}) {np.median(cpu[name]) / base_c:5.3f}"
        )
    runs = {name: [] for name in LAUNCH_VARIANTS}
    for i in range(args.rounds):
        names = list(LAUNCH_VARIANTS)
        for name in names[i % len(names) :] + names[: i % len(names)]:
            runs[name].append(launch_rtf_in_child(LAUNCH_VARIANTS[name], args.duration))
    rtf = {name: [r["rtf"] for r in v] for name, v in runs.items()}
    run_cpu = {name: [r["cpu"] for r in v] for name, v in runs.items()}
    base = "--chunk-seconds 0 --no-fsync"
    print(
        f"twil_sim launch, {args.duration:g} s simulated, {args.rounds} alternated rounds (fresh processes); "
        "per round, ratios to 1 MiB chunks without fdatasync (the recorder before):"
    )
    ratios = {}
    for name in LAUNCH_VARIANTS:
        r = [a / b for a, b in zip(rtf[name], rtf[base])]
        c = [a / b for a, b in zip(run_cpu[name], run_cpu[base])]
        ratios[name] = (float(np.median(r)), float(np.median(c)))
        print(
            f"  {name:30s} real-time factor {np.median(rtf[name]):.2f} ({min(rtf[name]):.2f}-{max(rtf[name]):.2f}), "
            f"ratio {np.median(r):.3f} ({min(r):.3f}-{max(r):.3f}); CPU of the run {np.median(run_cpu[name]):.2f} s, "
            f"ratio {np.median(c):.3f}"
        )
    result.add("messages_per_run", n_msgs, "messages recorded per throughput run")
    throughput = "recorder throughput (median of the rounds)"
    for name in VARIANTS:
        result.add("per wall s", np.median(wall[name]), "messages", row=name, table=throughput)
        result.add("per CPU s", np.median(cpu[name]), "messages", row=name, table=throughput)
        result.add("best per CPU s", max(cpu[name]), "messages", row=name, table=throughput)
        result.add(
            "per CPU s / 1 MiB chunks",
            np.median(cpu[name]) / base_c,
            row=name,
            table=throughput,
            headline=name == "1 s chunks" and "recorder, messages per CPU s: 1 s chunks / 1 MiB chunks",
        )
    launch = "twil_sim launch (medians; ratios per round to 1 MiB chunks without fdatasync)"
    for name in LAUNCH_VARIANTS:
        result.add("rtf", np.median(rtf[name]), "x real time", row=name, table=launch)
        result.add(
            "rtf / 1 MiB chunks",
            ratios[name][0],
            row=name,
            table=launch,
            headline=name == "--chunk-seconds 1 (default)"
            and "twil_sim real-time factor: 1 s chunks + fdatasync / 1 MiB chunks",
        )
        result.add("CPU / 1 MiB chunks", ratios[name][1], row=name, table=launch)
    result.write()


if __name__ == "__main__":
    main()
