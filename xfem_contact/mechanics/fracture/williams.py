"""Williams near-tip fields: the four branch functions of the tip enrichment and the exact
mode I / mode II displacement and stress of a crack tip, for numpy and UFL from one definition.

Conventions (SI units). A tip is a :class:`TipFrame`: its position and the crack's
direction ``d`` at the tip (a unit vector pointing ahead of the tip, out of the crack).
The local frame has ``x1`` along ``d`` and ``x2`` along ``d`` turned by +90 degrees; the
crack lies on ``x2 = 0, x1 < 0``; ``theta`` is in ``(-pi, pi]``, ``+pi`` on the upper lip
(``x2 -> 0+``) and ``-pi`` on the lower. Every function takes the points as ``x`` with
``x[0]``, ``x[1]`` the global coordinates (m): numpy arrays of any common shape (e.g.
DOLFINx's ``(3, n)`` interpolation points) or ``ufl.SpatialCoordinate(mesh)``, and an
:class:`Ops` (:data:`NUMPY` or :data:`UFL`) saying which. Vectors come back as
``ops.vector`` (numpy: shape ``(2, *x[0].shape)``), tensors as ``ops.matrix`` (numpy:
``(2, 2, *x[0].shape)``; gradients are ``G[i, j] = d u_i / d x_j``).

The Williams displacements are combinations of the branch functions (so the tip
enrichment reproduces them exactly), with ``c = 1 / (2 mu sqrt(2 pi))``::

    u1 = c [K_II (kappa + 1) F1 + K_I (kappa - 1) F2 + K_I F3 + K_II F4]
    u2 = c [K_I (kappa + 1) F1 + K_II (1 - kappa) F2 + K_II F3 - K_I F4]

and their stresses are Hooke's law of those gradients.
"""

from __future__ import annotations

import dataclasses
import math
import typing

import numpy as np

from xfem_contact.fem.branch import NUMPY, UFL, Ops, angular, branch_values  # noqa: F401

PLANES = ("strain", "stress")


class TipFrame(typing.NamedTuple):
    """A crack tip: ``origin`` (m) and unit ``direction`` of the crack ahead of the tip,
    each a pair of numbers or a 2-vector ``dolfinx.fem.Constant`` (build it with
    :func:`tip_frame` from numbers, which checks and normalises)."""

    origin: typing.Any
    direction: typing.Any


def tip_frame(origin, direction) -> TipFrame:
    """A :class:`TipFrame` of numbers: ``origin`` (m) and ``direction`` (normalised here).

    Raises:
        ValueError: ``origin`` or ``direction`` not two finite numbers, or a zero direction.
    """
    values = []
    for name, v in (("origin", origin), ("direction", direction)):
        v = np.asarray(v, dtype=np.float64).ravel()
        if v.shape != (2,) or not np.all(np.isfinite(v)):
            raise ValueError(f"{name} must be two finite numbers (x, y), got {v.tolist()}")
        values.append(v)
    norm = float(np.hypot(*values[1]))
    if norm == 0.0:
        raise ValueError("direction must be a non-zero vector (x, y), got (0, 0)")
    return TipFrame(values[0], values[1] / norm)


def local_coordinates(x, frame: TipFrame) -> tuple:
    """``(x1, x2)`` (m) of the points ``x`` in the tip frame."""
    dx, dy = x[0] - frame.origin[0], x[1] - frame.origin[1]
    c, s = frame.direction[0], frame.direction[1]
    return c * dx + s * dy, c * dy - s * dx


def polar(x, frame: TipFrame, ops: Ops = NUMPY, side: int = 0) -> tuple:
    """``(r, theta)`` (m, rad) of the points ``x`` around the tip.

    Args:
        side: 0 for points off the crack (``theta = atan2(x2, x1)``); +1 or -1 for points
            on the upper or lower lip, where ``theta = side |atan2(x2, x1)|`` takes the
            side's limit whatever the sign of a round-off ``x2``.
    """
    if side not in (-1, 0, 1):
        raise ValueError(f"side must be -1, 0 or 1, got {side!r}")
    x1, x2 = local_coordinates(x, frame)
    theta = ops.atan2(x2, x1)
    return ops.sqrt(x1 * x1 + x2 * x2), side * abs(theta) if side else theta


def branch_polar(r, theta, ops: Ops = NUMPY) -> tuple[tuple, tuple, tuple]:
    """``F_j`` (m^1/2), ``dF_j/dr`` (m^-1/2) and ``dF_j/dtheta`` (m^1/2 per rad), each a
    4-tuple (:func:`branch_values`), at polar coordinates ``(r, theta)``, ``r > 0``."""
    sr = ops.sqrt(r)
    factors, d_factors = angular(theta, ops)
    return (
        tuple(sr * a for a in factors),
        tuple(a / (2 * sr) for a in factors),
        tuple(sr * a for a in d_factors),
    )


def branch_local_gradients(r, theta, ops: Ops = NUMPY) -> tuple[tuple, tuple]:
    """``(dF_j/dx1, dF_j/dx2)`` (m^-1/2, each a 4-tuple) in the tip frame, by the chain rule
    ``d/dx1 = cos(t) d/dr - sin(t)/r d/dt``, ``d/dx2 = sin(t) d/dr + cos(t)/r d/dt``."""
    _, d_r, d_t = branch_polar(r, theta, ops)
    s, c, sr = ops.sin(theta), ops.cos(theta), ops.sqrt(r)
    d_t_r = tuple(g / sr / sr for g in d_t)
    return (
        tuple(c * a - s * b for a, b in zip(d_r, d_t_r, strict=True)),
        tuple(s * a + c * b for a, b in zip(d_r, d_t_r, strict=True)),
    )


def to_global_vector(v: tuple, frame: TipFrame) -> tuple:
    """Global components of a vector ``(v1, v2)`` given in the tip frame."""
    c, s = frame.direction[0], frame.direction[1]
    return c * v[0] - s * v[1], s * v[0] + c * v[1]


def to_global_tensor(t: tuple, frame: TipFrame) -> tuple:
    """Global components ``R t R^T`` of a 2 x 2 tensor (a pair of rows) given in the tip frame."""
    columns = [to_global_vector((t[0][j], t[1][j]), frame) for j in range(2)]  # R t
    rows = [(columns[0][i], columns[1][i]) for i in range(2)]
    return tuple(to_global_vector(row, frame) for row in rows)  # (R (R t)^T)^T


def branch_functions(x, frame: TipFrame, ops: Ops = NUMPY, side: int = 0):
    """The four branch functions at ``x`` (m^1/2), ``ops.vector`` of 4."""
    return ops.vector(branch_values(*polar(x, frame, ops, side), ops))


def branch_gradients(x, frame: TipFrame, ops: Ops = NUMPY, side: int = 0):
    """Global gradients of the branch functions at ``x`` (m^-1/2), ``ops.matrix`` 4 x 2."""
    g1, g2 = branch_local_gradients(*polar(x, frame, ops, side), ops)
    return ops.matrix([to_global_vector((a, b), frame) for a, b in zip(g1, g2, strict=True)])


def kolosov(nu, plane: str):
    """Kolosov's constant: ``3 - 4 nu`` (plane strain) or ``(3 - nu) / (1 + nu)`` (stress)."""
    if plane not in PLANES:
        raise ValueError(f"plane must be one of {PLANES}, got {plane!r}")
    return 3 - 4 * nu if plane == "strain" else (3 - nu) / (1 + nu)


def effective_modulus(E, nu, plane: str):
    """``E'`` (Pa): ``E / (1 - nu^2)`` in plane strain, ``E`` in plane stress."""
    kolosov(nu, plane)  # checks plane
    return E / (1 - nu * nu) if plane == "strain" else E


@dataclasses.dataclass(frozen=True)
class WilliamsField:
    """The exact near-tip field of stress intensity factors ``K_I``, ``K_II`` (Pa m^1/2).

    ``K_I``, ``K_II``, ``E`` (Pa) and ``nu`` may be numbers or UFL (e.g. Constants): the
    same object gives numpy values (``ops=NUMPY``) and UFL expressions (``ops=UFL``).
    ``side`` as in :func:`polar` (non-zero only for points on the lips).
    """

    frame: TipFrame
    K_I: typing.Any
    K_II: typing.Any
    E: typing.Any
    nu: typing.Any
    plane: str = "strain"

    def __post_init__(self):
        kolosov(0.0, self.plane)

    @property
    def mu(self):
        """Shear modulus (Pa)."""
        return self.E / (2 * (1 + self.nu))

    @property
    def lmbda(self):
        """Lame's first parameter of the 2D law (Pa), ``mu (3 - kappa) / (kappa - 1)``."""
        kappa = kolosov(self.nu, self.plane)
        return self.mu * (3 - kappa) / (kappa - 1)

    def coefficients(self) -> tuple[tuple, tuple]:
        """Rows of the 2 x 4 map from the branch functions to the local displacement."""
        kappa, c = kolosov(self.nu, self.plane), 1 / (2 * self.mu * math.sqrt(2 * math.pi))
        K1, K2 = self.K_I, self.K_II
        return (
            (c * K2 * (kappa + 1), c * K1 * (kappa - 1), c * K1, c * K2),
            (c * K1 * (kappa + 1), c * K2 * (1 - kappa), c * K2, -c * K1),
        )

    def _local_gradient(self, x, ops: Ops, side: int) -> tuple:
        g1, g2 = branch_local_gradients(*polar(x, self.frame, ops, side), ops)
        return tuple((_dot(row, g1), _dot(row, g2)) for row in self.coefficients())

    def displacement(self, x, ops: Ops = NUMPY, side: int = 0):
        """Displacement (m), global components, ``ops.vector``."""
        F = branch_values(*polar(x, self.frame, ops, side), ops)
        local = tuple(_dot(row, F) for row in self.coefficients())
        return ops.vector(to_global_vector(local, self.frame))

    def gradient_components(self, x, ops: Ops = NUMPY, side: int = 0) -> tuple:
        """Global displacement gradient ``d u_i / d x_j`` (1) as a pair of rows."""
        return to_global_tensor(self._local_gradient(x, ops, side), self.frame)

    def gradient(self, x, ops: Ops = NUMPY, side: int = 0):
        """Global displacement gradient ``d u_i / d x_j`` (1), ``ops.matrix``."""
        return ops.matrix(self.gradient_components(x, ops, side))

    def stress(self, x, ops: Ops = NUMPY, side: int = 0):
        """Cauchy stress (Pa), global components, ``ops.matrix`` (Hooke's law of
        :meth:`gradient` with this field's ``mu`` and 2D ``lmbda``)."""
        return ops.matrix(hooke(self.gradient_components(x, ops, side), self.mu, self.lmbda))


def _dot(row: tuple, values: tuple):
    """``sum_j row[j] values[j]``."""
    return sum(m * v for m, v in zip(row, values, strict=True))


def hooke(G: tuple, mu, lmbda) -> tuple:
    """``mu (G + G^T) + lmbda tr(G) I`` (Pa) of a gradient given as a pair of rows."""
    trace = lmbda * (G[0][0] + G[1][1])
    shear = mu * (G[0][1] + G[1][0])
    return ((2 * mu * G[0][0] + trace, shear), (shear, 2 * mu * G[1][1] + trace))
