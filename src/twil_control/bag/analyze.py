"""``analyze``: find what a bag holds and compute the metrics that apply to it.

    metrics = analyze_bag("map.bag", ground_truth_map="sim/maps/house.yaml")

Each analysis in ``analyses/`` detects itself from topic names and types and reads only the
topics it needs, so one command serves every launch. The result, the options and what each
analysis measures: docs/analyze.md. ``write_report`` adds the figures (Markdown with PNGs, or
one self-contained HTML file).
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path

from .analyses import cart, computed_torque_tracking, mapping, navigation, odometry
from .analyses.common import AnalysisSkipped, Result
from .bag_errors import BagError
from .output import check_new_output, open_new
from .reader import Bag

ANALYSES = (cart, computed_torque_tracking, odometry, mapping, navigation)
NAMES = tuple(a.NAME for a in ANALYSES)
OPTIONS = (
    "ground_truth_map",
    "wn",
    "arm_joints",
    "joints",
    "position_tolerance",
    "heading_tolerance_deg",
    "base_frame",
    "odom_frame",
    "map_frame",
    "only",
    "reference_timeout",
    "effort_limits",
)


def _check_options(options: dict) -> None:
    unknown = [k for k in options if k not in OPTIONS]
    if unknown:
        raise BagError(f"unknown analyze option(s) {', '.join(unknown)}; allowed: {', '.join(OPTIONS)}")
    for name in options.get("only") or ():
        if name not in NAMES:
            raise BagError(f"unknown analysis '{name}'; the analyses: {', '.join(NAMES)}")
    wn = options.get("wn")
    if wn is not None and not (wn > 0 and math.isfinite(wn)):
        raise BagError(f"wn must be a positive number of rad/s (got {wn})")
    gt = options.get("ground_truth_map")
    if gt is not None and not Path(gt).is_file():
        raise BagError(f"ground-truth map {gt}: no such file")


def run_analyses(bag: Bag, options: dict) -> tuple[dict[str, Result], dict[str, str]]:
    """(results of the analyses that ran, {name: reason} of those that could not)."""
    _check_options(options)
    only = options.get("only")
    results, skipped = {}, {}
    for a in ANALYSES:
        if only and a.NAME not in only:
            continue
        topics = a.detect(bag)
        if topics is None:
            continue
        try:
            results[a.NAME] = a.analyze(bag, topics, options)
        except AnalysisSkipped as why:
            skipped[a.NAME] = str(why)
    return results, skipped


def _summary(bag: Bag, results: dict[str, Result], skipped: dict[str, str]) -> dict:
    out = {"bag": str(bag.path), "duration_s": (bag.end_ns - bag.start_ns) * 1e-9, "analyses": list(results)}
    for name, r in results.items():
        out[name] = r.metrics
    if skipped:
        out["skipped"] = skipped
    return out


def analyze_bag(path, **options) -> dict:
    """The metrics of every analysis that applies to the bag (docs/analyze.md)."""
    bag = Bag(path)
    results, skipped = run_analyses(bag, options)
    return _summary(bag, results, skipped)


def to_json(metrics: dict) -> str:
    return json.dumps(metrics, indent=2, default=_json_default)


def _json_default(x):
    if hasattr(x, "item"):
        return x.item()
    raise TypeError(f"cannot write {type(x).__name__} as JSON")


# -- text ---------------------------------------------------------------------------------
def fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list) and v and not isinstance(v[0], dict):
        return ", ".join(fmt(x) for x in v)
    return str(v)


def format_text(summary: dict) -> str:
    lines = [f"bag: {summary['bag']} ({summary['duration_s']:.2f} s)"]
    if not summary["analyses"] and not summary.get("skipped"):
        lines.append(
            "no analysis applies: the bag has none of the topics of "
            + ", ".join(NAMES)
            + " (see python -m twil_control.bag analyze --help)"
        )
    for name in summary["analyses"]:
        lines.append(f"\n[{name}]")
        lines.extend(_metric_lines(summary[name]))
    for name, why in summary.get("skipped", {}).items():
        lines.append(f"\n[{name}] not analysed: {why}")
    return "\n".join(lines)


def _metric_lines(metrics: dict) -> list[str]:
    out = []
    width = max((len(k) for k in metrics), default=0)
    for k, v in metrics.items():
        if isinstance(v, dict):
            out.append(f"  {k}:")
            out.extend(f"    {kk:16s} {fmt(vv)}" for kk, vv in v.items())
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            cols = list(v[0])
            out.append(f"  {k}:")
            out.append("    " + " | ".join(cols))
            out.extend("    " + " | ".join(fmt(r.get(c)) for c in cols) for r in v)
        else:
            out.append(f"  {k:{width}s}  {fmt(v)}")
    return out


# -- reports ------------------------------------------------------------------------------
REPORT_FORMATS = (".md", ".html")


def check_report_path(out, force: bool = False) -> Path:
    out = Path(out)
    if out.suffix.lower() not in REPORT_FORMATS:
        raise BagError(
            f"report {out}: the extension must be .md (Markdown + PNG files) or .html "
            f"(one self-contained file), got '{out.suffix or 'none'}'"
        )
    check_new_output(out, "report", force)
    if out.suffix.lower() == ".md":  # its figures go beside it
        check_new_output(_files_dir(out), "report figures folder", force)
    return out


def _files_dir(out: Path) -> Path:
    return out.with_name(out.stem + "_files")


def _png(figure) -> bytes:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(8, 4.5))
    try:
        figure.draw(fig)
        fig.suptitle(figure.title, fontsize=10)
        fig.tight_layout()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        return buf.getvalue()
    finally:
        plt.close(fig)


def write_report(path, out, force: bool = False, **options) -> tuple[dict, Path]:
    """Analyse the bag and write a Markdown (+ PNGs in OUT_files/) or HTML report; existing
    files are replaced only with force."""
    out = check_report_path(out, force)
    bag = Bag(path)
    results, skipped = run_analyses(bag, options)
    summary = _summary(bag, results, skipped)
    html_mode = out.suffix.lower() == ".html"
    parts = [
        f"# Bag analysis: {bag.path.name}",
        "",
        f"`{bag.path}`, {summary['duration_s']:.2f} s, {bag.message_count} messages on "
        f"{len(bag.topics)} topics. Analyses: {', '.join(results) or 'none applies'}.",
        "",
    ]
    files_dir = _files_dir(out)
    body_html = []
    for name, r in results.items():
        parts += [f"## {name}", "", "| metric | value |", "|---|---|"]
        for k, v in r.metrics.items():
            if isinstance(v, dict):
                for kk, vv in v.items():
                    parts.append(f"| {k} [{kk}] | {fmt(vv)} |")
            elif isinstance(v, list) and v and isinstance(v[0], dict):
                continue
            else:
                parts.append(f"| {k} | {fmt(v)} |")
        for k, v in r.metrics.items():
            if isinstance(v, list) and v and isinstance(v[0], dict):
                cols = list(v[0])
                parts += ["", f"**{k}**", "", "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
                parts += ["| " + " | ".join(fmt(row.get(c)) for c in cols) + " |" for row in v]
        parts += [""] + [f"_{n}_" for n in r.notes] + [""]
        for fig in r.figures:
            png = _png(fig)
            if html_mode:
                parts.append(f"@@FIG {len(body_html)}")
                body_html.append((fig.title, base64.b64encode(png).decode()))
            else:
                files_dir.mkdir(exist_ok=True)
                with open_new(files_dir / f"{fig.name}.png", force) as f:
                    f.write(png)
                parts += [f"![{fig.title}]({files_dir.name}/{fig.name}.png)", ""]
    for name, why in skipped.items():
        parts += [f"## {name}", "", f"Not analysed: {why}", ""]
    text = _markdown_to_html(parts, body_html, bag.path.name) if html_mode else "\n".join(parts) + "\n"
    with open_new(out, force, "w") as f:
        f.write(text)
    return summary, out


def _markdown_to_html(lines: list[str], figures: list, title: str) -> str:
    """The report's few Markdown constructs (headings, tables, emphasis) as HTML."""
    body, table = [], []

    def flush():
        if table:
            rows = [r for r in table if not set(r.replace("|", "")) <= {"-"}]
            cells = [[html.escape(c.strip()) for c in r.strip("|").split("|")] for r in rows]
            body.append(
                "<table>"
                + "".join(
                    "<tr>"
                    + "".join(f"<{'th' if i == 0 else 'td'}>{c}</{'th' if i == 0 else 'td'}>" for c in row)
                    + "</tr>"
                    for i, row in enumerate(cells)
                )
                + "</table>"
            )
            table.clear()

    for line in lines:
        if line.startswith("|"):
            table.append(line)
            continue
        flush()
        if line.startswith("@@FIG "):
            cap, data = figures[int(line.split()[1])]
            body.append(
                f'<figure><img alt="{html.escape(cap)}" src="data:image/png;base64,{data}">'
                f"<figcaption>{html.escape(cap)}</figcaption></figure>"
            )
        elif line.startswith("## "):
            body.append(f"<h2>{html.escape(line[3:])}</h2>")
        elif line.startswith("# "):
            body.append(f"<h1>{html.escape(line[2:])}</h1>")
        elif line.strip():
            body.append(f"<p>{html.escape(line.strip('_*`'))}</p>")
    flush()
    style = (
        "body{font-family:sans-serif;max-width:60em;margin:2em auto}table{border-collapse:collapse}"
        "td,th{border:1px solid #ccc;padding:2px 8px;text-align:left}img{max-width:100%}"
    )
    return (
        f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
        f"<style>{style}</style></head><body>" + "\n".join(body) + "</body></html>\n"
    )
