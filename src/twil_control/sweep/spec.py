"""The sweep file: which launch, which fixed args, which varied args, how each run is judged.

YAML, loaded safely, with exactly one of ``grid`` (cartesian product), ``list`` (explicit runs)
or ``random`` (seeded samples) naming the varied args; the format is in docs/sweeps.md and
config/sweeps/. Every mistake is a SweepError naming the file, line and key.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from twil_control.core.node import check_seed
from twil_control.core.paths import InputPathError, find_file
from twil_control.core.yaml_io import Lines, YamlError, display_path, load_yaml_with_lines
from twil_control.errors import TwilControlError

#: Keys a sweep file may have, with what each is for (shown when a key is unknown).
KEYS = {
    "description": "free text",
    "launch": "launch file (relative to the package root)",
    "args": "fixed launch args {name: value}",
    "duration": "simulated seconds per run",
    "seed": "--seed per run",
    "timeout": "wall seconds per run",
    "grid": "varied args, cartesian product",
    "list": "varied args, explicit runs",
    "random": "varied args, seeded samples",
    "metrics": "options of analyze_bag",
    "objective": "{metric, goal: min|max}",
    "plots": "metrics to plot (default: every numeric metric that varies)",
}
VARIATIONS = ("grid", "list", "random")
#: Varied names that are run options rather than launch-file args.
RUN_OPTIONS = ("duration", "seed")
DISTRIBUTIONS = ("uniform", "log_uniform", "choice")
DEFAULT_TIMEOUT = 3600.0

Scalar = str | int | float | bool


class SweepError(TwilControlError, ValueError):
    """A sweep file that cannot be run; the message names the file, line and key."""


@dataclass(frozen=True)
class Sweep:
    """A validated sweep file."""

    path: Path
    launch: Path  # absolute
    fixed: dict[str, Scalar]  # fixed launch args
    varied_names: tuple[str, ...]  # varied names in file order (launch args, duration, seed)
    points: tuple[dict[str, Scalar], ...]  # one mapping of varied values per run
    duration: float | None
    seed: int
    timeout: float
    metrics: dict[str, Any] = field(default_factory=dict)
    objective: tuple[str, str] | None = None  # (metric, "min" | "max")
    plots: tuple[str, ...] | None = None  # None: every numeric metric that varies

    @property
    def name(self) -> str:
        return self.path.name.split(".")[0]


class _Reader:
    """Error messages that point at ``file:line: key``."""

    def __init__(self, path: Path, lines: Lines) -> None:
        self.label = display_path(path)
        self.lines = lines

    def fail(self, keys: tuple, message: str) -> SweepError:
        line = None
        for n in range(len(keys), -1, -1):  # the nearest enclosing key that has a line
            if keys[:n] in self.lines:
                line = self.lines[keys[:n]]
                break
        where = f"{self.label}:{line}" if line else self.label
        key = ".".join(str(k) for k in keys)
        return SweepError(f"{where}: {('key ' + repr(key) + ': ') if key else ''}{message}")


def load_sweep(path: str | Path) -> Sweep:
    """Read and check a sweep file; the launch file's declared args are checked too."""
    path = Path(path).absolute()
    try:
        data, lines = load_yaml_with_lines(path)
    except YamlError as exc:
        raise SweepError(str(exc)) from None
    r = _Reader(path, lines)
    if not isinstance(data, dict):
        raise r.fail(
            (), f"a sweep file is a mapping with at least 'launch' and one of {', '.join(VARIATIONS)}"
        )
    for key in data:
        if key not in KEYS:
            allowed = "; ".join(f"{k} ({v})" for k, v in KEYS.items())
            raise r.fail((key,), f"unknown key; allowed keys: {allowed}")
    launch = _launch(r, data)
    declared = _declared_args(r, launch)
    fixed = _fixed_args(r, data.get("args", {}), declared)
    given = [k for k in VARIATIONS if k in data]
    if len(given) != 1:
        raise r.fail(
            (given[1],) if len(given) > 1 else (),
            f"give exactly one of {', '.join(VARIATIONS)} (found {', '.join(given) or 'none'})",
        )
    kind = given[0]
    names, points = {"grid": _grid, "list": _list, "random": _random}[kind](r, data[kind])
    for name in names:
        if name in fixed:
            raise r.fail((kind, name), f"{name!r} is both fixed (in 'args') and varied")
        if name not in RUN_OPTIONS and name not in declared:
            raise r.fail((kind, name), _unknown_arg(name, launch, declared))
        if name in RUN_OPTIONS and name in data:
            raise r.fail((name,), f"{name!r} is varied in {kind!r}; remove the fixed value")
    for i, point in enumerate(points):
        _check_run_options(r, point, (kind, i))
    duration = _number(r, data, "duration", positive=True)
    seed = data.get("seed", 0)
    try:
        check_seed(seed, "seed")
    except ValueError as error:
        raise r.fail(("seed",), str(error)) from None
    timeout = _number(r, data, "timeout", positive=True)
    metrics = _metric_options(r, data.get("metrics", {}) or {})
    plots = data.get("plots")
    if plots is not None and (
        not isinstance(plots, list) or not plots or not all(isinstance(m, str) for m in plots)
    ):
        raise r.fail(("plots",), f"must be a non-empty list of metric names (got {plots!r})")
    return Sweep(
        path=path,
        launch=launch,
        fixed=fixed,
        varied_names=tuple(names),
        points=tuple(points),
        duration=duration,
        seed=seed,
        timeout=timeout if timeout is not None else DEFAULT_TIMEOUT,
        metrics=dict(metrics),
        objective=_objective(r, data.get("objective")),
        plots=tuple(plots) if plots else None,
    )


def _launch(r: _Reader, data: dict) -> Path:
    if "launch" not in data:
        raise r.fail((), "missing key 'launch' (the launch file every run starts)")
    value = data["launch"]
    if not isinstance(value, str) or not value.strip():
        raise r.fail(("launch",), f"must be a launch file path (got {value!r})")
    try:
        return find_file(value, "launch file")
    except InputPathError as error:
        raise r.fail(("launch",), str(error)) from None


def _declared_args(r: _Reader, launch: Path) -> set[str]:
    from twil_control.launch.loader import declared_args  # the launch loader's own reading

    try:
        return set(declared_args(launch))
    except Exception as exc:  # a broken launch file: say so before anything runs
        raise r.fail(("launch",), f"cannot read the launch file: {exc}") from None


def _unknown_arg(name: str, launch: Path, declared: set[str]) -> str:
    return (
        f"{name!r} is not an arg of {display_path(launch)} (declared: "
        f"{', '.join(sorted(declared)) or 'none'}) nor a run option "
        f"({', '.join(RUN_OPTIONS)})"
    )


def _fixed_args(r: _Reader, raw: Any, declared: set[str]) -> dict[str, Scalar]:
    if not isinstance(raw, dict):
        raise r.fail(("args",), f"must be a mapping {{name: value}} (got {type(raw).__name__})")
    for name, value in raw.items():
        if name in RUN_OPTIONS:
            raise r.fail(
                ("args", name), f"{name!r} is a run option: write it as a top-level key, not a launch arg"
            )
        if name not in declared:
            raise r.fail(
                ("args", name),
                f"{name!r} is not declared by the launch file (declared: {', '.join(sorted(declared))})",
            )
        _scalar(r, value, ("args", name))
    return dict(raw)


def _scalar(r: _Reader, value: Any, keys: tuple) -> Scalar:
    if value is None or not isinstance(value, (str, int, float, bool)):
        raise r.fail(keys, f"an arg value must be a string, number or boolean (got {value!r})")
    if isinstance(value, float) and not math.isfinite(value):
        raise r.fail(keys, f"must be a finite number (got {value!r})")
    return value


def _grid(r: _Reader, raw: Any) -> tuple[list[str], list[dict]]:
    if not isinstance(raw, dict) or not raw:
        raise r.fail(("grid",), "must be a non-empty mapping {arg: [values]}")
    axes = {name: _axis(r, spec, ("grid", name)) for name, spec in raw.items()}
    names = list(axes)
    points = [dict(zip(names, combo)) for combo in itertools.product(*axes.values())]
    return names, points


def _axis(r: _Reader, spec: Any, keys: tuple) -> list[Scalar]:
    """A grid axis: a list of values, {range: [start, stop(, step)]} or {linspace: [a, b, n]}."""
    if isinstance(spec, list):
        if not spec:
            raise r.fail(keys, "empty list of values; give at least one")
        return [_scalar(r, v, keys + (i,)) for i, v in enumerate(spec)]
    if isinstance(spec, dict) and len(spec) == 1:
        ((how, bounds),) = spec.items()
        ints = isinstance(bounds, list) and all(
            isinstance(b, int) and not isinstance(b, bool) for b in bounds
        )
        if how == "range" and ints and len(bounds) in (2, 3):
            values = list(range(*bounds))
            if not values:
                raise r.fail(keys + ("range",), f"range {bounds} is empty")
            return values
        if (
            how == "linspace"
            and isinstance(bounds, list)
            and len(bounds) == 3
            and all(_is_number(b) for b in bounds)
            and _ints_only(bounds[2:])
            and bounds[2] >= 1
        ):
            return [float(v) for v in np.linspace(bounds[0], bounds[1], bounds[2])]
    raise r.fail(
        keys,
        f"a grid axis is a list of values, {{range: [start, stop, step?]}} "
        f"(integers) or {{linspace: [first, last, count]}} (got {spec!r})",
    )


def _ints_only(values: list) -> bool:
    return all(isinstance(v, int) and not isinstance(v, bool) for v in values)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _list(r: _Reader, raw: Any) -> tuple[list[str], list[dict]]:
    if isinstance(raw, dict):  # zipped: {a: [1, 2], b: [3, 4]} -> (1, 3), (2, 4)
        if not raw:
            raise r.fail(("list",), "empty mapping; give {arg: [values]} of equal lengths")
        lengths = set()
        for name, values in raw.items():
            if not isinstance(values, list) or not values:
                raise r.fail(("list", name), f"must be a non-empty list of values (got {values!r})")
            lengths.add(len(values))
        if len(lengths) != 1:
            sizes = ", ".join(f"{n}: {len(v)}" for n, v in raw.items())
            raise r.fail(("list",), f"zipped lists must have equal lengths ({sizes})")
        names = list(raw)
        points = [{n: _scalar(r, raw[n][i], ("list", n, i)) for n in names} for i in range(lengths.pop())]
        return names, points
    if not isinstance(raw, list) or not raw:
        raise r.fail(
            ("list",),
            "must be a non-empty list of {arg: value} mappings, or a mapping of equal-length lists (zipped)",
        )
    names: list[str] = []
    for i, point in enumerate(raw):
        if not isinstance(point, dict) or not point:
            raise r.fail(("list", i), f"each run is a non-empty mapping {{arg: value}} (got {point!r})")
        for name, value in point.items():
            _scalar(r, value, ("list", i, name))
            if name not in names:
                names.append(name)
    return names, [dict(p) for p in raw]


def _random(r: _Reader, raw: Any) -> tuple[list[str], list[dict]]:
    if not isinstance(raw, dict):
        raise r.fail(("random",), "must be a mapping {seed, count, args}")
    for key in raw:
        if key not in ("seed", "count", "args"):
            raise r.fail(("random", key), "unknown key; allowed: seed, count, args")
    for key in ("seed", "count", "args"):
        if key not in raw:
            raise r.fail(("random",), f"missing key {key!r} (random needs seed, count and args)")
    seed, count, dists = raw["seed"], raw["count"], raw["args"]
    try:
        check_seed(seed, "seed")
    except ValueError as error:
        raise r.fail(("random", "seed"), str(error)) from None
    if not _ints_only([count]) or count < 1:
        raise r.fail(("random", "count"), f"must be an integer >= 1 (got {count!r})")
    if not isinstance(dists, dict) or not dists:
        raise r.fail(("random", "args"), "must be a non-empty mapping {arg: {distribution: ...}}")
    samplers = {name: _distribution(r, spec, ("random", "args", name)) for name, spec in dists.items()}
    rng = np.random.default_rng(seed)
    points = [{name: draw(rng) for name, draw in samplers.items()} for _ in range(count)]
    return list(samplers), points


def _distribution(r: _Reader, spec: Any, keys: tuple):
    """A sampler rng -> value for {uniform: [lo, hi]}, {log_uniform: [lo, hi]}, {choice: [...]}."""
    if not isinstance(spec, dict) or len(spec) != 1 or next(iter(spec)) not in DISTRIBUTIONS:
        raise r.fail(
            keys,
            f"a distribution is one of {{uniform: [low, high]}}, "
            f"{{log_uniform: [low, high]}} (low > 0), {{choice: [values]}} "
            f"(got {spec!r})",
        )
    ((kind, value),) = spec.items()
    keys = keys + (kind,)
    if kind == "choice":
        if not isinstance(value, list) or not value:
            raise r.fail(keys, "must be a non-empty list of values")
        choices = [_scalar(r, v, keys + (i,)) for i, v in enumerate(value)]
        return lambda rng: choices[int(rng.integers(len(choices)))]
    if not (
        isinstance(value, list)
        and len(value) == 2
        and all(_is_number(v) for v in value)
        and value[0] < value[1]
    ):
        raise r.fail(keys, f"must be [low, high] with low < high (got {value!r})")
    low, high = float(value[0]), float(value[1])
    if kind == "uniform":
        return lambda rng: float(rng.uniform(low, high))
    if low <= 0:
        raise r.fail(keys, f"log_uniform needs low > 0 (got {low})")
    return lambda rng: float(math.exp(rng.uniform(math.log(low), math.log(high))))


def _check_run_options(r: _Reader, point: dict, keys: tuple) -> None:
    if "duration" in point and not (_is_number(point["duration"]) and point["duration"] > 0):
        raise r.fail(
            keys + ("duration",), f"duration must be a positive number of seconds (got {point['duration']!r})"
        )
    if "seed" in point:
        try:
            check_seed(point["seed"], "seed")
        except ValueError as error:
            raise r.fail(keys + ("seed",), str(error)) from None


def _number(r: _Reader, data: dict, key: str, positive: bool) -> float | None:
    if key not in data:
        return None
    value = data[key]
    if not _is_number(value) or (positive and value <= 0):
        raise r.fail((key,), f"must be a positive number of seconds (got {value!r})")
    return float(value)


def _metric_options(r: _Reader, raw: Any) -> dict[str, Any]:
    """analyze_bag's keyword options, checked against the names it declares (OPTIONS)."""
    if not isinstance(raw, dict) or not all(isinstance(k, str) for k in raw):
        raise r.fail(("metrics",), "must be a mapping of analyze_bag options {name: value}")
    from .metrics import analyzer_options

    allowed = analyzer_options()
    for name in raw:
        if allowed is not None and name not in allowed:
            raise r.fail(("metrics", name), f"not an option of analyze_bag (allowed: {', '.join(allowed)})")
    return dict(raw)


def _objective(r: _Reader, raw: Any) -> tuple[str, str] | None:
    if raw is None:
        return None
    if (
        not isinstance(raw, dict)
        or set(raw) - {"metric", "goal"}
        or "metric" not in raw
        or not isinstance(raw["metric"], str)
    ):
        raise r.fail(("objective",), f"must be {{metric: NAME, goal: min|max}} (got {raw!r})")
    goal = raw.get("goal", "min")
    if goal not in ("min", "max"):
        raise r.fail(("objective", "goal"), f"must be min or max (got {goal!r})")
    return raw["metric"], goal
