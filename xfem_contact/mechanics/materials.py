"""Elastic materials (SI units: Pa, m): linear elasticity, and Saint Venant-Kirchhoff
for large rotations with small strains (the same moduli on the Green-Lagrange strain).

:class:`Material` is what a user gives (numbers); a problem turns it into
:class:`Moduli` on its mesh, whose ``E`` and ``nu`` enter the forms as Constants
(set them to change the material without a new compile), or into a
:class:`MaterialField` where a side's material varies by region."""

from __future__ import annotations

import dataclasses
import typing

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl

from xfem_contact.mechanics.parameters import Parameter, bind, constant, listen

PLANES = ("strain", "stress")


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
        Moduli.E.check(self.E, "Young's modulus E")
        Moduli.nu.check(self.nu, "Poisson's ratio nu")
        if self.plane not in PLANES:
            raise ValueError(f"plane must be one of {PLANES}, got {self.plane!r}")

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
        """Cauchy stress (Pa) of displacement ``u`` (m), small strain (the values as
        literals: forms that keep them use :class:`Moduli`)."""
        return hooke(self.mu, self.lmbda, u)

    def piola(self, u) -> ufl.core.expr.Expr:
        """First Piola-Kirchhoff stress (Pa) of ``u`` (m), Saint Venant-Kirchhoff
        (:func:`saint_venant_kirchhoff`; the values as literals, as :meth:`stress`)."""
        return saint_venant_kirchhoff(self.mu, self.lmbda, u)


def hooke(mu, lmbda, u) -> ufl.core.expr.Expr:
    """Small-strain Cauchy stress ``2 mu eps + lmbda tr(eps) I`` (Pa) of ``u`` (m);
    ``mu``, ``lmbda`` numbers, Constants or DG0 Functions (Pa)."""
    eps = ufl.sym(ufl.grad(u))
    return 2.0 * mu * eps + lmbda * ufl.tr(eps) * ufl.Identity(len(u))


def saint_venant_kirchhoff(mu, lmbda, u) -> ufl.core.expr.Expr:
    """``P = F S``, ``S = 2 mu E + lmbda tr(E) I``, ``E = (F^T F - I) / 2``,
    ``F = I + grad u`` (Pa; ``mu``, ``lmbda`` numbers or DG0 Functions, Pa): objective,
    so a rigid rotation gives ``P = 0``; equal to Hooke's law to first order in
    ``grad u``."""
    d = len(u)
    identity = ufl.Identity(d)
    F = identity + ufl.grad(u)
    E = 0.5 * (F.T * F - identity)
    return F * (2.0 * mu * E + lmbda * ufl.tr(E) * identity)


class Moduli:
    """A material on a mesh: ``E`` (Pa) and ``nu`` as Constants of the forms.

    Assigning ``E`` or ``nu`` (validated as :class:`Material`'s) changes every form
    built with this object, with no new compile. Not collective.

    Args:
        material: The initial values and the plane assumption (fixed).
        mesh: The mesh of the forms.
    """

    name = "material"
    E = Parameter("Pa", minimum=0.0, strict=True)
    nu = Parameter("1", minimum=-1.0, strict=True, maximum=0.5)

    def __init__(self, material: Material, mesh: dolfinx.mesh.Mesh):
        self._plane = material.plane
        self.E, self.nu = material.E, material.nu
        bind(self, mesh)

    @property
    def plane(self) -> str:
        """``"strain"`` or ``"stress"``: fixed, the forms are built with it."""
        return self._plane

    @plane.setter
    def plane(self, value) -> None:
        raise ValueError(
            f"plane is fixed when the forms are built (it is {self._plane!r}); build the "
            f"problem with Material(E, nu, plane={value!r}) instead"
        )

    @property
    def material(self) -> Material:
        """The current values as a :class:`Material`."""
        return Material(self.E, self.nu, self.plane)

    @property
    def ufl_E(self) -> ufl.core.expr.Expr:
        """Young's modulus (Pa), UFL."""
        return constant(self, "E")

    @property
    def ufl_mu(self) -> ufl.core.expr.Expr:
        """Shear modulus (Pa), UFL."""
        return constant(self, "E") / (2.0 * (1.0 + constant(self, "nu")))

    @property
    def ufl_lmbda(self) -> ufl.core.expr.Expr:
        """Lame's first parameter of the 2D law (Pa), UFL (reduced in plane stress)."""
        E, nu = constant(self, "E"), constant(self, "nu")
        if self.plane == "stress":
            return E * nu / (1.0 - nu**2)
        return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))

    def stress(self, u) -> ufl.core.expr.Expr:
        """Cauchy stress (Pa) of displacement ``u`` (m), small strain."""
        return hooke(self.ufl_mu, self.ufl_lmbda, u)

    def piola(self, u) -> ufl.core.expr.Expr:
        """First Piola-Kirchhoff stress (Pa) of ``u`` (m), Saint Venant-Kirchhoff
        (:func:`saint_venant_kirchhoff`)."""
        return saint_venant_kirchhoff(self.ufl_mu, self.ufl_lmbda, u)


class MaterialField:
    """A side whose material changes from region to region (cellwise constant).

    Several inclusions of one scene are all side -1; each may be of its own
    material. ``ufl_E``, ``ufl_mu`` and ``ufl_lmbda`` are DG0 Functions refilled
    whenever a region's :class:`Moduli` change, so :meth:`stress` is the same UFL law
    as :meth:`Moduli.stress` and new values compile nothing.

    Args:
        regions: DG0 Function holding each cell's region index (owned and ghost cells).
        moduli: The material of each region, indexed by region.
    """

    def __init__(self, regions: dolfinx.fem.Function, moduli: typing.Sequence[Moduli]):
        self.moduli = tuple(moduli)
        self._index = np.rint(regions.x.array).astype(np.int64)
        V0 = regions.function_space
        self.ufl_E, self.ufl_mu, self.ufl_lmbda = (dolfinx.fem.Function(V0) for _ in range(3))
        self._fill()
        for m in self.moduli:
            listen(m, lambda name, value: self._fill())

    def _fill(self) -> None:
        materials = [m.material for m in self.moduli]
        for f, key in ((self.ufl_E, "E"), (self.ufl_mu, "mu"), (self.ufl_lmbda, "lmbda")):
            f.x.array[:] = np.array([getattr(m, key) for m in materials])[self._index]

    def stress(self, u) -> ufl.core.expr.Expr:
        """Cauchy stress (Pa) of displacement ``u`` (m), small strain."""
        return hooke(self.ufl_mu, self.ufl_lmbda, u)

    def piola(self, u) -> ufl.core.expr.Expr:
        """First Piola-Kirchhoff stress (Pa), Saint Venant-Kirchhoff, as :meth:`Moduli.piola`."""
        return saint_venant_kirchhoff(self.ufl_mu, self.ufl_lmbda, u)
