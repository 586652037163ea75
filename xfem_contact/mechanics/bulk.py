"""Bulk models of the two sides of an enriched space, with the ghost penalty.

:class:`SmallStrain`: linear elasticity per side, ``sum_s int_s sigma_s(u_s) :
eps(v_s)``, plus the ghost penalty that keeps the operator well conditioned under
tiny cuts. :class:`SaintVenantKirchhoff`: the same moduli on the Green-Lagrange
strain, for large rotations with small strains (``kinematics="large"``); a new bulk
model provides the same ``form``. SI units (Pa, m).
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.fem.tip_zone import TipZone, branch_cells
from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.laws.base import Fields
from xfem_contact.mechanics.materials import MaterialField, Moduli
from xfem_contact.mechanics.parameters import Parameter, bind, constant

SIDES = (-1, 1)


def cell_size(mesh: dolfinx.mesh.Mesh) -> dolfinx.fem.Function:
    """Cell diameters h (m) as a DG0 function (largest vertex distance; owned and
    ghost cells): unlike ``ufl.CellDiameter`` it also serves curved (Q2-geometry)
    cells. Collective."""
    V0 = dolfinx.fem.functionspace(mesh, ("DG", 0))
    h = dolfinx.fem.Function(V0, name="h")
    tdim = mesh.topology.dim
    num_cells = mesh.topology.index_map(tdim).size_local
    num_cells += mesh.topology.index_map(tdim).num_ghosts
    cells = np.arange(num_cells, dtype=np.int32)
    h.x.array[V0.dofmap.list[cells, 0]] = mesh.h(tdim, cells)
    return h


class SmallStrain:
    """Small-strain elasticity of both sides plus the ghost penalty.

    Args:
        space: The enriched space (its cut mesh, and a crack's tip zone).
        materials: ``{-1: m, 1: m}``, each a :class:`Material` or a
            :class:`MaterialField` (a side whose material varies by region).
        degree: Displacement degree (the ghost penalty jumps derivatives 1..degree).
        h: Cell diameters (DG0, m).
        ghost_penalty: Dimensionless weight ``gamma``: for each side,
            ``gamma * 2 mu * sum_k c_k h^(2k-1) [d^k u][d^k v]`` on the interior facets
            of cut cells, k = 1..degree (zero for smooth solutions: exact polynomial
            fields stay exact). A Constant of the forms; 0 at construction leaves the
            term out of them (it cannot be switched on later).
        ghost_penalty_higher: ``c_k`` for ``k >= 2`` (``c_1 = 1``): the weight of the
            jumps of the second and higher derivatives relative to the gradient's
            (degree 2 only). A Constant of the forms. Their jumps are the only ones of
            the same order as the discretisation error (an interpolant's lower-order
            jumps converge faster), so they carry most of the term's consistency
            error; any positive value removes a sliver's top-degree modes.
    """

    name = "bulk"
    ghost_penalty = Parameter(minimum=0.0)
    ghost_penalty_higher = Parameter(minimum=0.0)
    #: Polynomial degree of the integrand per degree of the displacement (uncut cells
    #: outside a crack's tip zone)
    integrand_degree = 2

    def __init__(
        self,
        space: EnrichedSpace,
        materials: dict[int, Moduli | MaterialField],
        degree: int,
        h: dolfinx.fem.Function,
        ghost_penalty: float = DEFAULT.ghost_penalty,
        ghost_penalty_higher: float = DEFAULT.ghost_penalty_higher,
    ):
        cut = space.cut
        self.cut, self.materials, self.degree, self.h = cut, materials, degree, h
        #: With a crack's tip enrichment: the side measures' tip zone (the branch
        #: functions' cells) at the cut's quadrature degree
        self.zone = None
        if space.branch_field is not None:
            degree_of_cut = {"quadrature_degree": cut.quadrature_degree}
            self.zone = TipZone(cut, lambda: branch_cells(space), degree_of_cut)
        self.ghost_penalty = ghost_penalty
        self.ghost_penalty_higher = ghost_penalty_higher
        #: Whether the forms hold the ghost penalty (its weight > 0 at construction)
        self.penalised = self.ghost_penalty > 0
        bind(self, cut.mesh)

    def check_parameter(self, name: str, value: float) -> None:
        """Refuse a positive ghost penalty for forms built without the term."""
        if name == "ghost_penalty" and value > 0 and not getattr(self, "penalised", True):
            raise ValueError(
                "ghost_penalty was 0 when the problem was built, so its forms hold no "
                "ghost penalty term: build the problem with ghost_penalty > 0"
            )

    def form(self, u: Fields, v: Fields) -> ufl.Form:
        """Elastic energy of both sides plus the ghost penalty (UFL, bilinear in trial
        ``u`` or linear in ``v`` for a coefficient ``u``)."""
        a = sum(
            ufl.inner(self.materials[s].stress(u[i]), ufl.sym(ufl.grad(v[i]))) * self.dx(s)
            for i, s in enumerate(SIDES)
        )
        if self.penalised:
            a += self._ghost_penalty(u, v)
        return a

    def dx(self, side: int) -> ufl.Measure:
        """The measure of ``side``. With a crack, the uncut cells of the tip zone take
        the cut cells' degree (the branch functions' integrands are far from
        polynomials, and UFL's estimate of their degree, 40 to 60, would cost 1000
        points a cell; 112 on the ghost penalty's facets, which take that degree too),
        the others the integrand's polynomial degree."""
        if self.cut.crack is None:
            return self.cut.dx(side, self.uncut_metadata())
        if self.zone is None:
            return self.cut.dx(side, {"quadrature_degree": self.cut.quadrature_degree})
        return self.zone.dx(side, {"quadrature_degree": self.integrand_degree * self.degree})

    def uncut_metadata(self) -> dict:
        """Quadrature metadata of the uncut cells without a crack: none (UFL's
        estimate; the linear bulk is assembled once a solve)."""
        return {}

    def ghost_penalty_metadata(self) -> dict:
        """Quadrature metadata of the ghost penalty's facets. With a crack: the cut's
        degree (the branch functions'). On hexahedra: ``2 * degree``, the degree per
        direction of the jumps' products on a facet (UFL's estimate counts the total
        degree of Q elements through the cell's inverse Jacobian: 10 for Q2, a rule of
        36 points a facet whose kernel took minutes to compile). Else none (UFL's
        estimate, exact on affine simplices)."""
        if self.cut.crack is not None:
            return {"quadrature_degree": self.cut.quadrature_degree}
        if self.cut.mesh.topology.cell_type == dolfinx.mesh.CellType.hexahedron:
            return {"quadrature_degree": 2 * self.degree}
        return {}

    def _ghost_penalty(self, trial, test) -> ufl.Form:
        metadata = self.ghost_penalty_metadata()
        dS = ufl.Measure(
            "dS",
            domain=self.cut.mesh,
            subdomain_data=ghost_penalty_facets(self.cut),
            metadata=metadata,
        )
        h = ufl.avg(self.h)
        terms = []
        for i, s in enumerate(SIDES):
            mu = self.materials[s].ufl_mu
            mu = ufl.avg(mu) if isinstance(mu, ufl.Coefficient) else mu
            scale = constant(self, "ghost_penalty") * 2.0 * mu
            du, dv = ufl.grad(trial[i]), ufl.grad(test[i])
            for k in range(1, self.degree + 1):
                if k == 2:
                    scale = scale * constant(self, "ghost_penalty_higher")
                terms.append(
                    scale * h ** (2 * k - 1) * ufl.inner(ufl.jump(du), ufl.jump(dv)) * dS(i + 1)
                )
                du, dv = ufl.grad(du), ufl.grad(dv)
        return sum(terms[1:], terms[0])


class SaintVenantKirchhoff(SmallStrain):
    """Large rotations, small strains: ``sum_s int_s P_s(u_s) : grad v_s`` with the
    Saint Venant-Kirchhoff stress
    (:func:`~xfem_contact.mechanics.materials.saint_venant_kirchhoff`;
    objective: a rigid rotation of any angle carries no stress), plus the ghost
    penalty of :class:`SmallStrain` (it jumps gradients, which a rigid rotation keeps
    continuous). Same arguments as :class:`SmallStrain`; :meth:`form` takes the
    unknown ``u`` as a coefficient (the residual), never a trial function."""

    integrand_degree = 4  # P(u) : grad v, P cubic in grad u

    def uncut_metadata(self) -> dict:
        """The integrand's polynomial degree on the uncut cells: its tangent is
        assembled at every Newton iterate, and UFL's estimate (12 for P2 on curved Q2
        cells, where no degree is exact) doubles its points."""
        return {"quadrature_degree": self.integrand_degree * self.degree}

    def form(self, u: Fields, v: Fields) -> ufl.Form:
        """The residual's bulk terms (UFL, linear in the test functions ``v``)."""
        a = sum(
            ufl.inner(self.materials[s].piola(u[i]), ufl.grad(v[i])) * self.dx(s)
            for i, s in enumerate(SIDES)
        )
        if self.penalised:
            a += self._ghost_penalty(u, v)
        return a


#: Bulk models by kinematics
BULK_MODELS = {"small": SmallStrain, "large": SaintVenantKirchhoff}
KINEMATICS = tuple(BULK_MODELS)


def ghost_penalty_facets(cut: CutMesh) -> list[tuple[int, np.ndarray]]:
    """Interior-facet integration entities of the ghost penalty: id 1 (side -1) and
    2 (side +1) hold the owned interior facets with a cut cell on one side and a
    cell touching that side on the other. Collective (a DG0 scatter)."""
    mesh, tdim = cut.mesh, cut.mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    num_facets = mesh.topology.index_map(tdim - 1).size_local
    counts = np.diff(f2c.offsets[: num_facets + 1])
    interior = np.flatnonzero(counts == 2).astype(np.int32)
    cells = f2c.array[f2c.offsets[interior][:, None] + np.arange(2)]
    side = cut.side_indicator()
    all_sides = np.rint(side.x.array[side.function_space.dofmap.list[:, 0]]).astype(np.int8)
    sides = all_sides[cells]
    entries = []
    for sid, s in ((1, -1), (2, 1)):
        touches = (sides == s) | (sides == 0)
        chosen = interior[np.all(touches, axis=1) & np.any(sides == 0, axis=1)]
        entries.append(
            (
                sid,
                dolfinx.fem.compute_integration_domains(
                    dolfinx.fem.IntegralType.interior_facet, mesh.topology, chosen
                ),
            )
        )
    return entries


def check_ghosts(mesh: dolfinx.mesh.Mesh) -> None:
    """In parallel, the ghost penalty and the interface data need the cells across
    shared facets: refuse a mesh distributed without ghost cells. Collective."""
    comm = mesh.comm
    if comm.size == 1:
        return
    ghosts = mesh.topology.index_map(mesh.topology.dim).num_ghosts
    if comm.allreduce(ghosts, op=MPI.SUM) == 0:
        raise ValueError(
            "The mesh is distributed without ghost cells; create it with "
            "partitioner=dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode."
            "shared_facet) (see xfem_contact.io.meshes.ghosted_partitioner)"
        )
