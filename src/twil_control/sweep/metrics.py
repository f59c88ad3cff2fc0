"""A run's metrics: what twil_control.bag.analyze.analyze_bag says about its bag.

The sweep computes no metrics of its own: the bag analysis is one place (the bag tools), so
a sweep table and ``python -m twil_control.bag`` agree on every number.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

from twil_control.errors import TwilControlError

ANALYZE_MODULE = "twil_control.bag.analyze"


class MetricsUnavailable(TwilControlError, RuntimeError):
    """This checkout has no twil_control.bag.analyze (runs are then recorded without metrics)."""


def analyzer_available() -> bool:
    return importlib.util.find_spec(ANALYZE_MODULE) is not None


def analyzer_options() -> tuple[str, ...] | None:
    """The option names analyze_bag declares (None when it is not available)."""
    if not analyzer_available():
        return None
    from twil_control.bag import analyze

    return tuple(getattr(analyze, "OPTIONS", ())) or None


def metrics_of(bag_path: str | Path, options: dict[str, Any]) -> dict[str, Any]:
    """analyze_bag(bag_path, **options): the metrics of one run's bag (without its "bag"
    entry, the path it was given: the table has the run's bag already)."""
    if not analyzer_available():
        raise MetricsUnavailable(
            f"{ANALYZE_MODULE} is not in this checkout: runs are "
            f"recorded (status, wall time, bag) without metrics"
        )
    from twil_control.bag.analyze import analyze_bag

    metrics = analyze_bag(Path(bag_path), **options)
    metrics.pop("bag", None)
    return metrics


def flatten(metrics: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings become dotted columns; lists stay values (stored as JSON in tables)."""
    flat: dict[str, Any] = {}
    for key, value in metrics.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            flat.update(flatten(value, name + "."))
        else:
            flat[name] = value
    return flat
