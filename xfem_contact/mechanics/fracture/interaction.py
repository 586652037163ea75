"""Stress intensity factors by the domain interaction integral, and the J-integral.

In the tip frame (``x1`` along the crack direction ``d``), for a displacement ``u`` and an
auxiliary Williams field ``aux`` (:class:`~.williams.WilliamsField` with ``K = 1``),
with ``q`` a ring's q-function (:mod:`~.rings`)::

    I(u, aux) = int [s_ij aux_i,1 + s^aux_ij u_i,1 - s_ij e^aux_ij delta_1j] q_,j dA
                - int_lips t_i aux_i,1 q ds
    K_I = E' I(u, mode I) / 2,   K_II = E' I(u, mode II) / 2,
    J = I(u, u) / 2 (its lip term: - int_lips t_i u_i,1 q ds),

``t`` the traction on each lip (``sigma n``, ``n`` the body's outward normal there;
contact pressure, friction, loads on the lips), ``E'`` = ``E / (1 - nu^2)`` in plane strain
and ``E`` in plane stress. The integrand is written once for a pair of fields and summed
over the pieces of the displacement: one Function on a body-fitted mesh (``Piece(u,
ufl.dx)``), or each side's field of an enriched space on its side's measure. As ``I`` is
linear in ``q``, each quantity is assembled once as a vector over the q-space and every
ring costs one dot product.
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Sequence

import basix
import dolfinx.fem
import dolfinx.la
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.forms import form as xfem_form
from xfem_contact.mechanics.fracture.rings import Ring, interpolate_ring
from xfem_contact.mechanics.fracture.williams import (
    UFL,
    TipFrame,
    WilliamsField,
    effective_modulus,
    tip_frame,
)
from xfem_contact.mechanics.parameters import constant


class Piece(typing.NamedTuple):
    """A displacement (m; a vector Function or UFL expression) and the measure it holds on."""

    u: typing.Any
    measure: ufl.Measure


class Lip(typing.NamedTuple):
    """A crack lip carrying a traction.

    Attributes:
        traction: ``sigma n`` on the lip (Pa, UFL vector), ``n`` the body's outward normal.
        u: The displacement of the lip's side (m, UFL vector; for the J-integral).
        measure: The lip's measure (arc length, e.g. a crack's interface measure).
        side: +1 for the upper lip (``theta = pi``), -1 for the lower (``theta = -pi``).
    """

    traction: typing.Any
    u: typing.Any
    measure: ufl.Measure
    side: int


@dataclasses.dataclass(frozen=True)
class RingResult:
    """The integrals of one ring.

    Attributes:
        ring: The ring (radii in m).
        K_I: Mode I stress intensity factor (Pa m^1/2).
        K_II: Mode II stress intensity factor (Pa m^1/2).
        J: The J-integral (J/m^2).
        G: The energy release rate of the K: ``(K_I^2 + K_II^2) / E'`` (J/m^2).
    """

    ring: Ring
    K_I: float
    K_II: float
    J: float
    G: float


def flux(grad_a, sigma_a, grad_b, sigma_b, d, grad_q) -> ufl.core.expr.Expr:
    """The domain integrand of ``I(a, b)`` (UFL): ``(grad_b d).(sigma_a grad_q) +
    (grad_a d).(sigma_b grad_q) - (sigma_a : grad_b)(d . grad_q)`` (``grad[i, j] = du_i/dx_j``)."""
    return (
        ufl.dot(grad_b * d, sigma_a * grad_q)
        + ufl.dot(grad_a * d, sigma_b * grad_q)
        - ufl.inner(sigma_a, grad_b) * ufl.dot(d, grad_q)
    )


def _material_ufl(material) -> tuple:
    """``(E, nu)`` of a material for the forms: Constants of a bound
    :class:`~xfem_contact.mechanics.materials.Moduli`, or the numbers of a ``Material``."""
    if hasattr(material, "ufl_E"):
        return constant(material, "E"), constant(material, "nu")
    return material.E, material.nu


class InteractionIntegral:
    """K_I, K_II and J of one crack tip on several rings (compiled once, evaluated often).

    Args:
        pieces: The displacement as :class:`Piece` (``u``, measure) pairs.
        material: A ``Material`` or a bound ``Moduli`` (homogeneous around the tip); its
            ``stress(u)`` is the stress of every piece.
        tip: The tip's position (m) and ``direction`` the crack's direction ahead of it.
        rings: The q-functions (:class:`~.rings.Ring`, or ``(r_inf, r_sup)`` pairs in m).
        lips: The lips that carry tractions (:class:`Lip`); none for traction-free lips.
        degree: Degree of the Lagrange space of the q-functions.
        quadrature_degree: If given, the quadrature degree of every measure.

    Raises:
        ValueError: no pieces, a lip side not +-1, a bad tip, direction or ring.
    """

    def __init__(
        self,
        pieces: Sequence[Piece],
        material,
        tip,
        direction,
        rings: Sequence[Ring | tuple[float, float]],
        lips: Sequence[Lip] = (),
        degree: int = 1,
        quadrature_degree: int | None = None,
    ):
        pieces = [Piece(*p) for p in pieces]
        lips = [Lip(*lip) for lip in lips]
        if not pieces:
            raise ValueError("pieces must hold at least one (u, measure) pair")
        for lip in lips:
            if lip.side not in (-1, 1):
                raise ValueError(f"a lip's side must be +1 (upper) or -1 (lower), got {lip.side!r}")
        self.material = material
        self.rings = [r if isinstance(r, Ring) else Ring(*r) for r in rings]
        if not self.rings:
            raise ValueError("rings must hold at least one ring (r_inf, r_sup)")
        domain = ufl.domain.extract_unique_domain(pieces[0].u)
        mesh = self.mesh = dolfinx.mesh.Mesh(domain.ufl_cargo(), domain)
        self.Q = dolfinx.fem.functionspace(mesh, ("Lagrange", degree))
        self._origin = dolfinx.fem.Constant(mesh, np.zeros(2))
        self._direction = dolfinx.fem.Constant(mesh, np.array([1.0, 0.0]))
        self._mode = dolfinx.fem.Constant(mesh, np.array([1.0, 0.0]))
        self._q = [dolfinx.fem.Function(self.Q) for _ in self.rings]
        self.set_tip(tip, direction)

        def measure(m):
            return (
                m
                if quadrature_degree is None
                else m.reconstruct(
                    metadata={**m.metadata(), "quadrature_degree": quadrature_degree}
                )
            )

        frame = TipFrame(self._origin, self._direction)
        E, nu = _material_ufl(material)
        aux = WilliamsField(frame, self._mode[0], self._mode[1], E, nu, material.plane)
        x, d = ufl.SpatialCoordinate(mesh), self._direction
        phi = ufl.TestFunction(self.Q)
        grad_phi = ufl.grad(phi)
        grad_aux, sigma_aux = aux.gradient(x, UFL), aux.stress(x, UFL)
        interaction, energy = [], []
        for u, m in pieces:
            grad_u, sigma_u = ufl.grad(u), material.stress(u)
            interaction.append(flux(grad_u, sigma_u, grad_aux, sigma_aux, d, grad_phi) * measure(m))
            energy.append(0.5 * flux(grad_u, sigma_u, grad_u, sigma_u, d, grad_phi) * measure(m))
        for lip in lips:
            aux_lip = aux.gradient(x, UFL, side=lip.side)
            t = lip.traction
            interaction.append(-ufl.dot(t, aux_lip * d) * phi * measure(lip.measure))
            energy.append(-ufl.dot(t, ufl.grad(lip.u) * d) * phi * measure(lip.measure))
        self._forms = (sum(interaction[1:], interaction[0]), sum(energy[1:], energy[0]))

    def set_tip(self, tip, direction) -> None:
        """Move the tip (m) or turn its ``direction``, and refill the rings. Collective."""
        frame = tip_frame(tip, direction)
        self._origin.value[:] = frame.origin
        self._direction.value[:] = frame.direction
        self.frame = frame
        for q, ring in zip(self._q, self.rings, strict=True):
            interpolate_ring(q, frame, ring)

    def _assemble(self, ufl_form) -> np.ndarray:
        """The owned entries of the assembled vector of ``ufl_form`` over the q-space."""
        b = dolfinx.fem.assemble_vector(xfem_form(ufl_form))
        b.scatter_reverse(dolfinx.la.InsertMode.add)
        return b.array[: self.Q.dofmap.index_map.size_local].copy()

    def vectors(self) -> np.ndarray:
        """The assembled vectors of ``I(u, mode I)``, ``I(u, mode II)`` and ``J`` over the
        q-space, owned dofs, ``(3, n_owned)``. Collective."""
        out = []
        for mode in ((1.0, 0.0), (0.0, 1.0)):
            self._mode.value[:] = mode
            out.append(self._assemble(self._forms[0]))
        out.append(self._assemble(self._forms[1]))
        return np.array(out)

    def evaluate(self) -> list[RingResult]:
        """K_I, K_II, J and G on every ring for the current displacement. Collective; every
        process returns the same values."""
        n = self.Q.dofmap.index_map.size_local
        q = np.array([f.x.array[:n] for f in self._q]).reshape(len(self._q), n)
        local = q @ self.vectors().T  # (rings, 3)
        I_I, I_II, J = self.mesh.comm.allreduce(local, op=MPI.SUM).T
        E_eff = effective_modulus(self.material.E, self.material.nu, self.material.plane)
        K_I, K_II = E_eff * I_I / 2, E_eff * I_II / 2
        G = (K_I**2 + K_II**2) / E_eff
        return [
            RingResult(ring, float(a), float(b), float(c), float(g))
            for ring, a, b, c, g in zip(self.rings, K_I, K_II, J, G, strict=True)
        ]


def graded_facet_measure(measure: ufl.Measure, degree: int = 20) -> ufl.Measure:
    """A facet measure of a 2D mesh with a Gauss rule of ``degree`` mapped on every facet by
    ``s = 3 t^2 - 2 t^3``: an integrand with an ``r^-1/2`` singularity at either end of a
    facet becomes smooth, so the lip term of a tip on a mesh vertex (body-fitted meshes)
    integrates to near machine precision, where plain Gauss rules converge as ``1/degree``.

    Raises:
        ValueError: ``measure`` not an exterior or interior facet measure.
    """
    if measure.integral_type() not in ("exterior_facet", "interior_facet"):
        raise ValueError(
            f"measure must be a facet measure (ds or dS), got {measure.integral_type()!r}"
        )
    t, w = basix.make_quadrature(basix.CellType.interval, degree)
    t = t[:, 0]
    metadata = {
        "quadrature_rule": "custom",
        "quadrature_points": (t * t * (3 - 2 * t))[:, None],
        "quadrature_weights": w * 6 * t * (1 - t),
    }
    return measure.reconstruct(metadata={**measure.metadata(), **metadata})


def spread(results: Sequence[RingResult]) -> dict[str, float]:
    """Ring-to-ring spread of K_I, K_II, J: ``(max - min) / max |K|`` (``max |J|`` for J)."""
    K = np.array([[r.K_I, r.K_II] for r in results])
    J = np.array([r.J for r in results])
    scale = max(float(np.abs(K).max()), np.finfo(float).tiny)
    return {
        "K_I": float(np.ptp(K[:, 0])) / scale,
        "K_II": float(np.ptp(K[:, 1])) / scale,
        "J": float(np.ptp(J)) / max(float(np.abs(J).max()), np.finfo(float).tiny),
    }
