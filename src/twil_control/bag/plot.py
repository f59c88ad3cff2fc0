"""``plot`` and ``xy``: rqt_plot's time series and path plots of a bag's numeric fields.

Fields are named as in rqt_plot: ``/topic/field/sub[i]`` (``/joint_states/position[3]``,
``/twil/odom/pose/pose/position/x``); '.' works as the separator too. An ``xy`` curve is
``X_FIELD:Y_FIELD``; when the two come from different topics Y is interpolated at X's times.
The format follows the output's extension (png, svg, pdf).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .bag_errors import BagError
from .output import check_new_output, open_new
from .reader import Bag, resolve_spec

FORMATS = (".png", ".svg", ".pdf")


def check_output(path: Path | str, force: bool = False) -> Path:
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise BagError(
            f"output {path}: the extension must be one of {', '.join(FORMATS)} "
            f"(got '{path.suffix or 'none'}')"
        )
    return check_new_output(path, "output", force)


def _save(fig, out: Path, force: bool) -> None:
    with open_new(out, force) as f:
        fig.savefig(f, format=out.suffix[1:].lower(), dpi=110)


def series(bag: Bag, spec: str) -> tuple[np.ndarray, np.ndarray]:
    """(seconds since the bag's start, values) of one rqt_plot field spec."""
    topic, field = resolve_spec(bag, spec)
    t, cols = bag.columns(topic, [field])
    return (t - bag.start_ns) * 1e-9, cols[field]


def _figure(rows: int = 1, height: float = 3.5, **kw):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt.subplots(rows, 1, figsize=(9, 1.0 + height * rows), squeeze=False, **kw)


def plot_fields(
    bag: Bag,
    specs: list[str],
    out: Path | str,
    subplots: bool = False,
    title: str | None = None,
    force: bool = False,
) -> Path:
    """Time series of the fields, on one axes (or one per field with subplots)."""
    out = check_output(out, force)
    data = [(s, *series(bag, s)) for s in specs]
    fig, axes = _figure(len(specs) if subplots else 1, 2.5 if subplots else 4.0, sharex=True)
    for i, (spec, t, v) in enumerate(data):
        ax = axes[i if subplots else 0, 0]
        ax.plot(t, v, label=spec, lw=1.2)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1, 0].set_xlabel(f"time since bag start (s)   [{bag.path.name}]")
    fig.suptitle(title or ", ".join(specs) if len(specs) < 4 else (title or bag.path.name), fontsize=10)
    fig.tight_layout()
    _save(fig, out, force)
    _close(fig)
    return out


def xy_pair(bag: Bag, pair: str) -> tuple[np.ndarray, np.ndarray]:
    """x and y values of an 'X_FIELD:Y_FIELD' pair (Y interpolated at X's times when the
    fields come from different topics)."""
    if pair.count(":") != 1:
        raise BagError(
            f"xy curve '{pair}' must be X_FIELD:Y_FIELD (one ':'), e.g. "
            "/twil/odom/pose/pose/position/x:/twil/odom/pose/pose/position/y"
        )
    xs, ys = pair.split(":")
    tx, fx = resolve_spec(bag, xs)
    ty, fy = resolve_spec(bag, ys)
    if tx == ty:
        _, cols = bag.columns(tx, [fx, fy])
        return cols[fx], cols[fy]
    t1, c1 = bag.columns(tx, [fx])
    t2, c2 = bag.columns(ty, [fy])
    if len(t2) == 0 or len(t1) == 0:
        return np.zeros(0), np.zeros(0)
    inside = (t1 >= t2[0]) & (t1 <= t2[-1])
    return c1[fx][inside], np.interp(t1[inside], t2, c2[fy])


def plot_xy(
    bag: Bag, pairs: list[str], out: Path | str, title: str | None = None, force: bool = False
) -> Path:
    """Curves y(x) with equal axis scales (a platform's path), start and end marked."""
    out = check_output(out, force)
    fig, axes = _figure(1, 6.0)
    ax = axes[0, 0]
    for pair in pairs:
        x, y = xy_pair(bag, pair)
        (line,) = ax.plot(x, y, lw=1.4, label=pair)
        if len(x):
            ax.plot(x[0], y[0], "o", color=line.get_color(), ms=5)
            ax.plot(x[-1], y[-1], "s", color=line.get_color(), ms=5)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=7)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_title(title or f"{bag.path.name} (o start, s end)", fontsize=10)
    fig.tight_layout()
    _save(fig, out, force)
    _close(fig)
    return out


def _close(fig) -> None:
    import matplotlib.pyplot as plt

    plt.close(fig)
