"""Arithmetic expressions of design parameters in a mechanism description (attachment points, link lengths).

An expression is a number or a string such as ``"base_radius - platform_radius"`` or ``"0.5 * sqrt(3) * a"``:
numbers, parameter names, ``pi``, ``+ - * / **``, parentheses and the functions sqrt, sin, cos, tan, radians.
It is parsed once with :mod:`ast` (never ``eval``): anything else, or a name that is not a parameter, is refused with
a one-line message, so a description is checked before any kernel sees it.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

from scalesynth.names import hint

FUNCTIONS: dict[str, Callable[[float], float]] = {
    "sqrt": math.sqrt, "sin": math.sin, "cos": math.cos, "tan": math.tan, "radians": math.radians,
}
CONSTANTS = {"pi": math.pi}
_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.Pow: operator.pow}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
MAX_LENGTH = 200  # characters of one expression


class ExpressionError(ValueError):
    """An expression that cannot be parsed or names something unknown; the message is one short line."""


@dataclass(frozen=True)
class Expression:
    """A parsed expression: its text, the parameter names it reads, and ``value(params)``."""

    text: str
    names: frozenset[str]
    _tree: ast.AST

    def value(self, params: Mapping[str, float]) -> float:
        """The expression's value for these parameter values (every name in ``names`` must be given)."""
        try:
            out = float(_evaluate(self._tree, params))
        except (ArithmeticError, ValueError) as err:  # e.g. sqrt of a negative number, a division by zero
            raise ExpressionError(f"{self.text!r} cannot be evaluated ({err})") from None
        if not math.isfinite(out):
            raise ExpressionError(f"{self.text!r} is not finite for these parameters")
        return out


def parse(source: float | int | str, parameters: Iterable[str]) -> Expression:
    """Parse ``source`` (a number or an expression text) against the parameter names; ExpressionError if it is
    malformed, uses an operation outside the list above, or names an unknown parameter."""
    if isinstance(source, bool):
        raise ExpressionError(f"expected a number or an expression, got {source!r}")
    if isinstance(source, (int, float)):
        if not math.isfinite(source):
            raise ExpressionError(f"must be finite, got {source!r}")
        return Expression(repr(float(source)), frozenset(), ast.Constant(float(source)))
    if not isinstance(source, str):
        raise ExpressionError(f"expected a number or an expression, got {type(source).__name__}")
    text = source.strip()
    if not text or len(text) > MAX_LENGTH:
        raise ExpressionError(f"expected an expression of 1 to {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text, mode="eval").body
    except SyntaxError:
        raise ExpressionError(f"{text!r} is not an arithmetic expression") from None
    known = list(parameters)  # in the description's order, for the message's list
    names: set[str] = set()
    _check(tree, text, known, names)
    return Expression(text, frozenset(names), tree)


def _check(node: ast.AST, text: str, known: list[str], names: set[str]) -> None:
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise ExpressionError(f"{text!r}: only numbers may appear as constants")
    elif isinstance(node, ast.Name):
        if node.id in CONSTANTS:
            return
        if node.id not in known:
            inside = "" if text == node.id else f"{text!r}: "  # the whole expression is the name: say it once
            raise ExpressionError(f"{inside}unknown parameter {node.id!r} " + hint(node.id, known))
        names.add(node.id)
    elif isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        _check(node.left, text, known, names)
        _check(node.right, text, known, names)
    elif isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
        _check(node.operand, text, known, names)
    elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS
          and len(node.args) == 1 and not node.keywords):
        _check(node.args[0], text, known, names)
    else:
        raise ExpressionError(f"{text!r}: only numbers, parameters, pi, + - * / ** and "
                              f"{', '.join(FUNCTIONS)} are allowed")


def _evaluate(node: ast.AST, params: Mapping[str, float]) -> float:
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return CONSTANTS[node.id] if node.id in CONSTANTS else float(params[node.id])
    if isinstance(node, ast.BinOp):
        return _BINARY[type(node.op)](_evaluate(node.left, params), _evaluate(node.right, params))
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](_evaluate(node.operand, params))
    assert isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
    return FUNCTIONS[node.func.id](_evaluate(node.args[0], params))
