"""The scene schema: allowed keys, choices and the validated scene records.

One table (:data:`FIELDS`) names every key of every table with its type, range and
meaning (:data:`SCHEMA` is its text); :func:`check_table` checks a table against it.
Errors are :class:`SceneError`: one line ``KEY: message`` naming the key path
(``interfaces[0].radius``) and the valid choices. The frozen dataclasses
(:mod:`xfem_contact.scenes.records`) are what :func:`xfem_contact.scenes.scene.load_scene`
returns.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import re
from collections.abc import Callable

from xfem_contact.mechanics.laws import CONTACT_LAWS, LBB_OPTIONS, LINEAR_LAWS
from xfem_contact.mechanics.sliding.coupling import PAIRING_UPDATES
from xfem_contact.scenes.expressions import check_expression
from xfem_contact.scenes.records import InterfaceSpec, LoadSpec, Scene  # noqa: F401
from xfem_contact.solvers.options import LINEAR_PRESETS, defaults

_NEWTON = defaults("newton")  # the [solver] defaults are the Newton solver's

LAWS = LINEAR_LAWS + CONTACT_LAWS
SHAPES = ("circle", "ellipse", "line", "half-plane", "expression")
LOAD_TYPES = (
    "pressure",
    "traction",
    "displacement",
    "point_displacement",
    "body_force",
    "rotation",
    "tangential_support",
)
KINEMATICS = ("small", "large")
CELLS = ("quadrilateral", "triangle")
MESH_KINDS = ("rectangle", "annulus", "gmsh")
BUILTIN_PARTS = {
    "rectangle": ("left", "right", "bottom", "top", "boundary"),
    "annulus": ("inner", "outer", "boundary"),
    "gmsh": ("boundary",),  # plus the file's named 1-D physical groups
}
#: Keys in which the interfaces of one scene must agree: they lie in one body (the
#: outside material) and share the kinematics; laws and inside materials may differ
SHARED_INTERFACE_KEYS = ("kinematics", "outside", "slave", "pairing")
#: The [mesh] keys each mesh kind reads (besides ``kind``)
MESH_KEYS = {
    "rectangle": ("corners", "cells", "cell"),
    "annulus": ("radii", "cells", "geometry_degree"),
    "gmsh": ("file", "size", "cell", "geometry_degree"),
}
#: The parameters of each interface shape: (required, optional)
SHAPE_KEYS = {
    "circle": (("centre", "radius"), ()),
    "ellipse": (("centre", "axes"), ("angle", "angle_deg")),
    "line": (("point", "normal"), ()),
    "half-plane": (("point", "normal"), ()),
    "expression": (("expression",), ()),
}
#: The keys of each load type besides ``type``: (required, optional)
LOAD_KEYS = {
    "pressure": (("part", "value"), ("side", "history")),
    "traction": (("part", "value"), ("side", "history")),
    "displacement": (("part", "value"), ("component", "history")),
    "point_displacement": (("point", "component", "value"), ("history",)),
    "body_force": (("value",), ("side", "history")),
    "rotation": (("part",), ("value", "angle_deg", "centre", "history")),
    "tangential_support": (("part", "value"), ()),
}


class SceneError(ValueError):
    """Bad scene input: one line ``KEY: message`` (``key`` the path, ``interfaces[0].radius``)."""

    def __init__(self, key: str, message: str):
        self.key, self.message = key, message
        super().__init__(f"{key}: {message}" if key else message)


def join(key: str, name) -> str:
    """The path of ``name`` in the table at ``key`` (odd names quoted, one line)."""
    if isinstance(name, int):
        return f"{key}[{name}]"
    name = name if re.fullmatch(r"[A-Za-z0-9_-]+", name) else repr(name)
    return f"{key}.{name}" if key else name


def describe(value) -> str:
    """``value`` in a message: its kind and a short one-line repr."""
    kinds = ((bool, "boolean"), (numbers.Integral, "integer"), (numbers.Real, "number"))
    kinds += ((str, "string"), (list | tuple, "list"), (dict, "table"))
    kind = next((name for t, name in kinds if isinstance(value, t)), type(value).__name__)
    text = repr(value)
    return f"{kind} {text if len(text) <= 40 else text[:36] + ' ...'}"


@dataclasses.dataclass(frozen=True)
class Number:
    """A finite number (integer with ``integer``) in ``low <(=) value <(=) high``."""

    low: float | None = None
    high: float | None = None
    open: bool = False  # strict bounds
    integer: bool = False

    def __call__(self, value, key: str):
        kind = numbers.Integral if self.integer else numbers.Real
        if isinstance(value, bool) or not isinstance(value, kind):
            article = "an integer" if self.integer else "a number"
            raise SceneError(key, f"expected {article}, got {describe(value)}")
        if isinstance(value, numbers.Integral) and abs(value) > 2**63:
            raise SceneError(key, f"{describe(value)} is out of range")
        if not math.isfinite(value):
            raise SceneError(key, f"must be a finite number, got {value}")
        low = self.low is None or (value > self.low if self.open else value >= self.low)
        high = self.high is None or (value < self.high if self.open else value <= self.high)
        if not (low and high):
            raise SceneError(key, f"must be {self.bounds()}, got {value}")
        return value

    def bounds(self) -> str:
        if self.low is not None and self.high is not None:
            brackets = "()" if self.open else "[]"
            return f"in {brackets[0]}{self.low}, {self.high}{brackets[1]}"
        if self.high is None:
            return f"{'>' if self.open else '>='} {self.low}"
        return f"{'<' if self.open else '<='} {self.high}"


@dataclasses.dataclass(frozen=True)
class Choice:
    """One of ``choices`` (of their type: ``True`` is not ``1``)."""

    choices: tuple

    def __call__(self, value, key: str):
        if not any(type(value) is type(c) and value == c for c in self.choices):
            message = f"{describe(value)} is not valid; choose one of {list(self.choices)}"
            raise SceneError(key, message)
        return value


@dataclasses.dataclass(frozen=True)
class Text:
    """A string, matching ``pattern`` if given (``rule`` says it in words)."""

    pattern: str | None = None
    rule: str = ""

    def __call__(self, value, key: str):
        if not isinstance(value, str):
            raise SceneError(key, f"expected a string, got {describe(value)}")
        if self.pattern and not re.fullmatch(self.pattern, value):
            raise SceneError(key, f"{describe(value)}: {self.rule}")
        return value


def flag(value, key: str):
    if not isinstance(value, bool):
        raise SceneError(key, f"expected true or false, got {describe(value)}")
    return value


@dataclasses.dataclass(frozen=True)
class Vector:
    """A list of ``n`` entries, each checked by ``item``."""

    n: int
    item: Callable

    def __call__(self, value, key: str):
        if not isinstance(value, list | tuple) or len(value) != self.n:
            raise SceneError(key, f"expected a list of {self.n} entries, got {describe(value)}")
        return tuple(self.item(v, join(key, i)) for i, v in enumerate(value))


@dataclasses.dataclass(frozen=True)
class Scalar:
    """A number or an expression of x, y for ``target`` (see :func:`check_expression`)."""

    target: str = "number"

    def __call__(self, value, key: str):
        if isinstance(value, str):
            check_expression(value, key, self.target)
            return value
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            message = f"expected a number or an expression string, got {describe(value)}"
            raise SceneError(key, message)
        return Number()(value, key)


@dataclasses.dataclass(frozen=True)
class Expression:
    """An expression string of x, y for ``target`` (see :func:`check_expression`)."""

    target: str = "number"

    def __call__(self, value, key: str):
        if not isinstance(value, str):
            raise SceneError(key, f"expected an expression string, got {describe(value)}")
        check_expression(value, key, self.target)
        return value


def petsc_table(value, key: str):
    """A table of PETSc options: strings, finite numbers or booleans."""
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a table of PETSc options, got {describe(value)}")
    for name, option in value.items():
        if not isinstance(option, str | numbers.Real):
            message = f"expected a string, number or boolean, got {describe(option)}"
            raise SceneError(join(key, name), message)
        if isinstance(option, numbers.Real) and not isinstance(option, bool):
            Number()(option, join(key, name))
    return value


def load_path(value, key: str):
    """A load path: a stage name, or ``[[time, factor], ...]`` with times increasing."""
    if isinstance(value, str):
        return _NAME(value, key)
    if not isinstance(value, list | tuple) or not value:
        message = f"expected a stage name or a list of [time, factor] pairs, got {describe(value)}"
        raise SceneError(key, message)
    times = [Vector(2, Number())(pair, join(key, i))[0] for i, pair in enumerate(value)]
    if any(b <= a for a, b in zip(times, times[1:], strict=False)):
        raise SceneError(key, f"the times must increase strictly, got {times}")
    return value


def stages_table(value, key: str) -> dict[str, tuple[float, float]]:
    """The [stages] table: ``NAME = [start, end]`` pseudo-times, ``start < end``."""
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a table of NAME = [start, end], got {describe(value)}")
    stages = {}
    for name, interval in value.items():
        where = join(key, name)
        _NAME(name, where)
        start, end = Vector(2, Number())(interval, where)
        if not start < end:
            raise SceneError(where, f"start {start} must be before end {end}")
        stages[name] = (float(start), float(end))
    return stages


@dataclasses.dataclass(frozen=True)
class Field:
    """A key of a table: its check, its meaning, whether it must be given."""

    check: Callable
    doc: str
    required: bool = False


_POSITIVE = Number(0.0, open=True)
_NAME = Text(r"[A-Za-z0-9_.-]+", "use letters, digits, '_', '-' or '.'")
_POINT = Vector(2, Number())
_DEGREE = Choice((1, 2))
#: Every key of every table: its check and meaning (the schema in one place)
FIELDS = {
    "scene": {
        "name": Field(_NAME, "scene name (names the default output folder results/NAME)"),
        "description": Field(Text(), "free text"),
    },
    "mesh": {
        "kind": Field(Choice(MESH_KINDS), f"one of {MESH_KINDS}"),
        "file": Field(Text(), "a gmsh .geo or .msh file, relative to the scene file (gmsh)"),
        "size": Field(_POSITIVE, "target cell size (m) when meshing a .geo file (gmsh)"),
        "corners": Field(Vector(2, _POINT), "[[x0, y0], [x1, y1]] (m, rectangle)"),
        "radii": Field(
            Vector(2, _POSITIVE), "[r_inner, r_outer] (m, annulus centred at the origin)"
        ),
        "cells": Field(Vector(2, Number(1, integer=True)), "[nx, ny] or [n_radial, n_angular]"),
        "cell": Field(Choice(CELLS), f"one of {CELLS}"),
        "geometry_degree": Field(
            _DEGREE, "1 (straight cells) or 2 (curved cells: annulus, gmsh .geo)"
        ),
    },
    "discretisation": {
        "degree": Field(_DEGREE, "displacement degree 1 or 2"),
        "levelset_degree": Field(_DEGREE, "1 or 2"),
        "quadrature_degree": Field(Number(1, 30, integer=True), ">= 1 and <= 30"),
    },
    "interface": {
        "name": Field(_NAME, "label (names the multiplier field)"),
        "shape": Field(Choice(SHAPES), f"one of {SHAPES}", required=True),
        "centre": Field(_POINT, "[x, y] (m)"),
        "radius": Field(_POSITIVE, "(m) > 0"),
        "axes": Field(Vector(2, _POSITIVE), "[a, b] (m) > 0"),
        "angle": Field(Number(), "(rad) in [-2 pi, 2 pi]; or angle_deg"),
        "angle_deg": Field(Number(), "(degrees), instead of angle"),
        "point": Field(_POINT, "[x, y]"),
        "normal": Field(_POINT, "[nx, ny], non-zero"),
        "expression": Field(Expression(), "phi(x, y), negative inside"),
        "law": Field(Choice(LAWS), f"one of {LAWS}"),
        "friction": Field(Number(0.0), "Coulomb coefficient >= 0"),
        "augmentation": Field(_POSITIVE, "> 0"),
        "lbb": Field(Choice(LBB_OPTIONS), " | ".join(LBB_OPTIONS)),
        "kinematics": Field(Choice(KINEMATICS), f"one of {KINEMATICS}"),
        "slave": Field(Choice((-1, 1)), "slave side -1 or +1 (large kinematics; default -1)"),
        "master": Field(Choice((-1, 1)), "master side, the other one (large kinematics)"),
        "pairing": Field(
            Choice(PAIRING_UPDATES), f"one of {PAIRING_UPDATES} (large kinematics; default iterate)"
        ),
        "inside": Field(Text(), "material of side -1"),
        "outside": Field(Text(), "material of side +1"),
    },
    "material": {
        "E": Field(_POSITIVE, "Young's modulus (Pa) > 0", required=True),
        "nu": Field(Number(-1.0, 0.5, open=True), "Poisson ratio in (-1, 0.5)", required=True),
        "plane": Field(Choice(("strain", "stress")), "strain | stress"),
    },
    "solver": {
        "load_steps": Field(
            Number(1, 10_000, integer=True), "number of equal load steps (>= 1, default 1)"
        ),
        "end_time": Field(
            _POSITIVE,
            "pseudo-time of the last step (steps at k end_time / load_steps; default: the "
            "last time of any history or stage, at least 1)",
        ),
        "max_iterations": Field(
            Number(1, 10_000, integer=True),
            f"Newton iterations per step (default {_NEWTON['snes_max_it']})",
        ),
        "rtol": Field(_POSITIVE, f"relative Newton tolerance (default {_NEWTON['snes_rtol']})"),
        "atol": Field(_POSITIVE, f"absolute Newton tolerance (default {_NEWTON['snes_atol']})"),
        "linear": Field(
            Choice(tuple(LINEAR_PRESETS)),
            f"linear solver of the Newton steps: one of {tuple(LINEAR_PRESETS)} (default direct)",
        ),
        "petsc": Field(petsc_table, "table of extra PETSc options (without prefix)"),
    },
    "part": {
        "where": Field(
            Expression("boolean"), "boolean expression of x, y selecting boundary facets", True
        )
    },
    "load": {
        "part": Field(Text(), "a boundary part name"),
        "type": Field(Choice(LOAD_TYPES), f"one of {LOAD_TYPES}", required=True),
        "value": Field(lambda value, key: value, "number, [vx, vy], or expression(s) of x, y"),
        "side": Field(Choice((-1, 1)), "-1 or +1 (default both)"),
        "component": Field(Choice((0, 1)), "0 or 1 (displacement)"),
        "point": Field(_POINT, "[x, y] (point_displacement)"),
        "centre": Field(_POINT, "[x, y] (m), centre of a rotation (default [0, 0])"),
        "angle_deg": Field(Number(), "rotation angle in degrees (instead of value, in rad)"),
        "history": Field(
            load_path,
            "load path: [[t, factor], ...] (piecewise linear in pseudo-time t) or a stage "
            "name (default: factor = t)",
        ),
    },
    "outputs": {
        "vtx": Field(flag, "write VTX fields (bool)"),
        "png": Field(flag, "write pictures (bool)"),
    },
}
#: The meaning of every key of every table (the text of :data:`FIELDS`)
SCHEMA = {table: {key: f.doc for key, f in fields.items()} for table, fields in FIELDS.items()}
TOP_LEVEL = (
    "scene",
    "stages",
    "mesh",
    "discretisation",
    "materials",
    "interfaces",
    "parts",
    "loads",
    "solver",
    "outputs",
)


def check_table(value, fields: dict[str, Field], key: str) -> dict:
    """``value`` checked as a table of ``fields``: its type, unknown keys, missing required
    keys and every given value. Returns ``value``; raises :class:`SceneError`."""
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a table, got {describe(value)}")
    unknown = [name for name in value if name not in fields]
    if unknown:
        raise SceneError(join(key, unknown[0]), f"unknown key; valid: {list(fields)}")
    for name, field in fields.items():
        if name in value:
            field.check(value[name], join(key, name))
        elif field.required:
            raise SceneError(join(key, name), f"required: {field.doc}")
    return value
