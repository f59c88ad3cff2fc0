"""The goal panel's rules, free of any transport: what the form accepts and how goal states are
named. The HTTP server (view/panel_server.py) and the page both defer to this module, so a value the
page lets through is still refused here (server-side validation).

Ranges are the original rqt plugin's spin boxes: X and Y in [-20, 20] m, Ori in [-3.14, 3.14] rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from twil_control.errors import TwilControlError

X_RANGE = (-20.0, 20.0)
Y_RANGE = (-20.0, 20.0)
ORI_RANGE = (-3.14, 3.14)
FIELDS = {"x": ("X", X_RANGE, "m"), "y": ("Y", Y_RANGE, "m"), "ori": ("Ori", ORI_RANGE, "rad")}


class PanelInputError(TwilControlError, ValueError):
    """A form value the panel refuses; the message names the field, the value and the range."""


@dataclass(frozen=True)
class GoalForm:
    x: float
    y: float
    ori: float


def parse_field(key: str, raw) -> float:
    """One form value as a float inside its range, or PanelInputError saying why not."""
    if key not in FIELDS:
        raise PanelInputError(f"unknown field '{key}' (fields: {', '.join(FIELDS)})")
    label, (lo, hi), unit = FIELDS[key]
    if isinstance(raw, bool):
        raise PanelInputError(f"{label} must be a number in [{lo:g}, {hi:g}] {unit} (got {raw!r})")
    if isinstance(raw, str):
        text = raw.strip()
        if not text:
            raise PanelInputError(f"{label} is empty: enter a number in [{lo:g}, {hi:g}] {unit}")
        try:
            value = float(text)
        except ValueError:
            raise PanelInputError(
                f"{label} must be a number in [{lo:g}, {hi:g}] {unit} (got {raw!r})"
            ) from None
    elif isinstance(raw, (int, float)):
        try:
            value = float(raw)
        except OverflowError:  # a JSON integer of hundreds of digits
            raise PanelInputError(
                f"{label} must be a number in [{lo:g}, {hi:g}] {unit} (got an "
                f"integer of {len(str(raw))} digits)"
            ) from None
    else:
        raise PanelInputError(f"{label} must be a number in [{lo:g}, {hi:g}] {unit} (got {raw!r})")
    if not math.isfinite(value):
        raise PanelInputError(f"{label} must be a finite number in [{lo:g}, {hi:g}] {unit} (got {raw!r})")
    if not lo <= value <= hi:
        raise PanelInputError(f"{label} = {value:g} {unit} is out of range: allowed [{lo:g}, {hi:g}] {unit}")
    return value


def parse_goal_form(data) -> GoalForm:
    """The goal of a submitted form ({"x": .., "y": .., "ori": ..}); every problem is reported at
    once, one sentence per field, so the user fixes them in one go."""
    if not isinstance(data, dict):
        raise PanelInputError(f"a goal is a JSON object with x, y and ori (got {type(data).__name__})")
    extra = sorted(set(data) - set(FIELDS))
    errors = [f"unknown field(s) {', '.join(extra)} (fields: x, y, ori)"] if extra else []
    values = {}
    for key, (label, _, _) in FIELDS.items():
        if key not in data:
            errors.append(f"{label} is missing")
            continue
        try:
            values[key] = parse_field(key, data[key])
        except PanelInputError as exc:
            errors.append(str(exc))
    if errors:
        raise PanelInputError("; ".join(errors))
    return GoalForm(values["x"], values["y"], values["ori"])


def parse_enable(data) -> bool:
    """The controller switch request {"enable": true|false}."""
    if not isinstance(data, dict) or not isinstance(data.get("enable"), bool) or set(data) != {"enable"}:
        raise PanelInputError(
            f'the controller switch takes {{"enable": true}} or {{"enable": false}} (got {data!r})'
        )
    return data["enable"]
