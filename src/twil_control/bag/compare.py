"""``compare``: the metrics of two runs side by side, with B - A for numbers."""

from __future__ import annotations

import math

from .analyze import analyze_bag, fmt


def flatten(metrics: dict, prefix: str = "") -> dict:
    """{'cart_controller.final_position_error_m': 0.01, 'computed_torque.rms_deviation_rad.wam_joint_1': ...}"""
    out = {}
    for k, v in metrics.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for i, row in enumerate(v):
                out.update(flatten(row, f"{key}[{i}]."))
        elif isinstance(v, list):
            out[key] = ", ".join(fmt(x) for x in v)
        else:
            out[key] = v
    return out


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def compare_bags(a, b, **options) -> dict:
    """{'a': path, 'b': path, 'metrics': {name: {'a': .., 'b': .., 'diff': B - A or None}}}."""
    ma, mb = analyze_bag(a, **options), analyze_bag(b, **options)
    fa = flatten({k: v for k, v in ma.items() if k not in ("bag", "analyses")})
    fb = flatten({k: v for k, v in mb.items() if k not in ("bag", "analyses")})
    keys = list(fa) + [k for k in fb if k not in fa]
    rows = {}
    for k in keys:
        va, vb = fa.get(k), fb.get(k)
        rows[k] = {"a": va, "b": vb, "diff": vb - va if _number(va) and _number(vb) else None}
    return {"a": str(a), "b": str(b), "metrics": rows}


def format_comparison(c: dict) -> str:
    rows = c["metrics"]
    w = max((len(k) for k in rows), default=6)
    lines = [f"A: {c['a']}", f"B: {c['b']}", "", f"{'metric':{w}s}  {'A':>12s}  {'B':>12s}  {'B - A':>12s}"]
    for k, r in rows.items():
        d = fmt(r["diff"]) if r["diff"] is not None else ("" if r["a"] == r["b"] else "differs")
        lines.append(f"{k:{w}s}  {fmt(r['a']):>12s}  {fmt(r['b']):>12s}  {d:>12s}")
    return "\n".join(lines)
