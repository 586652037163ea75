"""User expressions of the coordinates given as text (scene files).

An expression is Python arithmetic in ``x`` and ``y`` (and ``z`` on a 3D mesh) (m) with the
functions
``sin cos tan exp log sqrt abs hypot arctan2 minimum maximum where isclose`` and
the constant ``pi``. It evaluates on numpy arrays (level sets, boundary
locators, Dirichlet data) and, for the functions UFL knows, on UFL coordinates
(loads). Names other than these are refused with a clear error.

Expressions are bounded before anything evaluates them: at most
:data:`MAX_LENGTH` characters and :data:`MAX_DEPTH` levels of nesting, only the
syntax listed above (numbers, names, ``+ - * / **``, comparisons and ``& | ~``
outside loads, calls of the functions), an exponent of ``**`` only a number of
size at most :data:`MAX_EXPONENT`, every number and every constant part finite.
Integers are read as floats, so no arithmetic on huge integers can run: an
accepted expression evaluates in time linear in its length.
"""

from __future__ import annotations

import ast
import functools
import math
from collections.abc import Callable

import numpy as np
import ufl

#: Longest expression text (characters)
MAX_LENGTH = 500
#: Deepest nesting of an expression (levels of its syntax tree)
MAX_DEPTH = 32
#: Largest size of the (literal) exponent of ``**``
MAX_EXPONENT = 16

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
ALLOWED_NAMES = frozenset({"x", "y", "z", "pi", *_NUMPY})
#: The coordinates an expression may use on a mesh of each geometric dimension
COORDINATES = {2: ("x", "y"), 3: ("x", "y", "z")}
#: Number of arguments of each function (numpy would read more as ``out=``)
_ARITY = dict.fromkeys(_NUMPY, 1) | dict.fromkeys(("hypot", "arctan2", "isclose"), 2)
_ARITY |= {"minimum": 2, "maximum": 2, "where": 3}
#: Operators by syntax node; the logical ones (comparisons, ``& | ~``) not in loads
_ARITHMETIC = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_ARITHMETIC |= {ast.USub: "-", ast.UAdd: "+"}
_LOGICAL = {ast.BitAnd: "&", ast.BitOr: "|", ast.Invert: "~", ast.Lt: "<", ast.LtE: "<="}
_LOGICAL |= {ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!="}
_OPERATOR_NODES = (ast.operator, ast.unaryop, ast.cmpop, ast.expr_context)


def _dispatch(name: str) -> Callable:
    def f(*args):
        if any(isinstance(a, ufl.core.expr.Expr) for a in args):
            if name not in _UFL:
                raise ValueError(f"{name}() is not available in loads (UFL expressions)")
            return _UFL[name](*args)
        return _NUMPY[name](*args)

    return f


def _short(text: str) -> str:
    """``text`` quoted on one line, cut to 60 characters."""
    quoted = repr(text)
    return quoted if len(quoted) <= 60 else quoted[:56] + "...'"


def _refusal(node: ast.AST, loads: bool, dim: int = 2) -> str | None:
    """Why ``node`` is not allowed in an expression (``loads``: evaluated by UFL) on a mesh
    of dimension ``dim``, or None."""
    functions = _UFL if loads else _NUMPY
    operators = _ARITHMETIC if loads else _ARITHMETIC | _LOGICAL
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) and not loads:
            return None
        if isinstance(node.value, bool) or not isinstance(node.value, int | float):
            return f"uses the constant {node.value!r}: only numbers are allowed"
        if isinstance(node.value, int) and abs(node.value) > 1e300:
            return "uses a number too large for a float"
        if not math.isfinite(node.value):
            return f"uses the non-finite number {node.value}"
        return None
    if isinstance(node, ast.Name):
        names = (*COORDINATES[dim], "pi")
        if node.id in names:
            return None
        if node.id in functions:
            return f"uses the function {node.id} without calling it"
        if node.id == "z":
            return "uses z, the third coordinate, on a 2D mesh (coordinates there: x, y)"
        return f"uses the unknown name {node.id!r}; allowed: {sorted({*names, *functions})}"
    if isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in functions:
            of = " of loads (UFL)" if loads else ""
            called = ast.unparse(node.func)
            return f"calls {called!r}, not a function{of}; functions: {sorted(functions)}"
        if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
            return f"calls {name}() with keyword or starred arguments"
        if len(node.args) != _ARITY[name]:
            return f"calls {name}() with {len(node.args)} argument(s); it takes {_ARITY[name]}"
        return None
    if isinstance(node, ast.BinOp | ast.UnaryOp):
        if type(node.op) not in operators:
            kind = "the operator" if type(node.op) in _LOGICAL else "the unsupported operator"
            where = " in a load (UFL)" if loads else ""
            valid = " ".join(sorted(set(operators.values())))
            return f"uses {kind} {_operator(node.op)}{where}; operators: {valid}"
        if isinstance(node.op, ast.Pow) and not _small_number(node.right):
            power = _short(ast.unparse(node.right))
            return (
                f"raises to the power {power}: the exponent of ** must be a number of size at "
                f"most {MAX_EXPONENT}"
            )
        return None
    if isinstance(node, ast.Compare):
        if loads:
            return "uses a comparison, which loads (UFL) do not take"
        if len(node.ops) > 1:
            return "chains comparisons; write (a < x) & (x < b)"
        if type(node.ops[0]) not in _LOGICAL:
            return f"uses the comparison {_operator(node.ops[0])}"
        return None
    if isinstance(node, ast.BoolOp):
        return "uses 'and'/'or'; write (a) & (b), (a) | (b) on comparisons"
    return f"uses {type(node).__name__} syntax, which expressions do not allow"


def _operator(op: ast.AST) -> str:
    names = {ast.Not: "not", ast.FloorDiv: "//", ast.Mod: "%", ast.LShift: "<<"}
    names |= {ast.RShift: ">>", ast.BitXor: "^", ast.MatMult: "@", ast.In: "in", ast.Is: "is"}
    return (_ARITHMETIC | _LOGICAL | names).get(type(op), type(op).__name__)


def _small_number(node: ast.AST) -> bool:
    """Whether ``node`` is a literal number (with a sign) of size <= MAX_EXPONENT."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        node = node.operand
    return (
        isinstance(node, ast.Constant)
        and isinstance(node.value, int | float)
        and not isinstance(node.value, bool)
        and abs(node.value) <= MAX_EXPONENT
    )


class _Floats(ast.NodeTransformer):
    """Integer literals as floats: no arithmetic on unbounded integers."""

    def visit_Constant(self, node):
        if isinstance(node.value, int) and not isinstance(node.value, bool):
            return ast.copy_location(ast.Constant(float(node.value)), node)
        return node


def _check_tree(tree: ast.Expression, text: str, what: str, loads: bool, dim: int) -> None:
    """Refuse disallowed syntax and too deep nesting (iterative: no recursion limit)."""
    stack = [(tree.body, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise ValueError(f"{what}: {_short(text)} nests deeper than {MAX_DEPTH} levels")
        problem = _refusal(node, loads, dim)
        if problem:
            raise ValueError(f"{what}: {_short(text)} {problem}")
        children = [c for c in ast.iter_child_nodes(node) if not isinstance(c, _OPERATOR_NODES)]
        if isinstance(node, ast.Call):
            children = node.args
        stack.extend((child, depth + 1) for child in children)


def _check_constants(node: ast.AST, text: str, what: str) -> bool:
    """Refuse a constant part (no ``x``, ``y``) that is not a finite number; returns
    whether ``node`` is constant. Depth is bounded by :data:`MAX_DEPTH`."""
    children = node.args if isinstance(node, ast.Call) else list(ast.iter_child_nodes(node))
    children = [c for c in children if not isinstance(c, _OPERATOR_NODES)]
    flags = [_check_constants(child, text, what) for child in children]
    constant = all(flags) and not (isinstance(node, ast.Name) and node.id in COORDINATES[3])
    if not constant:
        for child, flag in zip(children, flags, strict=True):
            if flag and not isinstance(child, ast.Constant | ast.Name):
                _finite_constant(child, text, what)
    return constant


def _finite_constant(node: ast.expr, text: str, what: str) -> None:
    code = compile(ast.Expression(body=node), "<constant>", "eval")
    try:
        with np.errstate(all="ignore"):
            value = eval(code, {"__builtins__": {}}, {**_FUNCTIONS, "pi": np.pi})
        finite = bool(np.all(np.isfinite(value)))
    except (ArithmeticError, TypeError, ValueError):
        finite = False
    if not finite:
        part = ast.unparse(node)
        raise ValueError(f"{what}: {_short(text)}: {_short(part)} is not a finite number")


_FUNCTIONS = {name: _dispatch(name) for name in _NUMPY}


def compile_expression(
    text: str, what: str = "expression", loads: bool = False, dim: int = 2
) -> Callable:
    """Turn ``text`` into ``f(x)``, ``x`` of shape (>=dim, n) (numpy) or a UFL coordinate.

    ``what`` names the expression in errors (its scene key); ``loads``: only what
    UFL evaluates (no comparisons, no ``& | ~``, the functions UFL knows); ``dim``: the
    mesh's geometric dimension (``z`` is a coordinate in 3D only).

    Raises:
        ValueError: ``WHAT: message`` (one line) on a syntax error, a name outside
            :data:`ALLOWED_NAMES`, disallowed syntax, a text or nesting too long, an
            exponent that is not a small number, a number or constant part not finite.
    """
    if not isinstance(text, str):
        raise ValueError(f"{what}: expected an expression string, got {text!r}")
    if len(text) > MAX_LENGTH:
        raise ValueError(f"{what}: the expression has {len(text)} characters; at most {MAX_LENGTH}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as err:
        reason = err.msg if isinstance(err, SyntaxError) else str(err) or "nested too deeply"
        raise ValueError(f"{what}: cannot read {_short(text)}: {reason}") from None
    _check_tree(tree, text, what, loads, dim)
    tree = ast.fix_missing_locations(_Floats().visit(tree))
    if _check_constants(tree.body, text, what) and not isinstance(tree.body, ast.Constant):
        _finite_constant(tree.body, text, what)
    code = compile(tree, f"<{what}>", "eval")

    def f(x):
        coordinates = {name: x[k] for k, name in enumerate(COORDINATES[dim])}
        return eval(code, {"__builtins__": {}}, {**_FUNCTIONS, "pi": np.pi, **coordinates})

    return f


@functools.cache
def _ufl_coordinate(dim: int = 2):
    import basix.ufl

    cell = {2: "triangle", 3: "tetrahedron"}[dim]
    return ufl.SpatialCoordinate(ufl.Mesh(basix.ufl.element("Lagrange", cell, 1, shape=(dim,))))


#: Sample points of a trial evaluation (shape (3, n), as DOLFINx interpolation passes)
_SAMPLES = np.vstack([np.repeat([-1.0, 0.0, 0.5, 1.0], 4), np.tile([-1.0, 0.0, 0.5, 1.0], 4)])
_SAMPLES = np.vstack([_SAMPLES, np.zeros(_SAMPLES.shape[1])])


def check_expression(text, what: str, target: str = "number", dim: int = 2) -> Callable:
    """Compile ``text`` and evaluate it once on sample points: ``target`` ``"number"``
    (numpy values, e.g. level sets, Dirichlet data), ``"boolean"`` (boundary parts) or
    ``"load"`` (UFL, a scalar); ``dim`` the mesh's geometric dimension. Returns the
    compiled ``f``; raises ``WHAT: message``."""
    f = compile_expression(text, what, loads=target == "load", dim=dim)
    try:
        with np.errstate(all="ignore"):
            if target == "load":
                value = ufl.as_ufl(f(_ufl_coordinate(dim)))
                if value.ufl_shape != ():
                    raise ValueError(f"the value has shape {value.ufl_shape}, not a scalar")
            else:
                value = np.asarray(f(_SAMPLES), dtype=bool if target == "boolean" else float)
                np.broadcast_to(value, _SAMPLES[0].shape)
    except Exception as err:  # the user's expression: any failure is a clear input error
        reason = " ".join(str(err).split()) or type(err).__name__
        raise ValueError(f"{what}: cannot evaluate {_short(text)}: {reason}") from None
    return f


def numpy_field(
    text: str, what: str = "expression", dim: int = 2
) -> Callable[[np.ndarray], np.ndarray]:
    """``text`` as a level set or a nodal field: ``f(x)``, ``x`` of shape (>=dim, n),
    returning a float array ``(n,)`` (a constant broadcast). Raises as
    :func:`compile_expression`."""
    f = compile_expression(text, what, dim=dim)
    return lambda x: np.broadcast_to(np.asarray(f(x), dtype=float), x[0].shape).copy()
