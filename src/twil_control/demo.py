"""``make demo``: the paper's controller in one command.

    python -m twil_control.demo [--duration 15] [--out runs] [name:=value ...]

Runs launch/twil_cart_linearizing.launch.yaml (TWIL + WAM from (0, 0, 0) to (2, 1, pi/2), the arm
on its program; launch arguments pass through), records the bag and the view's HTML replay, then
prints ``bag report``'s summary and where the bag, the figure and the replay are.
Exit codes: 0 done, 1 the run failed (the bag is kept), 2 bad input.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
import traceback
from pathlib import Path

from . import PACKAGE_ROOT
from .errors import InputError, exit_on_error

LAUNCH = PACKAGE_ROOT / "launch/twil_cart_linearizing.launch.yaml"


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m twil_control.demo", description=(__doc__ or "").split("\n", 1)[0]
    )
    p.add_argument("args", nargs="*", metavar="name:=value", help="arguments of " + LAUNCH.name)
    p.add_argument("--duration", type=float, default=15.0, metavar="S", help="simulated seconds (default 15)")
    p.add_argument(
        "--out", type=Path, default=Path("runs"), help="folder of the bag, figure and replay (default runs/)"
    )
    p.add_argument(
        "--no-html", action="store_true", help="no HTML replay (the run is then about twice as fast)"
    )
    return p


def output_stem(folder: Path) -> Path:
    """folder/demo_DATE, with a counter if a file of that name exists (nothing is overwritten)."""
    base = f"demo_{time.strftime('%Y-%m-%d-%H-%M-%S')}"
    stem, k = folder / base, 1
    while any(folder.joinpath(stem.name + ext).exists() for ext in (".bag", ".bag.active", ".png", ".html")):
        stem, k = folder / f"{base}-{k}", k + 1
    return stem


def main(argv: list[str] | None = None) -> int:
    a = _parser().parse_args(argv)
    return exit_on_error(lambda: _demo(a))


def _demo(a: argparse.Namespace) -> int:
    from .bag.bag_errors import BagError
    from .bag.report import cart_report
    from .launch.loader import load_launch, parse_cli_args
    from .launch.logging_setup import configure_logging
    from .launch.runner import RunOptions, run
    from .launch.supervision import RequiredNodeFailed, cause_of, is_bug
    from .view.view_node import ViewOptions

    clock = configure_logging(quiet=True)
    logging.getLogger("drake").setLevel(logging.WARNING)  # Meshcat's "listening at": no page is served
    if not (a.duration > 0 and a.duration < float("inf")):
        raise InputError(f"--duration must be a positive number of seconds (got {a.duration})")
    plan = load_launch(LAUNCH, parse_cli_args(a.args))
    try:
        a.out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"--out {a.out}: cannot create the folder ({error.strerror})") from None
    stem = output_stem(a.out)
    bag, html = stem.with_suffix(".bag"), None if a.no_html else stem.with_suffix(".html")
    print(
        f"running {LAUNCH.relative_to(PACKAGE_ROOT)} for {a.duration:g} simulated s "
        f"({' '.join(a.args) or 'default arguments'}) ...",
        flush=True,
    )
    view = None if html is None else ViewOptions(serve=False, save_html=html)
    result = run(
        plan,
        RunOptions(duration=a.duration, bag=bag, view=view, progress=sys.stderr.isatty()),
        on_master=clock.attach,
    )
    print(
        f"simulated {result.sim_time:.2f} s in {result.wall_time:.1f} s of wall time "
        f"({result.realtime_factor:.2f}x real time)"
    )
    if result.error is not None:
        cause = result.error.failure.error if isinstance(result.error, RequiredNodeFailed) else result.error
        if is_bug(cause):  # not a TwilControlError: show where it happened
            traceback.print_exception(cause_of(cause))
        print(
            f"error: the run failed at t = {result.sim_time:.3f} s: {result.error}; bag kept: {result.bag}",
            file=sys.stderr,
        )
        return 1
    try:
        _, text, figure = cart_report(result.bag)
    except BagError as error:  # the run is done and its bag kept: not bad input, exit 1
        print(f"error: {error}", file=sys.stderr)
        return 1
    print()
    print(text)
    print()
    print(f"bag:    {result.bag}")
    print(f"figure: {figure}")
    if html is not None:
        print(f"replay: {html} (open it in a browser)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
