"""Handles of the loads of a :class:`~xfem_contact.mechanics.loads.Loads`.

Each ``add_*`` returns one: its ``value`` (the magnitude at factor 1) can be read and
set, and ``apply(t)`` sets its factor ``path(t)``. Setting a value changes data
(a Constant, the arrays of Dirichlet functions), never a form: nothing compiles.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping

import dolfinx.fem
import numpy as np

from xfem_contact.mechanics.loads.load_path import LoadPath
from xfem_contact.mechanics.loads.values import finite_number, nodal_values, set_constant
from xfem_contact.mechanics.parameters import Parameter

#: A tangential spring's stiffness (Pa/m)
STIFFNESS = Parameter("Pa/m", minimum=0.0, strict=True)


def rotation_angle(angle, name: str = "angle") -> float:
    """``angle`` (rad) as a float: a finite number, refused in one line naming ``name``;
    warns (at the caller's caller) beyond a full turn: degrees given as radians?"""
    angle = finite_number(angle, name)
    if abs(angle) > 2 * np.pi:
        warnings.warn(
            f"{name}={angle} rad is more than a full turn; for degrees use angle_deg=",
            UserWarning,
            stacklevel=3,
        )
    return angle


#: The deprecation of a load's ``history``
_HISTORY = "Load.history is deprecated and will be removed in the next release: use Load.path"


class Load:
    """A load or support: its ``kind``, ``part`` (name, or None when given otherwise)
    and :class:`LoadPath`."""

    def __init__(self, kind: str, part, path: LoadPath):
        self.kind, self.path = kind, path
        self.part = part if isinstance(part, str) else None
        self._t = 1.0

    def apply(self, t: float) -> None:
        """Set this load to its value at pseudo-time ``t``."""
        self._t = t

    def __repr__(self) -> str:
        part = f" on {self.part!r}" if self.part else ""
        return f"<{self.kind}{part}: value {self.value!r}, {self.path!r}>"

    @property
    def history(self) -> LoadPath:
        """Deprecated name of :attr:`path`."""
        warnings.warn(_HISTORY, DeprecationWarning, stacklevel=2)
        return self.path

    @history.setter
    def history(self, path: LoadPath) -> None:
        warnings.warn(_HISTORY, DeprecationWarning, stacklevel=2)
        self.path = path


class FormLoad(Load):
    """A load of the residual (traction, pressure, body force): ``factor * magnitude``,
    both UFL Constants when the magnitude was given as numbers."""

    def __init__(self, kind, part, path, magnitude, constant, mesh):
        super().__init__(kind, part, path)
        self.magnitude, self._constant = magnitude, constant
        #: The factor ``path(t)`` (dimensionless) multiplying the magnitude in the form
        self.factor = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))

    @property
    def value(self):
        """The magnitude (a float or a tuple; the UFL expression if given as one)."""
        if self._constant is None:
            return self.magnitude
        value = self._constant.value
        return float(value) if value.shape == () else tuple(value.tolist())

    @value.setter
    def value(self, value) -> None:
        if self._constant is None:
            raise ValueError(
                f"The {self.kind} was given as an expression; only a magnitude given as "
                "numbers can be set (add it with a number or a tuple)"
            )
        set_constant(self._constant, value, self.kind)

    def apply(self, t: float) -> None:
        super().apply(t)
        self.factor.value = self.path(t)


class DirichletLoad(Load):
    """A prescribed displacement: functions ``g`` (one per side) set to ``path(t)``
    times their full values (m), the values interpolated from ``value`` on each
    function's space."""

    def __init__(
        self, kind, part, path, functions: list[dolfinx.fem.Function], value, sides=(None,)
    ):
        super().__init__(kind, part, path)
        self.functions, self.sides = functions, tuple(sides)
        self.value = value

    @property
    def value(self):
        """The prescribed value (m): a number, a tuple or a callable of ``x``, or a mapping
        ``{side: value}`` giving each side's field its own (e.g. the two lips' values
        where a crack meets the boundary)."""
        return self._value

    @value.setter
    def value(self, value) -> None:
        values = [value] * len(self.functions)
        if isinstance(value, Mapping):
            if set(value) != set(self.sides) or None in self.sides:
                valid = [s for s in self.sides if s is not None]
                raise ValueError(
                    f"{self.kind}: a value per side needs exactly the sides {valid}, got "
                    f"{sorted(value, key=str)}"
                )
            values = [value[s] for s in self.sides]
        full = [
            nodal_values(g.function_space, v, self.kind)
            for g, v in zip(self.functions, values, strict=True)
        ]
        self._value, self._full = value, full
        self.apply(self._t)

    def apply(self, t: float) -> None:
        super().apply(t)
        f = self.path(t)
        for g, full in zip(self.functions, self._full, strict=True):
            g.x.array[:] = f * full


class RotationLoad(Load):
    """A rigid rotation of a boundary part by ``path(t)`` times ``value`` (rad,
    counter-clockwise) about ``centre`` (m): ``u = (Q - I)(X - c)`` (the angle ramps,
    so each step is an exact rotation)."""

    def __init__(self, part, path, functions, arms, angle: float, centre, nodes):
        super().__init__("rotation", part, path)
        self.functions, self.arms, self.centre = functions, arms, centre
        #: ``(dofs (k, 2), reference nodes (k, 2))`` of the rotated bodies (predictor)
        self.nodes = nodes
        self._angle = angle  # checked by the caller
        self.apply(self._t)

    @property
    def value(self) -> float:
        """The angle (rad) at factor 1."""
        return self._angle

    @value.setter
    def value(self, angle: float) -> None:
        self._angle = rotation_angle(angle)
        self.apply(self._t)

    def apply(self, t: float) -> None:
        super().apply(t)
        a = self.path(t) * self._angle
        c, s = np.cos(a), np.sin(a)
        for g, arm in zip(self.functions, self.arms, strict=True):
            g.x.array[:] = np.column_stack(
                [(c - 1) * arm[:, 0] - s * arm[:, 1], s * arm[:, 0] + (c - 1) * arm[:, 1]]
            ).ravel()

    def rotate(self, w: dolfinx.fem.Function, t_from: float, t_to: float) -> None:
        """Turn the deformed configuration of the rotated bodies in ``w`` by the angle
        between ``t_from`` and ``t_to`` (a predictor: exact for a rigidly turning body)."""
        delta = (self.path(t_to) - self.path(t_from)) * self._angle
        if self.nodes is None or delta == 0.0:
            return
        dofs, X = self.nodes
        Q = np.array([[np.cos(delta), -np.sin(delta)], [np.sin(delta), np.cos(delta)]])
        x = X + w.x.array[dofs]
        w.x.array[dofs] = (x - self.centre) @ Q.T + self.centre - X


class TangentialSpring(Load):
    """A tangential spring (Pa/m): its stiffness a Constant; not ramped (a support)."""

    def __init__(self, part, facets: np.ndarray, stiffness: dolfinx.fem.Constant):
        super().__init__("tangential spring", part, LoadPath([(0.0, 1.0)]))
        self.facets, self.stiffness = facets, stiffness

    @property
    def value(self) -> float:
        """The stiffness (Pa/m)."""
        return float(self.stiffness.value)

    @value.setter
    def value(self, stiffness: float) -> None:
        self.stiffness.value = STIFFNESS.check(stiffness, "The spring stiffness")
