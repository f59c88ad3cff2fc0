"""roslaunch's role: ``python -m twil_control.launch [PACKAGE] FILE [FILE ...] [name:=value ...]
[options]``, the ``name:=value`` args anywhere on the line (launch/command_line.py).

Exit codes: 0 the run ended normally or was stopped by SIGINT, SIGTERM or SIGHUP, as roslaunch
is; 1 something failed while time ran (the bag kept), or a bug before time started (its
traceback); 2 the launch could not start (bad input, a TwilControlError: one line naming what
and where, nothing written). Each case and what it leaves on disk: docs/failures.md, docs/bags.md.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import signal
import sys
import time
from pathlib import Path

from twil_control.errors import InputError

from ..errors import exit_on_error
from ..foxglove import DEFAULT_PORT as FOXGLOVE_PORT
from .interrupt import STOP_SIGNALS, StopSignal, on_stop_while_starting
from .logging_setup import configure_logging

log = logging.getLogger("twil_control.launch")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m twil_control.launch",
        usage="%(prog)s [PACKAGE] FILE [FILE ...] [name:=value ...] [options]",
        description="Run launch files: the simulated robot, its nodes and controllers, "
        "recorded into a ROS 1 bag. name:=value args may stand anywhere on the line.",
    )
    p.add_argument(
        "files",
        nargs="+",
        metavar="FILE",
        help="launch files, YAML (launch/twil_sim.launch.yaml) or roslaunch XML (a .launch or "
        ".xml file), loaded into one graph; or PACKAGE FILE, the file found in a ROS package "
        "as roslaunch finds it",
    )
    p.add_argument(
        "--duration", type=float, metavar="S", help="simulated seconds to run (default: until done or Ctrl-C)"
    )
    p.add_argument(
        "--bag", type=Path, metavar="PATH", help="bag to write (default: runs/<launch>_<time>.bag)"
    )
    p.add_argument("--no-bag", action="store_true", help="record nothing")
    p.add_argument(
        "--bag-format",
        choices=("bag", "mcap"),
        help="record a ROS 1 bag or an MCAP file (ROS 1 profile, zstd chunks) (default: --bag's "
        "suffix, else the launch file's record format, else bag)",
    )
    p.add_argument(
        "--chunk-seconds",
        type=float,
        default=1.0,
        metavar="S",
        help="simulated seconds a bag chunk holds at most: what a hard kill can lose "
        "(default 1; 0 = 1 MiB chunks)",
    )
    p.add_argument(
        "--no-fsync",
        action="store_true",
        help="do not fdatasync each bag chunk (in a thread of its own, so that a power loss "
        "also loses only about the last chunk)",
    )
    p.add_argument(
        "--min-space",
        default="1G",
        metavar="SIZE",
        help="free space the bag's disk needs at start, warned about below it while "
        "recording (rosbag record's option; default 1G; k, M, G or bytes)",
    )
    p.add_argument(
        "--convert-memory",
        default="2G",
        metavar="SIZE",
        help="memory the child process that runs xacro and converts meshes may use "
        "(default 2G; k, M, G or bytes)",
    )
    p.add_argument(
        "--convert-time",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="seconds the child process that runs xacro and converts meshes may take (default 60)",
    )
    p.add_argument(
        "--max-mesh-size",
        default="128M",
        metavar="SIZE",
        help="a robot's mesh file larger than this is refused (default 128M)",
    )
    p.add_argument(
        "--max-mesh-triangles",
        type=int,
        default=2_000_000,
        metavar="N",
        help="a robot's mesh with more triangles of non-zero area is refused (default 2000000)",
    )
    p.add_argument(
        "--realtime",
        type=float,
        metavar="R",
        default=None,
        help="target real-time rate; 0 = as fast as possible (default 0)",
    )
    p.add_argument(
        "--view",
        action="store_true",
        help="serve the Meshcat view and goal panel (also view:=true); runs in real time "
        "unless --realtime says otherwise, until --duration or Ctrl-C",
    )
    p.add_argument(
        "--view-host",
        default="127.0.0.1",
        metavar="ADDR",
        help="address the view binds to (default 127.0.0.1: this machine only)",
    )
    p.add_argument(
        "--view-port",
        type=int,
        default=8800,
        metavar="N",
        help="port of the view's page (default 8800; 0 = any free port)",
    )
    p.add_argument(
        "--view-rate",
        type=float,
        default=20.0,
        metavar="HZ",
        help="frames per second the view sends at most (default 20); while the simulation is "
        "behind real time it drops frames, down to a quarter of this",
    )
    p.add_argument(
        "--save-html",
        type=Path,
        metavar="PATH",
        help="save the run as one self-contained HTML file (Meshcat recording), with or without --view",
    )
    p.add_argument(
        "--foxglove",
        type=int,
        nargs="?",
        const=FOXGLOVE_PORT,
        metavar="PORT",
        help=f"serve every topic live to Foxglove over its WebSocket protocol on PORT (default "
        f"{FOXGLOVE_PORT}; 0 = any free port); runs in real time unless --realtime says otherwise",
    )
    p.add_argument(
        "--foxglove-host",
        default="127.0.0.1",
        metavar="ADDR",
        help="address the Foxglove server binds to (default 127.0.0.1: this machine only)",
    )
    p.add_argument(
        "--foxglove-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="also accept Foxglove connections from web pages of ORIGIN (scheme://host[:port]; "
        "repeatable); accepted always: no Origin, the Foxglove and Lichtblick apps",
    )
    p.add_argument(
        "--foxglove-capabilities",
        metavar="LIST",
        help="foxglove_bridge's capabilities, comma-separated (default parameters,parametersSubscribe,"
        "time); clientPublish lets clients publish goals and velocity commands, services lets them "
        "switch controllers",
    )
    p.add_argument(
        "--foxglove-client-topic-whitelist",
        action="append",
        metavar="REGEX",
        help="topics clients may publish on, with clientPublish (repeatable; default .*)",
    )
    p.add_argument(
        "--foxglove-service-whitelist",
        action="append",
        metavar="REGEX",
        help="services clients may call, with services (repeatable; default .*)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of every random source (default 0)")
    p.add_argument(
        "--package-path",
        action="append",
        default=[],
        metavar="DIRS",
        help="folders searched for ROS packages (package.xml) before ROS_PACKAGE_PATH, "
        f"for $(find pkg) and package:// URLs; '{os.pathsep}'-separated, repeatable",
    )
    p.add_argument("--graph", action="store_true", help="print nodes and topics, then exit")
    p.add_argument("--debug", action="store_true", help="show tracebacks and debug logging")
    p.add_argument("--quiet", action="store_true", help="only warnings and errors")
    return p


def _default_bag(launch_file: Path, fmt: str) -> Path:
    """runs/<first launch file's name>_<local date and time>.<format>"""
    stem = launch_file.name.split(".")[0]
    runs = Path("runs")
    runs.mkdir(exist_ok=True)
    return runs / f"{stem}_{time.strftime('%Y-%m-%d-%H-%M-%S')}.{fmt}"


def _bag_path(opts, plan) -> Path | None:
    """Where the run is recorded: --bag, a rosbag record node's -O/-o, or
    runs/<launch>_<time>.<format>, in the format of --bag-format, --bag's (or -O's) suffix, the
    launch file's record format, or bag, in that order."""
    if opts.no_bag:
        return None
    from ..bag.recorder import check_writable, format_of

    output = plan.record_output
    if opts.bag is not None and output is not None:
        log.info(
            "--bag %s: the bag of rosbag record %s (%s) is not written",
            opts.bag,
            output.option,
            output.source,
        )
        output = None
    fmt = (
        opts.bag_format
        or (format_of(opts.bag) if opts.bag is not None else None)
        or (output.suffix_format() if output is not None else None)
        or plan.record_format
        or "bag"
    )
    if opts.bag is not None:
        path = opts.bag
    elif output is not None:
        path = output.path(fmt)
    else:
        path = _default_bag(Path(opts.files[0]), fmt)
    check_writable(path, fmt)
    return path


def _take_view_arg(opts) -> None:
    """`view:=true|false` among the launch args is --view (a runner option, not a launch-file arg)."""
    rest = []
    for arg in opts.args:
        name, sep, value = arg.partition(":=")
        if sep and name == "view":
            if value.lower() not in ("true", "false", "1", "0"):
                raise InputError(f"view:={value}: use view:=true or view:=false")
            opts.view = opts.view or value.lower() in ("true", "1")
        else:
            rest.append(arg)
    opts.args = rest


def _view_options(opts):
    """The view's options, or None (no Meshcat at all) without --view and --save-html."""
    if not opts.view and opts.save_html is None:
        return None
    if not 0 <= opts.view_port <= 65535:
        raise InputError(f"--view-port must be in 0..65535 (got {opts.view_port}); 0 picks a free port")
    if opts.save_html is not None and opts.save_html.exists():
        raise InputError(
            f"--save-html {opts.save_html} exists; choose another name (it is never overwritten)"
        )
    from ..view.view_node import MAX_RATE, ViewOptions

    if not 0 < opts.view_rate <= MAX_RATE:  # also refuses nan
        raise InputError(f"--view-rate must be in (0, {MAX_RATE:g}] frames per second (got {opts.view_rate})")
    return ViewOptions(
        serve=opts.view,
        host=opts.view_host,
        port=opts.view_port,
        save_html=opts.save_html,
        rate=opts.view_rate,
    )


def _set_convert_limits(opts) -> None:
    """--convert-memory, --convert-time, --max-mesh-size, --max-mesh-triangles into core.limited."""
    from ..bag.recorder import parse_size
    from ..core import limited

    sizes = {}
    for option, text in (("--convert-memory", opts.convert_memory), ("--max-mesh-size", opts.max_mesh_size)):
        try:
            sizes[option] = parse_size(text)
        except ValueError:
            raise InputError(f"{option} {text!r}: use bytes or a number with k, M or G, e.g. 2G") from None
    if not (opts.convert_time > 0 and math.isfinite(opts.convert_time)):
        raise InputError(f"--convert-time must be a positive number of seconds (got {opts.convert_time})")
    if sizes["--convert-memory"] < 256 << 20:
        raise InputError(f"--convert-memory must be at least 256M (got {opts.convert_memory})")
    if opts.max_mesh_triangles < 1:
        raise InputError(f"--max-mesh-triangles must be at least 1 (got {opts.max_mesh_triangles})")
    limited.LIMITS = limited.Limits(
        sizes["--convert-memory"], opts.convert_time, sizes["--max-mesh-size"], opts.max_mesh_triangles
    )


def _foxglove_options(opts):
    """The bridge's options, or None (no server) without --foxglove."""
    if opts.foxglove is None:
        return None
    if not 0 <= opts.foxglove <= 65535:
        raise InputError(f"--foxglove port must be in 0..65535 (got {opts.foxglove}); 0 picks a free port")
    from ..foxglove.access import DEFAULT_CAPABILITIES
    from ..foxglove.bridge import FoxgloveOptions

    capabilities = DEFAULT_CAPABILITIES
    if opts.foxglove_capabilities is not None:
        capabilities = tuple(c.strip() for c in opts.foxglove_capabilities.split(",") if c.strip())
    options = FoxgloveOptions(
        host=opts.foxglove_host,
        port=opts.foxglove,
        origins=tuple(opts.foxglove_origin),
        capabilities=capabilities,
        client_topic_whitelist=tuple(opts.foxglove_client_topic_whitelist or (".*",)),
        service_whitelist=tuple(opts.foxglove_service_whitelist or (".*",)),
    )
    options.access()  # a bad origin, capability or regex: one error line before anything starts
    return options


def _port_optional(argv: list[str]) -> list[str]:
    """`--foxglove` followed by a launch argument (goal:=...) or the file is `--foxglove` alone:
    argparse would take the next word as its PORT."""
    out = list(argv)
    for i, word in enumerate(out):
        if word == "--foxglove" and (i + 1 == len(out) or not out[i + 1].isdigit()):
            out[i] = f"--foxglove={FOXGLOVE_PORT}"
    return out


def main(argv: list[str] | None = None) -> int:
    from .command_line import split_launch_args

    launch_args, words = split_launch_args(sys.argv[1:] if argv is None else argv)
    opts = _parser().parse_intermixed_args(_port_optional(words))
    opts.args = launch_args
    clock = configure_logging(debug=opts.debug, quiet=opts.quiet)
    previous = {signum: signal.signal(signum, on_stop_while_starting) for signum in STOP_SIGNALS}
    try:
        # bad input (a TwilControlError) is one line and exit 2; anything else is a bug: its
        # traceback, exit 1
        return exit_on_error(lambda: _run(opts, clock), debug=opts.debug)
    except KeyboardInterrupt as stop:  # Ctrl-C (or SIGTERM, SIGHUP) while importing or building
        name = signal.Signals(stop.signum).name if isinstance(stop, StopSignal) else "SIGINT"
        log.info("interrupted by %s before time started: nothing was run, no bag written", name)
        return 0
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _run(opts, clock) -> int:
    from ..core.node import check_seed
    from .command_line import launch_files
    from .loader import load_launch, parse_cli_args
    from .runner import Launch, RunOptions, run
    from .supervision import RequiredNodeFailed, cause_of, is_bug

    if opts.duration is not None and not (opts.duration > 0 and math.isfinite(opts.duration)):
        raise InputError(f"--duration must be a positive number of seconds (got {opts.duration})")
    if opts.realtime is not None and not (opts.realtime >= 0 and math.isfinite(opts.realtime)):
        raise InputError(f"--realtime must be >= 0 (got {opts.realtime}); 0 runs as fast as possible")
    check_seed(opts.seed)
    if not (opts.chunk_seconds >= 0 and math.isfinite(opts.chunk_seconds)):
        raise InputError(
            f"--chunk-seconds must be >= 0 (got {opts.chunk_seconds}); 0 closes chunks by size only"
        )
    from ..bag.recorder import parse_size

    min_space = parse_size(opts.min_space)
    _set_convert_limits(opts)
    _take_view_arg(opts)
    from ..core import packages

    packages.set_extra_paths(p for arg in opts.package_path for p in arg.split(os.pathsep) if p)
    opts.files = launch_files(opts.files)
    plan = load_launch(opts.files, parse_cli_args(opts.args))

    if opts.graph:
        from .graph import print_graph

        launch = Launch(plan, seed=opts.seed)
        launch.build()
        launch.start()
        print_graph(launch)
        launch.shutdown()
        return 0

    bag = _bag_path(opts, plan)
    view = _view_options(opts)
    foxglove = _foxglove_options(opts)
    live = opts.view or foxglove is not None
    realtime = opts.realtime if opts.realtime is not None else (1.0 if live else 0.0)
    options = RunOptions(
        duration=opts.duration,
        bag=bag,
        realtime=realtime,
        seed=opts.seed,
        progress=sys.stderr.isatty() and not os.environ.get("CI"),
        view=view,
        stop_when_done=not opts.view,
        foxglove=foxglove,
        chunk_seconds=opts.chunk_seconds,
        min_space=min_space,
        fsync=not opts.no_fsync,
    )
    result = run(plan, options, on_master=clock.attach)
    # the run is over and its bag closed: a late Ctrl-C (a sweep repeats SIGINT until the
    # process is gone) has nothing left to stop, and must not change the exit code
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    summary = (
        f"simulated {result.sim_time:.3f} s in {result.wall_time:.2f} s "
        f"({result.realtime_factor:.1f}x real time)"
    )
    if result.bag:
        summary += f"; bag {result.bag} with {result.messages} messages"
    if result.error is not None:
        cause = result.error.failure.error if isinstance(result.error, RequiredNodeFailed) else result.error
        if opts.debug or is_bug(cause):  # a bug (not a TwilControlError) shows its traceback
            log.error("the run stopped on this exception", exc_info=cause_of(cause))
        log.error("%s", result.error)
        log.error("stopped at t = %.3f s; %s", result.sim_time, summary)
        return 1
    if result.failures:
        log.error(
            "%d node failure%s while the launch went on: %s; %s",
            len(result.failures),
            "s" if len(result.failures) > 1 else "",
            "; ".join(map(str, result.failures)),
            summary,
        )
        return 1
    stopped = f"interrupted by {signal.Signals(result.signal).name}: " if result.signal else ""
    log.info("%s%s", stopped, summary)
    return 0


if __name__ == "__main__":
    code = main()
    # the run is over and its bag closed: a Ctrl-C while the interpreter exits (a sweep's worker
    # repeats SIGINT every 0.5 s until the process is gone) has nothing left to stop, and would
    # only turn exit code 0 into death by SIGINT
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    sys.exit(code)
