"""The checks of scene values: each a callable ``check(value, key)`` that returns the value
(or its checked form) or raises :class:`SceneError`, one line ``KEY: message`` naming the
key path and the valid choices. :mod:`xfem_contact.scenes.schema` builds its tables of
keys (:data:`~xfem_contact.scenes.schema.FIELDS`) from them.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import re
from collections.abc import Callable

from xfem_contact.scenes.expressions import check_expression


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
    """A number or an expression of x, y (and z: ``dim`` 3) for ``target`` (see
    :func:`check_expression`)."""

    target: str = "number"
    dim: int = 2

    def __call__(self, value, key: str):
        if isinstance(value, str):
            check_expression(value, key, self.target, self.dim)
            return value
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            message = f"expected a number or an expression string, got {describe(value)}"
            raise SceneError(key, message)
        return Number()(value, key)


@dataclasses.dataclass(frozen=True)
class Expression:
    """An expression string of x, y (and z: ``dim`` 3) for ``target`` (see
    :func:`check_expression`)."""

    target: str = "number"
    dim: int = 2

    def __call__(self, value, key: str):
        if not isinstance(value, str):
            raise SceneError(key, f"expected an expression string, got {describe(value)}")
        check_expression(value, key, self.target, self.dim)
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
        return NAME(value, key)
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
        NAME(name, where)
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


NAME = Text(r"[A-Za-z0-9_.-]+", "use letters, digits, '_', '-' or '.'")


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


def material_name(table, key: str, where: str, materials) -> str:
    """The material a scene table names at ``key`` (default: the first of ``materials``),
    checked to be one of ``materials``."""
    name = table.get(key, next(iter(materials)))
    if name not in materials:
        message = f"{name!r}: no such material; defined: {sorted(materials)}"
        raise SceneError(f"{where}.{key}", message)
    return name
