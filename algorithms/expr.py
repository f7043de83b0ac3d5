"""A small, safe expression language for user-written surfaces, trims and objects.

Text such as ``"r_and(0.16 - y**2 - z**2, x)"`` is parsed with :mod:`ast` and checked against a
whitelist: numbers, the declared variables and constants, ``+ - * / **``, unary minus, and calls
of whitelisted functions. Anything else (attributes, subscripts, comprehensions, lambdas,
keywords, strings, names not declared) is rejected with a message that says what and where.
Raw text is never given to ``eval``: the checked tree is turned into nested closures.

The same compiled expression evaluates

* on numbers or numpy arrays (``expr(x=..., y=...)``), with each function's numeric form;
* on intervals (``expr.interval(x=I, y=I, z=I)``), with each function's interval form. The
  arithmetic operators are those of the values passed in, so any interval class with
  ``+ - * / **`` overloads works; a built-in function ``f`` calls the method ``f`` of its first
  argument (``x.sqrt()``, ``x.sin()``, ``x.minimum(y)``, ...), and a registered
  :class:`Function` uses its own ``interval`` callable.

Callers extend the language with their own building blocks (R-functions, perturbations) by
passing ``functions={name: Function(numeric, interval)}``.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np


class ExpressionError(ValueError):
    """An expression that is not valid in the language (with what and where)."""


@dataclass(frozen=True)
class Function:
    """A function callable from expressions.

    numeric: evaluates on floats / numpy arrays. interval: evaluates on intervals (None: the
    function cannot be used where an interval extension is needed). nargs: the exact argument
    count, or None for any number >= 1.
    """

    numeric: Callable[..., Any]
    interval: Callable[..., Any] | None = None
    nargs: int | None = None
    doc: str = ""


def _method(name: str) -> Callable[..., Any]:
    def call(first: Any, *rest: Any) -> Any:
        m = getattr(first, name, None)
        if m is None:
            raise ExpressionError(f"{name}() has no interval form for {type(first).__name__}")
        return m(*rest)

    return call


def _nary(f: Callable[[Any, Any], Any]) -> Callable[..., Any]:
    def call(*args: Any) -> Any:
        out = args[0]
        for a in args[1:]:
            out = f(out, a)
        return out

    return call


BUILTINS: dict[str, Function] = {
    "sqrt": Function(np.sqrt, _method("sqrt"), 1),
    "exp": Function(np.exp, _method("exp"), 1),
    "log": Function(np.log, _method("log"), 1),
    "sin": Function(np.sin, _method("sin"), 1),
    "cos": Function(np.cos, _method("cos"), 1),
    "tan": Function(np.tan, _method("tan"), 1),
    "atan2": Function(np.arctan2, _method("atan2"), 2),
    "abs": Function(np.abs, lambda a: abs(a), 1),
    "min": Function(_nary(np.minimum), _nary(lambda a, b: a.minimum(b)), None),
    "max": Function(_nary(np.maximum), _nary(lambda a, b: a.maximum(b)), None),
}

CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

_BINOPS: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a**b,
}
_OPNAMES = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}

Node = Callable[[dict[str, Any], bool], Any]  # (environment, interval mode) -> value


@dataclass(frozen=True, eq=False)
class Expr:
    """A checked, compiled expression. Call it with the variables as keywords."""

    text: str
    variables: tuple[str, ...]
    used: frozenset[str]  # the variables the text uses
    _node: Node = field(repr=False)

    def __call__(self, **values: Any) -> Any:
        return self._node(self._env(values), False)

    def interval(self, **values: Any) -> Any:
        """Evaluate with interval forms (values are interval objects or plain numbers)."""
        return self._node(self._env(values), True)

    def _env(self, values: Mapping[str, Any]) -> dict[str, Any]:
        missing = [v for v in self.used if v not in values]
        if missing:
            raise ExpressionError(f"{self.text!r} needs a value for {', '.join(sorted(missing))}")
        return dict(values)


def _where(node: ast.AST, text: str) -> str:
    col = getattr(node, "col_offset", None)
    return f" at column {col + 1} of {text!r}" if col is not None else f" in {text!r}"


def compile_expr(text: str, *, variables: Sequence[str] = ("x", "y", "z"),
                 functions: Mapping[str, Function] | None = None,
                 constants: Mapping[str, float] | None = None,
                 names: Mapping[str, Expr] | None = None) -> Expr:
    """Check and compile ``text``.

    variables: names bound at evaluation time. functions: extra functions (they may shadow the
    built-ins). constants: extra named numbers. names: named sub-expressions compiled before
    (see :func:`compile_defs`), evaluated with the same variables.
    """
    if not isinstance(text, str):
        raise ExpressionError(f"an expression must be text, not {type(text).__name__}")
    if len(text) > 20000:
        raise ExpressionError("expression too long (more than 20000 characters)")
    funcs = {**BUILTINS, **(functions or {})}
    consts = {**CONSTANTS, **(constants or {})}
    subs = dict(names or {})
    var_set = set(variables)
    for n in var_set:
        if not n.isidentifier():
            raise ExpressionError(f"variable name {n!r} is not an identifier")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"syntax error in {text!r}: {exc.msg} (column {exc.offset})") from None
    used: set[str] = set()

    def build(node: ast.AST, depth: int = 0) -> Node:
        if depth > 200:
            raise ExpressionError(f"expression nested too deeply: {text[:60]!r}")
        if isinstance(node, ast.Expression):
            return build(node.body, depth + 1)
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
                raise ExpressionError(f"only numbers are allowed, not {node.value!r}{_where(node, text)}")
            val = float(node.value)
            return lambda env, iv: val
        if isinstance(node, ast.Name):
            nm = node.id
            if nm in var_set:
                used.add(nm)
                return lambda env, iv: env[nm]
            if nm in subs:
                sub = subs[nm]
                used.update(sub.used)
                return lambda env, iv: sub._node(env, iv)
            if nm in consts:
                cval = float(consts[nm])
                return lambda env, iv: cval
            if nm in funcs:
                raise ExpressionError(f"{nm} is a function: call it as {nm}(...){_where(node, text)}")
            known = sorted(var_set | set(consts) | set(subs))
            raise ExpressionError(f"unknown name {nm!r}{_where(node, text)} (known: {', '.join(known)})")
        if isinstance(node, ast.BinOp):
            op = _BINOPS.get(type(node.op))
            if op is None:
                raise ExpressionError(f"operator {type(node.op).__name__} is not allowed{_where(node, text)} "
                                      f"(allowed: + - * / **)")
            left, right = build(node.left, depth + 1), build(node.right, depth + 1)
            return lambda env, iv: op(left(env, iv), right(env, iv))
        if isinstance(node, ast.UnaryOp):
            operand = build(node.operand, depth + 1)
            if isinstance(node.op, ast.USub):
                return lambda env, iv: -operand(env, iv)
            if isinstance(node.op, ast.UAdd):
                return operand
            raise ExpressionError(f"operator {type(node.op).__name__} is not allowed{_where(node, text)}")
        if isinstance(node, ast.Call):
            if not isinstance(node.func, ast.Name):
                raise ExpressionError(f"only plain function names can be called{_where(node, text)}")
            fname = node.func.id
            if fname not in funcs:
                raise ExpressionError(f"unknown function {fname!r}{_where(node, text)} "
                                      f"(known: {', '.join(sorted(funcs))})")
            if node.keywords:
                raise ExpressionError(f"keyword arguments are not allowed{_where(node, text)}")
            fn = funcs[fname]
            if fn.nargs is not None and len(node.args) != fn.nargs:
                raise ExpressionError(f"{fname}() takes {fn.nargs} argument(s), got {len(node.args)}"
                                      f"{_where(node, text)}")
            if not node.args:
                raise ExpressionError(f"{fname}() needs arguments{_where(node, text)}")
            args = [build(a, depth + 1) for a in node.args]

            def call(env: dict[str, Any], iv: bool) -> Any:
                vals = [a(env, iv) for a in args]
                if iv:
                    if fn.interval is None:
                        raise ExpressionError(f"{fname}() has no interval extension")
                    return fn.interval(*vals)
                return fn.numeric(*vals)

            return call
        raise ExpressionError(f"{type(node).__name__} is not allowed in expressions{_where(node, text)}")

    node = build(tree)
    return Expr(text, tuple(variables), frozenset(used), node)


def compile_defs(defs: Mapping[str, str] | Sequence[tuple[str, str]], *,
                 variables: Sequence[str] = ("x", "y", "z"),
                 functions: Mapping[str, Function] | None = None,
                 constants: Mapping[str, float] | None = None) -> dict[str, Expr]:
    """Compile named definitions in order; each may use the names defined before it.

    Definitions whose text is a plain number become constants for the later ones.
    """
    items = list(defs.items()) if isinstance(defs, Mapping) else list(defs)
    consts = dict(constants or {})
    out: dict[str, Expr] = {}
    for name, text in items:
        if not str(name).isidentifier():
            raise ExpressionError(f"definition name {name!r} is not an identifier")
        if name in set(variables):
            raise ExpressionError(f"definition {name!r} would hide a variable")
        if isinstance(text, (int, float)) and not isinstance(text, bool):
            consts[name] = float(text)
            continue
        e = compile_expr(str(text), variables=variables, functions=functions, constants=consts, names=out)
        if not e.used:
            consts[name] = float(e())  # a constant expression: fold it
        else:
            out[name] = e
    out.update({k: compile_expr(repr(v), variables=variables) for k, v in consts.items()
                if k not in CONSTANTS and k not in (constants or {})})
    return out
