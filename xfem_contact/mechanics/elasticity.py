"""Linear elasticity on a cut mesh with an enriched displacement per side.

Interface conditions (per interface): ``"free"`` (traction-free lips: an open
crack or gap) and ``"bonded"`` (displacement continuity enforced by a vector
multiplier ``lambda`` on the interface, P1 on the vertices of cut cells;
``lambda`` is the traction ``sigma n`` on side -1, ``n`` from side -1 to +1).
Units: SI (Pa, m, N/m^2 for tractions).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.loading import Facets, LoadFactor, boundary_facets
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.linear import solve_restricted

INTERFACE_LAWS = ("free", "bonded")
SIDES = (-1, 1)

#: A load: a number, a UFL expression, or a callable of the UFL coordinate ``x``
Load = float | ufl.core.expr.Expr | Callable


@dataclasses.dataclass
class Solution:
    """Displacements per side (m) and, for bonded interfaces, the multiplier (Pa)."""

    w: dolfinx.fem.Function
    space: EnrichedSpace

    def field(self, i: int) -> dolfinx.fem.Function:
        """Collapsed copy of field ``i``: 0 side -1, 1 side +1, 2 multiplier."""
        return self.w.sub(i).collapse()


class ElasticityProblem:
    """Small-strain elasticity of the two sides of a cut mesh.

    Args:
        cut: The cut mesh (interface and sides).
        degree: Displacement degree (1 or 2).
        materials: One :class:`Material` for both sides, or ``{-1: m1, 1: m2}``.
        interface: ``"free"`` or ``"bonded"``.
        min_support_fraction: See :class:`EnrichedSpace`. Default: keep every
            dof when the ghost penalty is on (it defines the field's extension
            over empty supports), else drop dofs with no support on their side.
        ghost_penalty: Dimensionless weight ``gamma`` of the ghost penalty that
            keeps the operator well conditioned under tiny cuts: for each side,
            ``gamma * 2 mu * sum_k h^(2k-1) [d^k u][d^k v]`` on the interior facets
            of cut cells, k = 1..degree (zero for smooth solutions: exact
            polynomial fields stay exact). 0 disables it.
        multiplier_stabilization: Weight ``gamma`` of the Barbosa-Hughes term
            (see :meth:`multiplier_stabilization_form`); 0 disables it.
        multiplier_extension: Weight of the normal-gradient term that fixes the
            multiplier off the interface (see :meth:`multiplier_extension_form`);
            0 disables it.
    """

    def __init__(
        self,
        cut: CutMesh,
        degree: int,
        materials: Material | dict[int, Material],
        interface: str = "free",
        min_support_fraction: float | None = None,
        ghost_penalty: float = 0.01,
        multiplier_stabilization: float = 0.1,
        multiplier_extension: float = 1e-12,
    ):
        if interface not in self.LAWS:
            raise ValueError(f"Unknown interface law {interface!r}; valid: {self.LAWS}")
        if isinstance(materials, Material):
            materials = {-1: materials, 1: materials}
        missing = [s for s in SIDES if s not in materials]
        if missing or not all(isinstance(m, Material) for m in materials.values()):
            raise ValueError(f"Give a Material for sides -1 and +1 (missing: {missing})")
        if ghost_penalty < 0:
            raise ValueError(f"ghost_penalty must be >= 0, got {ghost_penalty}")
        self.ghost_penalty = ghost_penalty
        self.multiplier_stabilization = multiplier_stabilization
        self.multiplier_extension = multiplier_extension
        if min_support_fraction is None:
            min_support_fraction = 0.0 if ghost_penalty > 0 else 1e-12
        self.cut, self.interface, self.materials = cut, interface, materials
        self.space = EnrichedSpace(
            cut,
            degree,
            multiplier=self.multiplier_components(interface, cut.mesh.geometry.dim),
            min_support_fraction=min_support_fraction,
        )
        self.mesh = cut.mesh
        _check_ghosts(self.mesh)
        self._bcs: list[dolfinx.fem.DirichletBC] = []
        self._rhs: list = []
        self._x = ufl.SpatialCoordinate(self.mesh)
        #: Scales every load and prescribed displacement (see :mod:`xfem_contact.mechanics.loading`)
        self.load_factor = LoadFactor(self.mesh)

    #: Interface laws this problem solves
    LAWS = INTERFACE_LAWS

    @staticmethod
    def multiplier_components(law: str, gdim: int) -> int:
        """Number of interface multiplier components a law needs."""
        return gdim if law == "bonded" else 0

    # -- boundary parts and loads ---------------------------------------------------
    def facets(self, part: Facets) -> np.ndarray:
        """Local exterior facet indices of a boundary part; error if it is empty."""
        return boundary_facets(self.mesh, part)

    def _ufl(self, value: Load):
        if isinstance(value, ufl.core.expr.Expr) or not callable(value):
            return ufl.as_ufl(value)
        return value(self._x)

    def add_displacement(self, part: Facets, value, component: int | None = None) -> None:
        """Prescribe the displacement (m) on a boundary part, on both sides' fields.

        ``value``: a number or a callable of ``x`` (shape ``(3, n)``) returning
        ``(n,)`` for one component or ``(gdim, n)`` for the vector.
        """
        fdim = self.mesh.topology.dim - 1
        facets = self.facets(part)
        for field in (0, 1):
            sub = self.space.W.sub(field)
            if component is not None:
                sub = sub.sub(component)
            V, _ = sub.collapse()
            g = dolfinx.fem.Function(V)
            if callable(value):
                g.interpolate(value)
            else:
                g.x.array[:] = value
            self.load_factor.track(g)
            dofs = dolfinx.fem.locate_dofs_topological((sub, V), fdim, facets)
            self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))

    def add_point_displacement(self, point, value: float, component: int) -> None:
        """Fix one displacement component at a mesh node (e.g. to remove rigid modes)."""
        point = np.asarray(point, dtype=float)

        def at_point(x):
            return np.isclose(x[0], point[0]) & np.isclose(x[1], point[1])

        found = 0
        for field in (0, 1):
            sub = self.space.W.sub(field).sub(component)
            V, _ = sub.collapse()
            dofs = dolfinx.fem.locate_dofs_geometrical((sub, V), at_point)
            found += self.mesh.comm.allreduce(dofs[0].size, op=MPI.SUM)
            g = dolfinx.fem.Function(V)
            g.x.array[:] = value
            self.load_factor.track(g)
            self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))
        if found == 0:
            raise ValueError(f"No mesh node at {point.tolist()} to fix")

    def add_traction(self, part: Facets, traction: Load, side: int | None = None) -> None:
        """Surface traction (Pa) on a boundary part; ``side`` restricts it to one side.

        Scaled by the load factor, as every load."""
        facets = self.facets(part)
        t = self.load_factor.scaled(self._ufl(traction))
        for s in SIDES if side is None else (side,):
            v = self.space.test()[0 if s == -1 else 1]
            self._rhs.append(ufl.inner(t, v) * self.cut.ds(s, facets))

    def add_pressure(self, part: Facets, pressure: Load, side: int | None = None) -> None:
        """Pressure (Pa, positive pushes into the body) on a boundary part: t = -p n."""
        n = ufl.FacetNormal(self.mesh)
        p = self._ufl(pressure)
        self.add_traction(part, -p * n, side)

    def add_body_force(self, force: Load, side: int | None = None) -> None:
        """Body force density (N/m^3) on one side or both."""
        f = self.load_factor.scaled(self._ufl(force))
        for s in SIDES if side is None else (side,):
            v = self.space.test()[0 if s == -1 else 1]
            self._rhs.append(ufl.inner(f, v) * self.cut.dx(s))

    # -- forms and solve -----------------------------------------------------------
    @functools.cached_property
    def cell_size(self) -> dolfinx.fem.Function:
        """Cell diameters h (m) as a DG0 function (largest vertex distance): unlike
        ``ufl.CellDiameter`` it also serves curved (Q2-geometry) cells."""
        V0 = dolfinx.fem.functionspace(self.mesh, ("DG", 0))
        h = dolfinx.fem.Function(V0, name="h")
        tdim = self.mesh.topology.dim
        num_cells = self.mesh.topology.index_map(tdim).size_local
        num_cells += self.mesh.topology.index_map(tdim).num_ghosts
        cells = np.arange(num_cells, dtype=np.int32)
        h.x.array[V0.dofmap.list[cells, 0]] = self.mesh.h(tdim, cells)
        return h

    def bulk_form(self, u, v) -> ufl.Form:
        """Elastic energy of both sides plus the ghost penalty, ``u``, ``v``: field tuples."""
        a = sum(
            ufl.inner(self.materials[s].stress(u[i]), ufl.sym(ufl.grad(v[i]))) * self.cut.dx(s)
            for i, s in enumerate(SIDES)
        )
        if self.ghost_penalty > 0:
            a += self._ghost_penalty(u, v)
        return a

    def bilinear_form(self) -> ufl.Form:
        trial, test = self.space.trial(), self.space.test()
        a = self.bulk_form(trial, test)
        if self.interface == "bonded":
            lam, mu = trial[2], test[2]
            jump_v, jump_u = test[1] - test[0], trial[1] - trial[0]
            a += (ufl.inner(lam, jump_v) + ufl.inner(mu, jump_u)) * self.cut.dGamma
            if self.multiplier_stabilization > 0:
                a -= self.multiplier_stabilization_form(lam, mu, trial, test)
            if self.multiplier_extension > 0:
                a -= self.multiplier_extension_form(lam, mu)
        return a

    def traction_weights(self) -> tuple[float, float]:
        """Weights ``(w_-, w_+)`` of the sides in the interface traction average:
        ``w_- = mu_+ / (mu_- + mu_+)``, ``w_+ = mu_- / (mu_- + mu_+)`` (1/2 each for
        one material). The softer side weighs more, as in weighted Nitsche methods:
        with the plain mean, a 1000 times stiffer inclusion under hydrostatic
        pressure had a contact pressure oscillating by 180 % (part of the interface
        even opened); weighted, it is smooth to 2 % at h = 0.05 and converges."""
        mu_minus, mu_plus = self.materials[-1].mu, self.materials[1].mu
        return mu_plus / (mu_minus + mu_plus), mu_minus / (mu_minus + mu_plus)

    def interface_traction(self, u) -> ufl.core.expr.Expr:
        """Weighted average traction ``(w_- sigma_-(u_-) + w_+ sigma_+(u_+)) n`` (Pa) on
        the interface (see :meth:`traction_weights`)."""
        w_minus, w_plus = self.traction_weights()
        stress = w_minus * self.materials[-1].stress(u[0]) + w_plus * self.materials[1].stress(u[1])
        return stress * self.cut.normal

    def multiplier_stabilization_form(self, lam, mu, u, v) -> ufl.Form:
        """Barbosa-Hughes term ``s int (lambda - t(u)).(mu - t(v))`` (``s`` the
        :meth:`stabilization_scale`, ``t`` the weighted average interface traction;
        ``lam``, ``mu`` Cartesian vectors):
        consistent, and LBB-stable for any multiplier space."""
        t_u, t_v = self.interface_traction(u), self.interface_traction(v)
        return self.stabilization_scale() * ufl.inner(lam - t_u, mu - t_v) * self.cut.dGamma

    def multiplier_extension_form(self, lam, mu) -> ufl.Form:
        """``gamma h^2 / (2 mu) int_{cut cells} (grad lambda n).(grad mu n) dx``.

        The multiplier lives on the vertices of cut cells but acts on the interface
        only. Where the interface follows a line of the cells' reference coordinates
        (a circle in a polar mesh, a line along a cell row), combinations of those
        vertex functions vanish on the whole interface: every interface term, the
        Barbosa-Hughes one included, misses them and the matrix is singular (Newton
        then stalls on round-off). This term sets the multiplier constant along the
        normal off the interface (the normal-gradient stabilisation of TraceFEM): it
        removes those modes. It only has to make them determinate, so its weight is
        tiny: on the annulus (paper case 3) every weight from 1e-16 to 0.1 gave one
        Newton step where none stalled on round-off or took 3-4 steps; but the term
        is not consistent for a multiplier varying along a curved interface, and
        weights of 1e-8 (P2 triangles, h = 1/160: pressure error 4.5e-5 instead of
        2.9e-5) to 0.1 (bonded inclusion: 4 times larger) spoil the accuracy. The
        default 1e-12 changes no measured error.
        ``lam``, ``mu``: multiplier (scalar or vector) trial/test or coefficient.
        """
        n = self.cut.normal
        shear = 0.5 * (self.materials[-1].mu + self.materials[1].mu)
        scale = self.multiplier_extension * self.cell_size**2 / (2.0 * shear)
        on_cut_cells = 1.0 - abs(self.side_indicator)  # 1 on cut cells, 0 elsewhere
        grad_lam, grad_mu = ufl.dot(ufl.grad(lam), n), ufl.dot(ufl.grad(mu), n)
        return on_cut_cells * scale * ufl.inner(grad_lam, grad_mu) * ufl.dx(domain=self.mesh)

    @functools.cached_property
    def side_indicator(self) -> dolfinx.fem.Function:
        """The cells' sides as a DG0 function: -1, +1, or 0 on cut cells."""
        return self.cut.side_indicator()

    def stabilization_scale(self) -> ufl.core.expr.Expr:
        """``gamma h / (4 sum_s w_s^2 mu_s)`` (m/Pa) of the multiplier stabilisation
        (UFL): ``gamma h / (2 mu)`` for one material; for two, the shear modulus the
        weighted traction average sees (see :meth:`traction_weights`)."""
        w_minus, w_plus = self.traction_weights()
        shear = w_minus**2 * self.materials[-1].mu + w_plus**2 * self.materials[1].mu
        return self.multiplier_stabilization * self.cell_size / (4.0 * shear)

    def _ghost_penalty(self, trial, test) -> ufl.Form:
        dS = ufl.Measure("dS", domain=self.mesh, subdomain_data=ghost_penalty_facets(self.cut))
        h = ufl.avg(self.cell_size)
        terms = []
        for i, s in enumerate(SIDES):
            scale = self.ghost_penalty * 2.0 * self.materials[s].mu
            du, dv = ufl.grad(trial[i]), ufl.grad(test[i])
            for k in range(1, self.space.degree + 1):
                terms.append(
                    scale * h ** (2 * k - 1) * ufl.inner(ufl.jump(du), ufl.jump(dv)) * dS(i + 1)
                )
                du, dv = ufl.grad(du), ufl.grad(dv)
        return sum(terms[1:], terms[0])

    def linear_form(self) -> ufl.Form:
        if not self._rhs:
            return ufl.ZeroBaseForm((ufl.TestFunction(self.space.W),))
        return sum(self._rhs[1:], self._rhs[0])

    def solve(self, petsc_options: dict | None = None) -> Solution:
        """Assemble and solve (one KSP solve on the active dofs). Collective."""
        a, L = form(self.bilinear_form()), form(self.linear_form())
        w, _ = solve_restricted(a, L, self._bcs, self.space, petsc_options)
        return Solution(w, self.space)


def ghost_penalty_facets(cut: CutMesh) -> list[tuple[int, np.ndarray]]:
    """Interior-facet integration entities of the ghost penalty: id 1 (side -1) and
    2 (side +1) hold the owned interior facets with a cut cell on one side and a
    cell touching that side on the other."""
    mesh, tdim = cut.mesh, cut.mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    num_facets = mesh.topology.index_map(tdim - 1).size_local
    counts = np.diff(f2c.offsets[: num_facets + 1])
    interior = np.flatnonzero(counts == 2).astype(np.int32)
    cells = f2c.array[f2c.offsets[interior][:, None] + np.arange(2)]
    sides = _all_cell_sides(cut)[cells]
    entries = []
    for sid, side in ((1, -1), (2, 1)):
        touches = (sides == side) | (sides == 0)
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


def _all_cell_sides(cut: CutMesh) -> np.ndarray:
    """Side (-1, 0 = cut, +1) of owned and ghost cells (ghosts via a DG0 scatter)."""
    side = cut.side_indicator()
    return np.rint(side.x.array[side.function_space.dofmap.list[:, 0]]).astype(np.int8)


def _check_ghosts(mesh: dolfinx.mesh.Mesh) -> None:
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
