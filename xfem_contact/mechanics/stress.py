"""Cauchy stress and von Mises stress of displacement fields, for output.

The stress of a side is evaluated from its material's own UFL law (``material.stress(u)``,
or ``material.piola(u)`` in large kinematics), so moduli held as Constants or DG0
Functions are read at evaluation time and new values compile nothing. In 2D the
out-of-plane stress enters the 3 x 3 tensor: ``sigma_zz = nu (sigma_xx + sigma_yy)`` in
plane strain (``lambda tr(E) / J`` with the Green-Lagrange ``E`` in large kinematics),
0 in plane stress. ``nu`` is read from the law itself (its response to a uniaxial strain),
not from a number.

:class:`StressFields` interpolates both into discontinuous Lagrange spaces of degree
``k - 1`` (``k`` the displacement degree; DG0 for P1): for affine simplices the
small-strain stress of a degree-``k`` field lies in that space, so the interpolation is
exact, costs one local kernel call per cell and needs no solve (an L2 projection would
need a mass matrix per side and smear nothing more accurately).
"""

from __future__ import annotations

from collections.abc import Sequence

import dolfinx.fem
import ufl


def _plane(material) -> str:
    """``"strain"`` or ``"stress"`` of a material (or of the first region of a field)."""
    for source in (material, *getattr(material, "moduli", ()), *getattr(material, "materials", ())):
        plane = getattr(source, "plane", None)
        if plane is not None:
            return plane
    return "strain"


def _lame(material, mesh) -> tuple:
    """``(lambda, 2 mu + lambda)`` (Pa, UFL) read off ``material.stress`` under the uniaxial
    strain ``eps = e_x (x) e_x``."""
    x = ufl.SpatialCoordinate(mesh)
    s = material.stress(ufl.as_vector([x[0], 0.0 * x[1]]))
    return s[1, 1], s[0, 0]


def cauchy_stress(material, u, kinematics: str = "small") -> ufl.core.expr.Expr:
    """The 3 x 3 Cauchy stress (Pa, UFL) of a 2D displacement ``u`` (m).

    Args:
        material: Anything with ``stress(u)`` (and ``piola(u)`` for large kinematics)
            returning UFL (Pa): a material, its moduli on a mesh, a material field.
        u: Displacement (UFL vector, 2 components).
        kinematics: ``"small"`` (Hooke's law) or ``"large"`` (``P F^T / det F`` of
            the first Piola-Kirchhoff stress ``P``).
    """
    mesh = ufl.domain.extract_unique_domain(u)
    lmbda, two_mu_lmbda = _lame(material, mesh)
    if kinematics == "large":
        F = ufl.Identity(2) + ufl.grad(u)
        J = ufl.det(F)
        s = material.piola(u) * F.T / J
        zz = lmbda * 0.5 * ufl.tr(F.T * F - ufl.Identity(2)) / J
    elif kinematics == "small":
        s = material.stress(u)
        zz = lmbda / (lmbda + two_mu_lmbda) * (s[0, 0] + s[1, 1])  # nu (s_xx + s_yy)
    else:
        raise ValueError(f"kinematics must be 'small' or 'large', got {kinematics!r}")
    if _plane(material) == "stress":
        zz = 0.0 * s[0, 0]
    return ufl.as_matrix([[s[0, 0], s[0, 1], 0.0], [s[1, 0], s[1, 1], 0.0], [0.0, 0.0, zz]])


def von_mises(sigma: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """``sqrt(3/2 s:s)`` (Pa, UFL) of a 3 x 3 stress, ``s`` its deviator."""
    s = sigma - ufl.tr(sigma) / 3.0 * ufl.Identity(3)
    return ufl.sqrt(1.5 * ufl.inner(s, s))


class StressFields:
    """Cauchy stress and von Mises stress of displacement Functions, refreshed on demand.

    For each ``(name, material, u)`` the Functions ``stress_NAME`` (3 x 3 tensor) and
    ``von_mises_NAME`` (scalar), Pa, in discontinuous Lagrange spaces of degree
    ``max(k - 1, 0)`` on ``u``'s mesh (``k`` the degree of ``u``); ``name`` empty gives
    ``stress`` and ``von_mises``. The expressions are compiled once here; :meth:`update`
    interpolates them again from the current values of ``u`` and of the moduli.
    Collective.

    Args:
        sides: ``(name, material, u)`` per displacement field; ``u`` a Lagrange Function.
        kinematics: See :func:`cauchy_stress`.
    """

    def __init__(
        self, sides: Sequence[tuple[str, object, dolfinx.fem.Function]], kinematics: str = "small"
    ):
        self.stress: list[dolfinx.fem.Function] = []
        self.von_mises: list[dolfinx.fem.Function] = []
        self._expressions = []
        for name, material, u in sides:
            V = u.function_space
            mesh, degree = V.mesh, V.ufl_element().embedded_superdegree
            family = ("DG", max(degree - 1, 0))
            T = dolfinx.fem.functionspace(mesh, (*family, (3, 3)))
            S = dolfinx.fem.functionspace(mesh, family)
            suffix = f"_{name}" if name else ""
            sigma_h = dolfinx.fem.Function(T, name=f"stress{suffix}")
            vm_h = dolfinx.fem.Function(S, name=f"von_mises{suffix}")
            sigma = cauchy_stress(material, u, kinematics)
            for target, expr in ((sigma_h, sigma), (vm_h, von_mises(sigma))):
                points = target.function_space.element.interpolation_points
                self._expressions.append((target, dolfinx.fem.Expression(expr, points)))
            self.stress.append(sigma_h)
            self.von_mises.append(vm_h)
        self.update()

    def update(self) -> None:
        """Interpolate the stresses of the current displacements. Not collective
        (owned and ghost cells are evaluated locally)."""
        for target, expression in self._expressions:
            target.interpolate(expression)
