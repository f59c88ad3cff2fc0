"""Ranges and choices for typed parameter schemas: ``param(...)`` declares a field with its rule,
e.g. ``publish_rate: float = param(gt=0)`` or ``law: str = param("corrected", choices=LAWS)``.

load_typed (core.typed_params) checks the rule after the type, naming the file:line where the
parameter was set. A bound on a number implies that it is finite: NaN and infinity are refused
(1 / .inf Hz is no rate, and a NaN gain never reaches a robot).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Rule:
    """What a parameter's value must satisfy beyond its type; numbers inside lists and mappings
    are each checked."""

    gt: float | None = None
    ge: float | None = None
    lt: float | None = None
    le: float | None = None
    finite: bool = False
    choices: tuple | None = None
    nonempty: bool = False
    why: str = ""  # the reason for the bounds, appended to a refusal

    @property
    def numeric(self) -> bool:
        return self.finite or any(b is not None for b in (self.gt, self.ge, self.lt, self.le))

    def _bounds(self) -> str:
        return " and ".join(
            f"{op} {bound:g}"
            for op, bound in ((">", self.gt), (">=", self.ge), ("<", self.lt), ("<=", self.le))
            if bound is not None
        )

    def allowed(self) -> str:
        """What the rule allows, as a phrase: 'a finite number > 0', "one of 'a', 'b'"."""
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        number = f"a finite number {self._bounds()}".rstrip() if self.numeric else ""
        if self.nonempty:
            return "a non-empty list" + (f" of {number[2:]}s" if number else "")
        return number

    def problem(self, value: Any) -> str | None:
        """None if `value` satisfies the rule, else what is wrong with it ('must be ...'), with
        the rule's reason when it has one."""
        found = self._problem(value)
        return f"{found}; {self.why}" if found and self.why else found

    def _problem(self, value: Any) -> str | None:
        if value is None:  # an Optional field left unset
            return None
        if self.choices is not None and value not in self.choices:
            return f"must be {self.allowed()}"
        if self.nonempty and isinstance(value, (list, tuple, dict)) and not value:
            return f"must be {self.allowed()}"
        if self.numeric:
            for number in _numbers(value):
                if not self._number_ok(number):
                    if number is value:
                        return f"must be {self.allowed()}"
                    return (
                        f"must hold only finite numbers {self._bounds()}".rstrip() + f" (one is {number!r})"
                    )
        return None

    def _number_ok(self, x: float) -> bool:
        return (
            math.isfinite(x)
            and (self.gt is None or x > self.gt)
            and (self.ge is None or x >= self.ge)
            and (self.lt is None or x < self.lt)
            and (self.le is None or x <= self.le)
        )


def _numbers(value: Any):
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        yield value
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from _numbers(item)
    elif isinstance(value, dict):
        for item in value.values():
            yield from _numbers(item)


def param(
    default: Any = dataclasses.MISSING,
    *,
    factory: Callable[[], Any] | None = None,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    finite: bool = False,
    choices: tuple | list | None = None,
    nonempty: bool = False,
    why: str = "",
):
    """A dataclass field with a Rule (see the module docstring); without a default or factory
    the parameter is required. `why` explains the bounds to whoever breaks them."""
    rule = Rule(gt, ge, lt, le, finite, tuple(choices) if choices is not None else None, nonempty, why)
    if factory is not None:
        return dataclasses.field(default_factory=factory, metadata={"rule": rule})
    return dataclasses.field(default=default, metadata={"rule": rule})


def rule_of(field: dataclasses.Field) -> Rule | None:
    return field.metadata.get("rule")
