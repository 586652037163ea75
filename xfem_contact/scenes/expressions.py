"""User expressions of the coordinates given as text (scene files).

An expression is Python arithmetic in ``x`` and ``y`` (m) with the functions
``sin cos tan exp log sqrt abs hypot arctan2 minimum maximum where isclose`` and
the constant ``pi``. It evaluates on numpy arrays (level sets, boundary
locators, Dirichlet data) and, for the functions UFL knows, on UFL coordinates
(loads). Names other than these are refused with a clear error.
"""

from __future__ import annotations

import ast
from collections.abc import Callable

import numpy as np
import ufl

_UFL = {
    "sin": ufl.sin,
    "cos": ufl.cos,
    "tan": ufl.tan,
    "exp": ufl.exp,
    "log": ufl.ln,
    "sqrt": ufl.sqrt,
    "abs": abs,
    "minimum": ufl.min_value,
    "maximum": ufl.max_value,
}
_NUMPY = {
    "sin": np.sin,
    "cos": np.cos,
    "tan": np.tan,
    "exp": np.exp,
    "log": np.log,
    "sqrt": np.sqrt,
    "abs": np.abs,
    "hypot": np.hypot,
    "arctan2": np.arctan2,
    "minimum": np.minimum,
    "maximum": np.maximum,
    "where": np.where,
    "isclose": np.isclose,
}
ALLOWED_NAMES = frozenset({"x", "y", "pi", *_NUMPY})


def _dispatch(name: str) -> Callable:
    def f(*args):
        if any(isinstance(a, ufl.core.expr.Expr) for a in args):
            if name not in _UFL:
                raise ValueError(f"{name}() is not available in loads (UFL expressions)")
            return _UFL[name](*args)
        return _NUMPY[name](*args)

    return f


def compile_expression(text: str, what: str = "expression") -> Callable:
    """Turn ``text`` into ``f(x)``, ``x`` of shape (>=2, n) (numpy) or a UFL coordinate.

    Raises:
        ValueError: on a syntax error or a name outside :data:`ALLOWED_NAMES`.
    """
    try:
        tree = ast.parse(str(text), mode="eval")
    except SyntaxError as err:
        raise ValueError(f"Cannot read the {what} {text!r}: {err.msg}") from None
    names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
    unknown = sorted(names - ALLOWED_NAMES)
    if unknown or any(isinstance(n, ast.Attribute) for n in ast.walk(tree)):
        raise ValueError(
            f"The {what} {text!r} uses unknown names {unknown}; allowed: {sorted(ALLOWED_NAMES)}"
        )
    code = compile(tree, f"<{what}>", "eval")
    functions = {name: _dispatch(name) for name in _NUMPY}

    def f(x):
        return eval(code, {"__builtins__": {}}, {**functions, "pi": np.pi, "x": x[0], "y": x[1]})

    return f
