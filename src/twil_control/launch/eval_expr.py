"""roslaunch's ``$(eval EXPR)``, evaluated on a whitelisted syntax tree instead of Python's eval.

What roslaunch users write in ``$(eval ...)`` works (docs/ros1.md lists it); anything else is an
EvalError naming the expression and the part refused, and nothing is ever run through Python's
``eval``. Sizes are bounded from the operands before a value is built (MAX_SIZE characters as
printed, MAX_POWER_BITS), so a launch file cannot exhaust memory or time.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable, Mapping
from typing import Any

from twil_control.errors import TwilControlError

MAX_LENGTH = 100_000  # items of a string or list (what the old name promised; kept for callers)
MAX_SIZE = 1_000_000  # characters a value prints as: every result is bounded by this before it is built
MAX_POWER_BITS = 4096

STRING_METHODS = frozenset(
    {
        "lower",
        "upper",
        "strip",
        "lstrip",
        "rstrip",
        "startswith",
        "endswith",
        "replace",
        "split",
        "join",
        "find",
        "count",
        "capitalize",
        "title",
        "isdigit",
        "zfill",
    }
)

_MATH = {
    name: getattr(math, name)
    for name in (
        "pi",
        "e",
        "tau",
        "inf",
        "sqrt",
        "sin",
        "cos",
        "tan",
        "asin",
        "acos",
        "atan",
        "atan2",
        "radians",
        "degrees",
        "floor",
        "ceil",
        "fabs",
        "hypot",
        "exp",
        "log",
        "log10",
        "isclose",
    )
}

_BUILTINS: dict[str, Callable] = {
    "str": str,
    "int": int,
    "float": float,
    "bool": bool,
    "len": len,
    "abs": abs,
    "min": min,
    "max": max,
    "round": round,
}

_CONSTANTS = {"true": True, "false": False, "True": True, "False": False}

_BINARY = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
    ast.Pow: operator.pow,
    ast.BitOr: operator.or_,  # on integers and booleans: jackal_control's `gx5_enable | microstrain_enable`
    ast.BitAnd: operator.and_,
    ast.BitXor: operator.xor,
}
_BITWISE = (ast.BitOr, ast.BitAnd, ast.BitXor)
_COMPARE = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
}
_UNARY = {ast.Not: operator.not_, ast.USub: operator.neg, ast.UAdd: operator.pos}


def size(value: Any, _memo: dict | None = None) -> int:
    """About the characters ``str(value)`` has, without making it: a list repeated by reference
    (``[x] * n``) is measured once per distinct item object."""
    if isinstance(value, str):
        return len(value) + 2
    if isinstance(value, (list, tuple)):
        memo = {} if _memo is None else _memo
        known = memo.get(id(value))
        if known is None:
            known = 2 + sum(size(item, memo) + 2 for item in value)
            memo[id(value)] = known
        return known
    if isinstance(value, int) and not isinstance(value, bool):
        return value.bit_length() * 3 // 10 + 2  # decimal digits
    return 24  # floats, booleans, None


class EvalError(TwilControlError, ValueError):
    """An expression outside the whitelist, or one that fails while evaluated."""


def evaluate(expression: str, names: Callable[[str], Any], functions: Mapping[str, Callable]) -> Any:
    """The value of ``expression``.

    ``names(name)`` gives a bare name's value (an arg, typed) or raises KeyError;
    ``functions`` are the substitution functions (arg, env, optenv, find, anon, dirname).
    """
    shown = f"$(eval {expression})"
    if "__" in expression:  # roslaunch's own rule, kept as a first line of defence
        raise EvalError(f"{shown}: double underscores are not allowed in $(eval ...)")
    try:
        tree = ast.parse(expression.strip(), mode="eval")
    except SyntaxError as exc:
        raise EvalError(f"{shown}: not a valid expression ({exc.msg})") from None
    evaluator = _Evaluator(shown, names, {**_BUILTINS, **functions})
    try:
        return evaluator.visit(tree.body)
    except EvalError:
        raise
    except (ArithmeticError, TypeError, ValueError, IndexError, KeyError) as exc:
        if type(exc).__module__ != "builtins":  # a substitution's own error says it all
            raise
        raise EvalError(f"{shown}: {type(exc).__name__}: {exc}") from None


class _Evaluator:
    def __init__(self, shown: str, names: Callable[[str], Any], functions: Mapping[str, Callable]) -> None:
        self.shown = shown
        self.names = names
        self.functions = functions

    def refuse(self, node: ast.AST, what: str) -> EvalError:
        part = ast.unparse(node) if isinstance(node, ast.AST) else str(node)
        return EvalError(
            f"{self.shown}: {what} is not allowed in $(eval ...) (at {part!r}); "
            f"allowed: arithmetic, comparisons, | & ^ on integers, and/or/not, if-else, strings, "
            f"arg names, arg() env() optenv() find() anon() dirname(), math "
            f"functions and string methods"
        )

    def visit(self, node: ast.AST) -> Any:
        method = getattr(self, f"on_{type(node).__name__}", None)
        if method is None:
            raise self.refuse(node, type(node).__name__)
        return self.checked(method(node))

    def checked(self, value: Any) -> Any:
        if isinstance(value, (str, list, tuple)) and len(value) > MAX_LENGTH:
            raise EvalError(f"{self.shown}: result longer than {MAX_LENGTH} items")
        self.bounded(size(value))
        return value

    def bounded(self, n: int) -> None:
        """Refuse a result that would print as more than MAX_SIZE characters (before it is made)."""
        if n > MAX_SIZE:
            raise EvalError(
                f"{self.shown}: the result would be about {n:,} characters long, more than the "
                f"{MAX_SIZE:,} allowed in $(eval ...)"
            )

    def check_growth(self, text: str, method: str, args: list) -> None:
        """Refuse a string method call whose result would exceed MAX_LENGTH, before making it."""
        size = len(text)
        if method == "zfill" and args and isinstance(args[0], int):
            size = args[0]
        elif method == "replace" and len(args) >= 2 and all(isinstance(a, str) for a in args[:2]):
            hits = text.count(args[0]) if args[0] else len(text) + 1
            size = len(text) + hits * len(args[1])
        elif method == "join" and args and isinstance(args[0], (list, tuple)):
            size = sum(len(str(item)) for item in args[0]) + len(text) * len(args[0])
        if size > MAX_LENGTH:
            raise EvalError(f"{self.shown}: result longer than {MAX_LENGTH} items")
        self.bounded(size)

    def on_Constant(self, node: ast.Constant) -> Any:
        if isinstance(node.value, (str, int, float, bool)):
            return node.value
        raise self.refuse(node, f"a {type(node.value).__name__} literal")

    def on_Name(self, node: ast.Name) -> Any:
        if node.id in _CONSTANTS:
            return _CONSTANTS[node.id]
        if node.id in _MATH and not callable(_MATH[node.id]):
            return _MATH[node.id]
        try:
            return self.names(node.id)
        except KeyError:
            raise EvalError(f"{self.shown}: name {node.id!r} is not a declared arg") from None

    def on_List(self, node: ast.List) -> list:
        return [self.visit(item) for item in node.elts]

    def on_Tuple(self, node: ast.Tuple) -> tuple:
        return tuple(self.visit(item) for item in node.elts)

    def on_BinOp(self, node: ast.BinOp) -> Any:
        op = _BINARY.get(type(node.op))
        if op is None:
            raise self.refuse(node, f"operator {type(node.op).__name__}")
        left, right = self.visit(node.left), self.visit(node.right)
        if isinstance(node.op, ast.Pow) and isinstance(left, int) and isinstance(right, int):
            if right > 0 and abs(left) > 1 and right * max(abs(left).bit_length(), 1) > MAX_POWER_BITS:
                raise EvalError(f"{self.shown}: {left} ** {right} is too large")
        if isinstance(node.op, _BITWISE) and not (isinstance(left, int) and isinstance(right, int)):
            raise self.refuse(
                node, f"operator {type(node.op).__name__} on {type(left).__name__} and {type(right).__name__}"
            )
        if isinstance(node.op, ast.Mod) and isinstance(left, str):
            raise self.refuse(node, "string formatting with %")
        if isinstance(node.op, ast.Mult):
            for seq, count in ((left, right), (right, left)):
                if isinstance(seq, (str, list, tuple)) and isinstance(count, int):
                    if len(seq) * count > MAX_LENGTH:
                        raise EvalError(f"{self.shown}: result longer than {MAX_LENGTH} items")
                    self.bounded(size(seq) * max(count, 0))
        if isinstance(node.op, ast.Add) and isinstance(left, (str, list, tuple)):
            if isinstance(right, (str, list, tuple)) and len(left) + len(right) > MAX_LENGTH:
                raise EvalError(f"{self.shown}: result longer than {MAX_LENGTH} items")
            self.bounded(size(left) + size(right))
        return op(left, right)

    def on_UnaryOp(self, node: ast.UnaryOp) -> Any:
        op = _UNARY.get(type(node.op))
        if op is None:
            raise self.refuse(node, f"operator {type(node.op).__name__}")
        return op(self.visit(node.operand))

    def on_BoolOp(self, node: ast.BoolOp) -> Any:
        value = self.visit(node.values[0])
        for item in node.values[1:]:  # short-circuit as Python does
            if isinstance(node.op, ast.And) and not value:
                return value
            if isinstance(node.op, ast.Or) and value:
                return value
            value = self.visit(item)
        return value

    def on_Compare(self, node: ast.Compare) -> bool:
        left = self.visit(node.left)
        for op_node, comparator in zip(node.ops, node.comparators):
            op = _COMPARE.get(type(op_node))
            if op is None:
                raise self.refuse(node, f"comparison {type(op_node).__name__}")
            right = self.visit(comparator)
            if not op(left, right):
                return False
            left = right
        return True

    def on_IfExp(self, node: ast.IfExp) -> Any:
        return self.visit(node.body) if self.visit(node.test) else self.visit(node.orelse)

    def on_Subscript(self, node: ast.Subscript) -> Any:
        value = self.visit(node.value)
        if not isinstance(value, (str, list, tuple)):
            raise self.refuse(node, f"indexing a {type(value).__name__}")
        return value[self.visit(node.slice)]

    def on_Slice(self, node: ast.Slice) -> slice:
        parts = [None if part is None else self.visit(part) for part in (node.lower, node.upper, node.step)]
        return slice(*parts)

    def on_Call(self, node: ast.Call) -> Any:
        if node.keywords:
            raise self.refuse(node, "a keyword argument")
        args = [self.visit(arg) for arg in node.args]
        func = node.func
        if isinstance(func, ast.Name):
            target = self.functions.get(func.id) or (_MATH[func.id] if callable(_MATH.get(func.id)) else None)
            if target is None:
                raise self.refuse(node, f"calling {func.id!r}")
            if target is str and args:  # the printed form of a nested value, before it is made
                self.bounded(size(args[0]))
            return target(*args)
        if isinstance(func, ast.Attribute):
            owner = self.visit(func.value)
            if isinstance(owner, str) and func.attr in STRING_METHODS:
                self.check_growth(owner, func.attr, args)
                return getattr(owner, func.attr)(*args)
            raise self.refuse(node, f"the method {func.attr!r} of a {type(owner).__name__}")
        raise self.refuse(node, "this call")
