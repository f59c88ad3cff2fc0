"""``report``: a cart_linearizing_controller run in a few lines and one figure (``make demo``).

The lines and the figure's panels come from the cart analysis (analyses/cart.py), so they say
what ``bag analyze`` says (docs/analyze.md): ``metrics, text, png = cart_report(bag)``.
"""

from __future__ import annotations

import math
from pathlib import Path

from .analyses import cart
from .analyze import run_analyses
from .bag_errors import BagError
from .reader import Bag

#: (figure of the cart analysis, grid cell: row, column slice) of the report's figure
PANELS = (
    ("cart_polar", 0, slice(0, 1)),
    ("cart_path", 0, slice(1, 2)),
    ("cart_v1", 1, slice(0, 1)),
    ("cart_torques", 1, slice(1, 2)),
    ("cart_arm", 2, slice(0, 2)),
)


def cart_report(bag_path, figure_path=None, **options) -> tuple[dict, str, Path]:
    """(the cart analysis's metrics, the summary text, the figure written: `figure_path`, or
    the bag's path with .png). Raises BagError for a bag without a cart controller run."""
    bag_path = Path(bag_path)
    figure_path = Path(figure_path) if figure_path is not None else bag_path.with_suffix(".png")
    if figure_path.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise BagError(f"figure {figure_path}: the extension must be .png, .svg or .pdf")
    bag = Bag(bag_path)
    results, skipped = run_analyses(bag, {**options, "only": [cart.NAME]})
    if cart.NAME not in results:
        why = skipped.get(cart.NAME, f"no {cart.STATUS} topic")
        raise BagError(f"{bag_path}: no cart_linearizing_controller run to report ({why})")
    result = results[cart.NAME]
    write_figure(result, figure_path, f"{bag_path.name}: TWIL + WAM under cart_linearizing_controller")
    return result.metrics, summary_text(result.metrics), figure_path


def summary_text(m: dict) -> str:
    """The run in seven lines."""
    goal = (
        f"goal ({m['reference_x_m']:.3g} m, {m['reference_y_m']:.3g} m, "
        f"{math.degrees(m['reference_theta_rad']):.1f} deg) commanded at t = {m['reference_time_s']:.2f} s"
    )
    lines = [goal]

    def error(source: str, suffix: str) -> None:
        if f"final_position_error{suffix}_m" in m:
            converge = m[f"converge_time{suffix}_s"]
            tol = m["converge_tolerance"].replace(", ", " and ")
            lines.append(
                f"  final error against {source}: {100 * m[f'final_position_error{suffix}_m']:.2f} cm, "
                f"{m[f'final_heading_error{suffix}_deg']:.2f} deg; "
                + (
                    f"within {tol} from {converge:.2f} s after the command"
                    if converge is not None
                    else f"not within {tol} at the end"
                )
            )

    error("the simulator's truth", "")
    error("the odometry", "_odometry")
    if "V1_final" in m:
        lines.append(
            f"  Lyapunov V1: {m['V1_at_reference']:.4g} at the command, {m['V1_final']:.3g} at the end"
        )
    if "arm_rms_error_rad" in m:
        worst = max(m["arm_rms_error_rad"], key=m["arm_rms_error_rad"].get)
        lines.append(
            f"  arm RMS tracking error: {m['arm_rms_error_all_joints_rad']:.2g} rad over "
            f"{len(m['arm_rms_error_rad'])} joints (largest {worst}, {m['arm_rms_error_rad'][worst]:.2g} rad)"
        )
    lines.append(
        f"  peak wheel torques: right {m['peak_tau_right_Nm']:.2f} N m, left {m['peak_tau_left_Nm']:.2f} N m; "
        f"scaled to the limit for {m['torque_scaled_s']:.2f} s"
    )
    return "\n".join(lines)


def write_figure(result, path: Path, title: str) -> Path:
    """The analysis's figures named in PANELS on one page."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figures = {f.name: f for f in result.figures}
    fig = plt.figure(figsize=(13, 14), layout="constrained")
    grid = fig.add_gridspec(3, 2, height_ratios=[1.3, 1.0, 1.1])
    try:
        for name, row, cols in PANELS:
            if name in figures:
                sub = fig.add_subfigure(grid[row, cols])
                figures[name].draw(sub)
                sub.suptitle(figures[name].title, fontsize=10)
        fig.suptitle(title, fontsize=12)
        fig.savefig(path, dpi=80)
    finally:
        plt.close(fig)
    return path
