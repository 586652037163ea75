"""Elastic materials (SI units: Pa, m): linear elasticity, and Saint Venant-Kirchhoff
for large rotations with small strains (the same moduli on the Green-Lagrange strain)."""

from __future__ import annotations

import dataclasses
import typing

import dolfinx.fem
import numpy as np
import ufl


@dataclasses.dataclass(frozen=True)
class Material:
    """Isotropic linear elasticity in 2D.

    Args:
        E: Young's modulus (Pa), > 0.
        nu: Poisson's ratio, in (-1, 0.5).
        plane: ``"strain"`` or ``"stress"``.
    """

    E: float
    nu: float
    plane: typing.Literal["strain", "stress"] = "strain"

    def __post_init__(self):
        if not self.E > 0:
            raise ValueError(f"Young's modulus E must be > 0 Pa, got {self.E}")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"Poisson's ratio nu must be in (-1, 0.5), got {self.nu}")
        if self.plane not in ("strain", "stress"):
            raise ValueError(f"plane must be 'strain' or 'stress', got {self.plane!r}")

    @property
    def mu(self) -> float:
        """Shear modulus (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def lmbda(self) -> float:
        """Lamé's first parameter of the 2D law (Pa); plane stress uses the reduced one."""
        lmbda = self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))
        if self.plane == "stress":
            return 2.0 * self.mu * lmbda / (lmbda + 2.0 * self.mu)
        return lmbda

    def stress(self, u) -> ufl.core.expr.Expr:
        """Cauchy stress (Pa) of displacement ``u`` (m), small strain."""
        eps = ufl.sym(ufl.grad(u))
        return 2.0 * self.mu * eps + self.lmbda * ufl.tr(eps) * ufl.Identity(len(u))

    def piola(self, u) -> ufl.core.expr.Expr:
        """First Piola-Kirchhoff stress (Pa) of ``u`` (m), Saint Venant-Kirchhoff
        (:func:`saint_venant_kirchhoff`)."""
        return saint_venant_kirchhoff(self.mu, self.lmbda, u)


def saint_venant_kirchhoff(mu, lmbda, u) -> ufl.core.expr.Expr:
    """``P = F S``, ``S = 2 mu E + lmbda tr(E) I``, ``E = (F^T F - I) / 2``,
    ``F = I + grad u`` (Pa; ``mu``, ``lmbda`` numbers or DG0 Functions, Pa): objective,
    so a rigid rotation gives ``P = 0``; equal to the linear law to first order in
    ``grad u``."""
    d = len(u)
    identity = ufl.Identity(d)
    F = identity + ufl.grad(u)
    E = 0.5 * (F.T * F - identity)
    return F * (2.0 * mu * E + lmbda * ufl.tr(E) * identity)


class MaterialField:
    """A side whose material changes from region to region (cellwise constant).

    Several inclusions of one scene are all side -1; each may be of its own
    material. ``mu``, ``lmbda`` and ``E`` are DG0 Functions, so :meth:`stress` is the
    same UFL law as :meth:`Material.stress`.

    Args:
        regions: DG0 Function holding each cell's region index (owned and ghost cells).
        materials: The material of each region, indexed by region.
    """

    def __init__(self, regions: dolfinx.fem.Function, materials: typing.Sequence[Material]):
        self.materials = tuple(materials)
        index = np.rint(regions.x.array).astype(np.int64)
        V0 = regions.function_space
        self.E, self.mu, self.lmbda = (dolfinx.fem.Function(V0) for _ in range(3))
        for f, key in ((self.E, "E"), (self.mu, "mu"), (self.lmbda, "lmbda")):
            f.x.array[:] = np.array([getattr(m, key) for m in self.materials])[index]

    def stress(self, u) -> ufl.core.expr.Expr:
        """Cauchy stress (Pa) of displacement ``u`` (m), small strain."""
        eps = ufl.sym(ufl.grad(u))
        return 2.0 * self.mu * eps + self.lmbda * ufl.tr(eps) * ufl.Identity(len(u))

    def piola(self, u) -> ufl.core.expr.Expr:
        """First Piola-Kirchhoff stress (Pa), Saint Venant-Kirchhoff, as :meth:`Material.piola`."""
        return saint_venant_kirchhoff(self.mu, self.lmbda, u)
