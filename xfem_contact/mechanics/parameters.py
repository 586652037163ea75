"""Parameters of the forms as data: validated scalars that enter UFL as ``fem.Constant``.

A law, a bulk model or a material declares its tunable scalars as :class:`Parameter`
attributes. Reading one gives a float; assigning one validates the value and updates
the ``dolfinx.fem.Constant`` that every form built from the object holds, so a new
value (a friction sweep, a stiffer inclusion, a larger augmentation) costs a new
assembly and never a new compile: the forms' signatures do not depend on the values.

An object's Constants are made when it is bound to a mesh (:func:`bind`, which the
problem does at construction); an object serves one mesh (a problem on another mesh
takes a copy, :func:`bound_copy`).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import numbers
from collections.abc import Callable

import dolfinx.fem
import dolfinx.mesh
import numpy as np

_STORE = "_parameters"


@dataclasses.dataclass
class _Store:
    """The values of an object's parameters and, once bound, their Constants."""

    values: dict[str, float] = dataclasses.field(default_factory=dict)
    constants: dict[str, dolfinx.fem.Constant] = dataclasses.field(default_factory=dict)
    mesh: dolfinx.mesh.Mesh | None = None
    #: Called with (name, value) after every change (e.g. to refill a DG0 field)
    listeners: list[Callable[[str, float], None]] = dataclasses.field(default_factory=list)


def is_number(value) -> bool:
    """Whether ``value`` is a real number (Python's or NumPy's), neither a bool nor a
    string: what every parameter, magnitude and time accepts."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


def _store(obj) -> _Store:
    store = obj.__dict__.get(_STORE)
    if store is None:
        store = obj.__dict__[_STORE] = _Store()
    return store


class Parameter:
    """A scalar parameter of a model object (a descriptor).

    Args:
        unit: The unit, for messages (``"Pa"``, ``"1"``, ...).
        minimum: The smallest valid value (None: no bound).
        strict: Whether ``minimum`` itself is invalid (``> minimum``).
        maximum: The largest valid value, always excluded (None: no bound).
    """

    def __init__(
        self,
        unit: str = "1",
        minimum: float | None = None,
        strict: bool = False,
        maximum: float | None = None,
    ):
        self.unit, self.minimum, self.strict, self.maximum = unit, minimum, strict, maximum
        self.name = "parameter"

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        try:
            return _store(obj).values[self.name]
        except KeyError:
            raise AttributeError(f"{type(obj).__name__}.{self.name} is not set") from None

    def __set__(self, obj, value) -> None:
        value = self.check(value, f"{getattr(obj, 'name', type(obj).__name__)} {self.name}")
        if hasattr(obj, "check_parameter"):  # the owner's own rule (e.g. a term not built)
            obj.check_parameter(self.name, value)
        store = _store(obj)
        store.values[self.name] = value
        if self.name in store.constants:
            store.constants[self.name].value = value
        for listener in store.listeners:
            listener(self.name, value)

    def requirement(self) -> str:
        """The valid range in words, e.g. ``"> 0 Pa"``."""
        parts = []
        if self.minimum is not None:
            parts.append(f"{'>' if self.strict else '>='} {self.minimum:g}")
        if self.maximum is not None:
            parts.append(f"< {self.maximum:g}")
        return " and ".join(parts) + ("" if self.unit == "1" else f" {self.unit}")

    def check(self, value, what: str) -> float:
        """``value`` as a float, or a one-line ValueError naming ``what`` and the valid
        range (strings and bools are refused: ``"0.3"`` is not a number)."""
        x = float(value) if is_number(value) else math.nan
        low = self.minimum is not None and (x <= self.minimum if self.strict else x < self.minimum)
        high = self.maximum is not None and x >= self.maximum
        if not math.isfinite(x) or low or high:
            valid = self.requirement()
            raise ValueError(
                f"{what} must be a finite number{' ' + valid if valid else ''}, got {value!r}"
            )
        return x


def parameter_names(obj) -> list[str]:
    """Names of the :class:`Parameter` attributes of ``obj``'s class (MRO order)."""
    names = []
    for cls in reversed(type(obj).__mro__):
        names += [k for k, v in vars(cls).items() if isinstance(v, Parameter) and k not in names]
    return names


def values(obj) -> dict[str, float]:
    """The parameters of ``obj`` that are set, by name."""
    return {k: v for k, v in _store(obj).values.items() if k in parameter_names(obj)}


def bind(obj, mesh: dolfinx.mesh.Mesh) -> None:
    """Make the Constants of ``obj``'s parameters on ``mesh`` (once; not collective).

    Raises:
        ValueError: if ``obj`` is bound to another mesh already.
    """
    store = _store(obj)
    if store.mesh is not None and store.mesh is not mesh:
        raise ValueError(
            f"{type(obj).__name__} is bound to another mesh; give each problem its own "
            "object (or a copy)"
        )
    store.mesh = mesh
    for name in parameter_names(obj):
        if name in store.values and name not in store.constants:
            store.constants[name] = dolfinx.fem.Constant(
                mesh, dolfinx.default_scalar_type(store.values[name])
            )


def bound_copy(obj, mesh: dolfinx.mesh.Mesh):
    """``obj`` bound to ``mesh``: itself when free or bound there already, else a
    copy with the same values and Constants of its own."""
    store = _store(obj)
    if store.mesh is not None and store.mesh is not mesh:
        obj = copy.copy(obj)
        obj.__dict__[_STORE] = _Store(values=dict(store.values))
    bind(obj, mesh)
    return obj


def constant(obj, name: str) -> dolfinx.fem.Constant:
    """The Constant of parameter ``name`` of a bound ``obj`` (UFL).

    Raises:
        ValueError: if ``obj`` is not bound to a mesh yet.
    """
    store = _store(obj)
    if name not in store.constants:
        raise ValueError(
            f"{type(obj).__name__}.{name} has no Constant: bind the object to a mesh first "
            "(a problem does so when it is built)"
        )
    return store.constants[name]


def listen(obj, listener: Callable[[str, float], None]) -> None:
    """Call ``listener(name, value)`` after every change of a parameter of ``obj``."""
    _store(obj).listeners.append(listener)
