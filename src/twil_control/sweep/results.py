"""The sweep's table (CSV + Parquet), its printed summary and its plots.

One row per run in sweep order: run id, index, status (ok / failed / timeout / pending),
error text, wall time, bag path, every launch arg, duration and seed, then the metrics
(nested metrics flattened to dotted names; list-valued ones stored as JSON text).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pandas as pd

from .metrics import flatten
from .runs import Run

BASE_COLUMNS = ["run_id", "index", "status", "error", "wall_time", "bag"]
PENDING = "pending"
#: Metrics the printed summary lists at most.
MAX_SHOWN = 12


def table(runs: list[Run], records: dict[str, dict]) -> tuple[pd.DataFrame, list[str]]:
    """(the table, the metric column names). Runs without a record are 'pending'."""
    arg_names: list[str] = []
    for run in runs:
        for name in list(run.args) + ["duration", "seed"]:
            if name not in arg_names:
                arg_names.append(name)
    rows, metric_names = [], []
    for run in runs:
        rec = records.get(run.run_id)
        row: dict[str, Any] = {
            "run_id": run.run_id,
            "index": run.index,
            "status": rec["status"] if rec else PENDING,
            "error": rec.get("error") if rec else None,
            "wall_time": rec.get("wall_time") if rec else None,
            "bag": rec.get("bag") if rec else None,
        }
        row.update(run.args)
        row["duration"], row["seed"] = run.duration, run.seed
        for name, value in flatten((rec or {}).get("metrics") or {}).items():
            column = name if name not in row else f"metric.{name}"  # never hide an arg
            if column not in metric_names:
                metric_names.append(column)
            row[column] = json.dumps(value) if isinstance(value, (list, dict)) else value
        rows.append(row)
    columns = BASE_COLUMNS + arg_names + metric_names
    return pd.DataFrame(rows, columns=columns), metric_names


def write_table(frame: pd.DataFrame, out_dir: Path) -> tuple[Path, Path]:
    csv, parquet = out_dir / "results.csv", out_dir / "results.parquet"
    frame.to_csv(csv, index=False)
    _parquet_safe(frame).to_parquet(parquet, index=False)
    return csv, parquet


def _parquet_safe(frame: pd.DataFrame) -> pd.DataFrame:
    """Parquet columns have one type: a column mixing numbers and text is stored as text."""
    out = frame.copy()
    for column in out.columns:
        values = out[column].dropna()
        if out[column].dtype == object and len({_kind(v) for v in values}) > 1:
            out[column] = out[column].map(lambda v: None if _missing(v) else str(v))
    return out


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    return type(value).__name__


def _missing(value: Any) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def numeric_columns(frame: pd.DataFrame, names: list[str]) -> list[str]:
    return [
        n
        for n in names
        if n in frame and pd.api.types.is_numeric_dtype(frame[n]) and not pd.api.types.is_bool_dtype(frame[n])
    ]


def summary(
    frame: pd.DataFrame,
    metric_names: list[str],
    varied: list[str],
    objective: tuple[str, str] | None,
    shown: list[str] | None = None,
) -> str:
    """Counts per status, mean/min/max over ok runs of the ``shown`` metrics (default: the
    objective's and every numeric metric that varies; at most MAX_SHOWN), the best run."""
    counts = frame["status"].value_counts()
    lines = [
        f"runs: {len(frame)}  "
        + "  ".join(
            f"{s}: {int(counts.get(s, 0))}"
            for s in ("ok", "failed", "timeout", PENDING)
            if counts.get(s, 0) or s == "ok"
        )
    ]
    ok = frame[frame["status"] == "ok"]
    numeric = numeric_columns(ok, metric_names)
    if shown is None:
        shown = plotted_metrics(frame, metric_names, None)
    if objective and objective[0] in numeric:
        shown = [objective[0]] + [m for m in shown if m != objective[0]]
    if shown:
        width = max(len(n) for n in shown[:MAX_SHOWN])
        lines.append(
            f"{'metric':<{width}}  {'mean':>12} {'min':>12} {'max':>12}  "
            f"(over ok runs; all metrics are in the table)"
        )
        for name in shown[:MAX_SHOWN]:
            col = ok[name].dropna()
            stats = (
                f"{col.mean():>12.6g} {col.min():>12.6g} {col.max():>12.6g}"
                if len(col)
                else f"{'-':>12} {'-':>12} {'-':>12}"
            )
            lines.append(
                f"{name:<{width}}  {stats}"
                + (f"  ({len(col)} of {len(ok)} runs)" if len(col) < len(ok) else "")
            )
        if len(shown) > MAX_SHOWN:
            lines.append(f"... and {len(shown) - MAX_SHOWN} more metrics")
    elif not metric_names:
        lines.append("no metrics recorded")
    if objective:
        lines.append(best_run_text(frame, objective, varied))
    failed = frame[frame["status"].isin(["failed", "timeout"])]
    for _, row in failed.head(5).iterrows():
        first = (row["error"] or "").strip().splitlines()
        lines.append(f"{row['status']} run {row['index']} ({row['run_id']}): {first[0] if first else ''}")
    if len(failed) > 5:
        lines.append(f"... and {len(failed) - 5} more failed (see the 'error' column)")
    return "\n".join(lines)


def best_run(frame: pd.DataFrame, objective: tuple[str, str]) -> pd.Series | None:
    metric, goal = objective
    if metric not in frame:
        return None
    ok = frame[(frame["status"] == "ok") & frame[metric].notna()]
    if ok.empty or not pd.api.types.is_numeric_dtype(ok[metric]):
        return None
    return ok.loc[ok[metric].idxmin() if goal == "min" else ok[metric].idxmax()]


def best_run_text(frame: pd.DataFrame, objective: tuple[str, str], varied: list[str]) -> str:
    metric, goal = objective
    row = best_run(frame, objective)
    if row is None:
        have = "no ok run has it" if metric in frame else "no run has this metric"
        return f"best ({goal} {metric}): none ({have})"
    args = ", ".join(f"{n}={row[n]}" for n in varied if n in row)
    return f"best ({goal} {metric}): run {row['index']} ({row['run_id']}) {metric}={row[metric]:.6g}; {args}"


def plotted_metrics(
    frame: pd.DataFrame, metric_names: list[str], chosen: tuple[str, ...] | None
) -> list[str]:
    """The chosen metrics that are numeric, else every numeric metric that varies over the
    ok runs (a constant one, such as a configured value echoed back, says nothing)."""
    ok = frame[frame["status"] == "ok"]
    numeric = numeric_columns(ok, metric_names)
    if chosen is not None:
        return [m for m in chosen if m in numeric]
    return [m for m in numeric if ok[m].dropna().nunique() > 1]


def plot(frame: pd.DataFrame, metrics: list[str], varied: list[str], out_dir: Path) -> list[Path]:
    """One PNG per metric: the metric against each varied arg (ok runs)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = frame[frame["status"] == "ok"]
    paths = []
    out_dir.mkdir(parents=True, exist_ok=True)
    for metric in metrics:
        fig, axes = plt.subplots(1, len(varied), figsize=(4.2 * len(varied), 3.4), squeeze=False)
        for ax, arg in zip(axes[0], varied):
            x = ok[arg]
            if pd.api.types.is_numeric_dtype(x) and not pd.api.types.is_bool_dtype(x):
                ax.plot(x, ok[metric], "o", alpha=0.8)
            else:  # text or booleans: one position per distinct value
                labels = sorted({str(v) for v in x})
                ax.plot([labels.index(str(v)) for v in x], ok[metric], "o", alpha=0.8)
                ax.set_xticks(range(len(labels)), labels)
            ax.set_xlabel(arg)
            ax.set_ylabel(metric)
            ax.grid(True, alpha=0.3)
        valued = int(ok[metric].notna().sum())
        fig.suptitle(f"{metric}: {valued} of {len(frame)} runs (ok and with a value)")
        fig.tight_layout()
        path = out_dir / f"{_file_name(metric)}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        paths.append(path)
    return paths


def _file_name(metric: str) -> str:
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in metric)
