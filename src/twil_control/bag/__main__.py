"""rosbag / rqt_plot / PlotJuggler's roles: ``python -m twil_control.bag COMMAND ...``.

Exit codes: 0 done, 2 bad input (a missing file, a file that is not a bag, a bag without
index, an unknown topic or field, a bad option: a TwilControlError): one line ``error: ...``
naming the problem, no traceback (``--debug`` shows it); 1 for any other exception, a bug,
with its traceback.
"""

from __future__ import annotations

import argparse
import logging
import signal
import sys
import threading
from pathlib import Path

from ..errors import exit_on_error
from .output import check_new_output

EXAMPLES = """examples:
  python -m twil_control.bag info runs/cart.bag
  python -m twil_control.bag plot runs/cart.bag /joint_states/position[3] /twil/odom/pose/pose/position/x -o out.png
  python -m twil_control.bag xy runs/qbot.bag /qbot/ground_truth/odom/pose/pose/position/x:/qbot/ground_truth/odom/pose/pose/position/y -o path.png
  python -m twil_control.bag analyze runs/cart.bag -o report.html
  python -m twil_control.bag report runs/cart.bag -o cart.png
  python -m twil_control.bag export runs/cart.bag /joint_states -o joints.csv
  python -m twil_control.bag compare corrected.bag printed.bag
  python -m twil_control.bag play runs/qbot.bag --rate 2
  python -m twil_control.bag reindex runs/crashed.bag.active -o fixed.bag
  python -m twil_control.bag convert runs/qbot.bag runs/qbot.mcap
  python -m twil_control.bag convert runs/qbot.mcap runs/qbot_ros2 --to ros2
"""


def _output(s: argparse.ArgumentParser, what: str, required: bool = True) -> None:
    """-o/--output FILE and --force: a bag tool never replaces a file unless asked."""
    s.add_argument("-o", "--output", type=Path, required=required, help=what)
    s.add_argument("--force", action="store_true", help="replace the output file if it exists")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m twil_control.bag",
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Inspect, plot, analyse, export, compare, replay, "
        "repair and convert ROS 1 bags (format 2.0) and MCAP files "
        "of ROS 1 messages.",
    )
    p.add_argument("--debug", action="store_true", help="show tracebacks")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")

    s = sub.add_parser(
        "info",
        help="summary of a bag (rosbag info)",
        description="Path, version, duration, start and end, size, compression, "
        "message count; per topic its type, count and rate. Reads only the index.",
    )
    s.add_argument("bag", type=Path)
    s.add_argument("-y", "--yaml", action="store_true", help="YAML output (rosbag info -y)")

    s = sub.add_parser(
        "plot",
        help="time series of numeric fields (rqt_plot)",
        description="Time series of numeric fields named as in rqt_plot: "
        "/topic/field/sub[i], e.g. /joint_states/position[3] or "
        "/twil/odom/pose/pose/position/x. Several fields share one axes "
        "(--subplots: one each). Format from the extension: png, svg, pdf.",
    )
    s.add_argument("bag", type=Path)
    s.add_argument("fields", nargs="+", metavar="TOPIC/FIELD")
    _output(s, "image file (.png, .svg, .pdf)")
    s.add_argument("--subplots", action="store_true", help="one axes per field")
    s.add_argument("--title")

    s = sub.add_parser(
        "xy",
        help="y against x (a platform's path)",
        description="Curves y(x), each X_FIELD:Y_FIELD (rqt_plot field names), equal "
        "axis scales, start (o) and end (s) marked. Fields of different "
        "topics are matched in time (Y interpolated at X's times).",
    )
    s.add_argument("bag", type=Path)
    s.add_argument("pairs", nargs="+", metavar="X_FIELD:Y_FIELD")
    _output(s, "image file (.png, .svg, .pdf)")
    s.add_argument("--title")

    s = sub.add_parser(
        "analyze",
        help="metrics of what the bag holds (controller, odometry, mapping, navigation)",
        description="Detects from the topics which analyses apply (cart controller, "
        "computed torque, odometry/qbot, mapping, navigation), prints their "
        "metrics and optionally writes a report (.md with PNGs beside it, "
        "or one self-contained .html).",
    )
    s.add_argument("bag", type=Path)
    _output(s, "report file (.md or .html)", required=False)
    s.add_argument("--json", action="store_true", help="print the metrics as JSON")
    s.add_argument(
        "--ground-truth-map",
        type=Path,
        metavar="MAP.yaml",
        help="map_server YAML (+ image) to score /map and clearances against",
    )
    s.add_argument("--wn", type=float, help="computed-torque natural frequency, rad/s (default 5)")
    s.add_argument("--arm-joints", help="comma-separated joint names of the arm references")
    s.add_argument("--only", help="comma-separated analyses to run")

    s = sub.add_parser(
        "report",
        help="a cart_linearizing_controller run: summary lines and one figure",
        description="The cart analysis in a few lines (final error against the truth and "
        "the odometry, convergence, V1, arm tracking, wheel torques) and one "
        "figure (e, alpha, psi, path, V1, wheel torques, arm errors), written "
        "next to the bag unless -o says where.",
    )
    s.add_argument("bag", type=Path)
    s.add_argument("-o", "--output", type=Path, help="figure file (.png, .svg, .pdf; default: BAG with .png)")

    s = sub.add_parser(
        "export",
        help="one topic as a CSV or Parquet table",
        description="One row per message: time (s), time_ns, every field (dotted names; "
        "fixed-length numeric arrays one column per element).",
    )
    s.add_argument("bag", type=Path)
    s.add_argument("topic")
    _output(s, ".csv or .parquet")
    s.add_argument("--fields", help="comma-separated dotted field names (default: all)")

    s = sub.add_parser(
        "play",
        help="replay onto the in-process bus (rosbag play)",
        description="Publishes the messages in time order on the topic bus, the "
        "simulated clock following the bag's time, paced by --rate.",
    )
    s.add_argument("bag", type=Path)
    s.add_argument(
        "--rate", type=float, default=1.0, help="bag seconds per wall second (0: as fast as possible)"
    )
    s.add_argument("--start", type=float, default=0.0, help="seconds into the bag to start from")
    s.add_argument("--duration", type=float, help="seconds of the bag to play")
    s.add_argument("--topics", help="comma-separated topics (default: all)")
    s.add_argument(
        "--view",
        action="store_true",
        help="draw the replay in the Meshcat view (robot from /tf, /map, costmaps, scans, plans)",
    )
    s.add_argument(
        "--view-host",
        default="127.0.0.1",
        metavar="ADDR",
        help="address the view binds to (default 127.0.0.1: this machine only)",
    )
    s.add_argument(
        "--save-html", type=Path, metavar="PATH", help="also save the replay as one self-contained HTML file"
    )
    s.add_argument("--force", action="store_true", help="replace the --save-html file if it exists")

    s = sub.add_parser(
        "compare",
        help="the metrics of two bags side by side",
        description="Runs analyze on both bags and prints each metric for A and B and B - A.",
    )
    s.add_argument("bag_a", type=Path)
    s.add_argument("bag_b", type=Path)
    s.add_argument("--json", action="store_true")
    s.add_argument("--ground-truth-map", type=Path, metavar="MAP.yaml")
    s.add_argument("--wn", type=float)

    s = sub.add_parser(
        "reindex",
        help="recover a bag without index into a new bag",
        description="Reads the records of an unindexed or truncated bag in file order "
        "and writes every complete message into a new, indexed bag.",
    )
    s.add_argument("bag", type=Path)
    _output(s, "new bag file")
    s.add_argument("--compression", default="lz4", choices=("lz4", "bz2", "none"))

    s = sub.add_parser(
        "convert",
        help="ROS 1 bag <-> MCAP, or either to a ROS 2 bag",
        description="Converts a ROS 1 bag to MCAP (ROS 1 profile: ros1 encoding, ros1msg "
        "schemas) or back, keeping every connection, definition, latching flag, "
        "message and stamp; or, with --to ros2, to a ROS 2 bag folder (MCAP "
        "storage, rosbags' converter). An existing output is replaced only with --force.",
    )
    s.add_argument("input", type=Path, help=".bag or .mcap file")
    s.add_argument("output", type=Path, help=".mcap or .bag file, or a new folder with --to ros2")
    s.add_argument(
        "--to", choices=("bag", "mcap", "ros2"), help="output format (default: from the output's suffix)"
    )
    s.add_argument("--force", action="store_true", help="replace the output file if it exists")
    s.add_argument(
        "--compression",
        default="zstd",
        choices=("zstd", "lz4", "none"),
        help="MCAP chunk compression (default zstd)",
    )
    return p


def _split(text: str | None) -> list[str] | None:
    return [x.strip() for x in text.split(",") if x.strip()] if text else None


def _analysis_options(a) -> dict:
    opts = {}
    if a.ground_truth_map is not None:
        opts["ground_truth_map"] = a.ground_truth_map
    if a.wn is not None:
        opts["wn"] = a.wn
    if getattr(a, "arm_joints", None):
        opts["arm_joints"] = _split(a.arm_joints)
    if getattr(a, "only", None):
        opts["only"] = _split(a.only)
    return opts


def _run(a) -> int:
    if a.command == "info":
        from .info import bag_info, format_info, format_yaml

        info = bag_info(a.bag)
        print(format_yaml(info) if a.yaml else format_info(info), end="\n" if not a.yaml else "")
    elif a.command == "plot":
        from .plot import plot_fields
        from .reader import Bag

        print(plot_fields(Bag(a.bag), a.fields, a.output, subplots=a.subplots, title=a.title, force=a.force))
    elif a.command == "xy":
        from .plot import plot_xy
        from .reader import Bag

        print(plot_xy(Bag(a.bag), a.pairs, a.output, title=a.title, force=a.force))
    elif a.command == "analyze":
        from .analyze import analyze_bag, format_text, to_json, write_report

        opts = _analysis_options(a)
        if a.output is not None:
            summary, out = write_report(a.bag, a.output, force=a.force, **opts)
        else:
            summary, out = analyze_bag(a.bag, **opts), None
        print(to_json(summary) if a.json else format_text(summary))
        if out is not None and not a.json:
            print(f"\nreport: {out}")
    elif a.command == "report":
        from .report import cart_report

        _, text, figure = cart_report(a.bag, a.output)
        print(text)
        print(f"figure: {figure}")
    elif a.command == "export":
        from .export import export_topic

        out, n = export_topic(a.bag, a.topic, a.output, _split(a.fields), force=a.force)
        print(f"{out}: {n} rows")
    elif a.command == "play" and (a.view or a.save_html):
        _play_with_view(a)
    elif a.command == "play":
        from .play import Player
        from .reader import Bag

        player = Player(Bag(a.bag), rate=a.rate, start=a.start, duration=a.duration, topics=_split(a.topics))
        for topic, why in player.stats.skipped.items():
            logging.getLogger("twil_control.bag").warning("not playing %s: %s", topic, why)
        st = player.run()
        print(
            f"played {st.messages} messages on {len(st.per_topic)} topics: bag time "
            f"{st.bag_start:.3f} .. {st.bag_end:.3f} s in {st.wall:.2f} s wall"
        )
    elif a.command == "compare":
        from .analyze import to_json
        from .compare import compare_bags, format_comparison

        c = compare_bags(a.bag_a, a.bag_b, **_analysis_options(a))
        print(to_json(c) if a.json else format_comparison(c))
    elif a.command == "convert":
        from .convert import convert

        c = convert(a.input, a.output, a.to, a.compression, force=a.force)
        print(f"{c.out}: {c.messages} messages on {c.connections} connections ({c.to})")
        _report_corrupt(a.input, c.corrupt)
    elif a.command == "reindex":
        from .reindex import reindex

        r = reindex(a.bag, a.output, a.compression, force=a.force)
        cut = (
            f"; the file ends inside a chunk at byte {r.size} (its complete records recovered)"
            if r.partial_chunk
            else ""
        )
        print(
            f"{r.out}: recovered {r.messages} messages on {r.topics} topics from {r.chunks} complete "
            f"chunks{cut}"
            + (f"; {r.dropped} messages without a connection record dropped" if r.dropped else "")
        )
        _report_corrupt(a.bag, r.corrupt)
    return 0


def _report_corrupt(path, corrupt: list) -> None:
    """What a copy left out: each corrupt MCAP chunk, and the messages dropped with it."""
    if corrupt:
        for c in corrupt:
            print(f"warning: {path}: left out corrupt {c.describe()}", file=sys.stderr)
        print(
            f"warning: {sum(c.messages for c in corrupt)} messages dropped with {len(corrupt)} corrupt "
            f"chunk{'s' if len(corrupt) > 1 else ''}",
            file=sys.stderr,
        )


def _play_with_view(a) -> None:
    """bag play --view / --save-html: the replay drawn in the Meshcat view (twil_control.view)."""
    import time

    from ..core.node import Master
    from ..view.bag_replay import replay_into_view
    from ..view.view_node import ViewOptions
    from .play import Player
    from .reader import Bag

    if a.save_html is not None:
        check_new_output(a.save_html, "--save-html", a.force)
    master = Master()
    player = Player(
        Bag(a.bag), bus=master.bus, rate=a.rate, start=a.start, duration=a.duration, topics=_split(a.topics)
    )
    options = ViewOptions(serve=False, host=a.view_host, save_html=a.save_html, replace_html=a.force)
    view, st = replay_into_view(master, options, player.run)
    try:
        print(
            f"played {st.messages} messages on {len(st.per_topic)} topics: bag time "
            f"{st.bag_start:.3f} .. {st.bag_end:.3f} s in {st.wall:.2f} s wall"
        )
        if a.view:
            print(f"view: {view.meshcat.web_url()} (Ctrl-C to exit)", flush=True)
            try:
                while True:
                    time.sleep(1.0)
            except (KeyboardInterrupt, _Stopped):  # Ctrl-C ends the replay as it is meant to
                pass
    finally:
        view.shutdown()


class _Stopped(BaseException):
    """SIGINT, SIGTERM or SIGHUP, raised where the command is, so that what it was writing is
    removed. Not a KeyboardInterrupt: one that left the program would make the interpreter end
    itself with SIGINT after printing the command's own line."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


_stopping: list[int] = []  # the signal that stopped the command: later ones are not raised again


def _raise_stopped(signum, frame) -> None:
    if not _stopping:
        _stopping.append(signum)
        raise _Stopped(signum)


def main(argv: list[str] | None = None) -> int:
    a = _parser().parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s: %(message)s")
    previous = {}
    _stopping.clear()
    if threading.current_thread() is threading.main_thread():
        stops = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
        previous = {s: signal.signal(s, _raise_stopped) for s in stops}
    try:
        return exit_on_error(lambda: _run(a), debug=a.debug)
    except KeyboardInterrupt:
        return _stopped(a, signal.SIGINT)
    except _Stopped as stop:
        return _stopped(a, stop.signum)
    except BrokenPipeError:  # `bag info x.bag | head`
        return 0
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _stopped(a, signum: int) -> int:
    """One line for a command stopped by a signal (what it was writing is already removed),
    and the shell's exit code for it, 128 + the signal's number: the command did not finish."""
    name = signal.Signals(signum).name
    output = getattr(a, "output", None)
    made = f"; {output} was not made" if a.command in ("convert", "reindex") and output else ""
    print(f"bag {a.command}: stopped by {name}{made}", file=sys.stderr)
    return 128 + signum


if __name__ == "__main__":
    sys.exit(main())
