"""The body-fitted route with duplicated interface lines: two bodies, Nitsche's method.

The two sides of the interface are separate meshes (DOLFINx submeshes of a gmsh mesh
that follows the interface, curved P2 cells for degree 2), each with its own standard
Lagrange displacement, coupled on the interface facets by Nitsche's method: with
``[u] = u_1 - u_2``, ``{t} = (sigma(u_1) + sigma(u_2)) n / 2`` (``n`` out of body 1),

    - int {t(u)} . [v] - int {t(v)} . [u] + int (gamma E / h) [u] . [v]

for a closed sticking interface (case 2), and the same with normal components only for
a closed frictionless one (case 3 at alpha = 0: the tangential motion is free). Both
cases are closed all round, so the unilateral condition of contact is inactive and
these terms are the contact problem's; an interface that opens would need the
nonlinear (Chouly-Hild) Nitsche contact term. Mixed-domain assembly (``entity_maps``)
of DOLFINx 0.11. SI units (m, Pa).
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import numpy as np
import ufl
from dolfinx.common import Timer
from mpi4py import MPI

from xfem_contact._timers import phase, seconds
from xfem_contact.cases import paper
from xfem_contact.cases.body_fitted import INCLUSION_GEO, annulus_geo, mesh_geo
from xfem_contact.mechanics.bulk import cell_size
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.options import preset, remove_options, unique_prefix

#: Nitsche's penalty: gamma = NITSCHE * degree^2 (dimensionless)
NITSCHE = 10.0


class TwoBodies:
    """Bodies 1 and 2 (the 2-D physical groups tagged 1 and 2 of a gmsh mesh) with a
    displacement each, tied on the facets of the group ``interface``. Collective.

    Args:
        gm: The :class:`~xfem_contact.io.gmsh.GmshMesh`.
        degree: Lagrange degree of the displacements.
        material: One material for both bodies.
        normal_only: Tie the normal displacement only (frictionless).
    """

    def __init__(self, gm, degree: int, material: Material, normal_only: bool = False):
        mesh, tdim = gm.mesh, gm.mesh.topology.dim
        self.gm, self.mesh, self.material = gm, mesh, material
        self.normal_only = normal_only
        self.entity_maps, self.V = [], []
        for tag in (1, 2):
            sub, entity_map, _, _ = dolfinx.mesh.create_submesh(mesh, tdim, gm.cell_tags.find(tag))
            self.entity_maps.append(entity_map)
            self.V.append(dolfinx.fem.functionspace(sub, ("Lagrange", degree, (2,))))
        W = ufl.MixedFunctionSpace(*self.V)
        (u1, u2), (v1, v2) = ufl.TrialFunctions(W), ufl.TestFunctions(W)
        self.v = (v1, v2)
        dx = ufl.Measure("dx", domain=mesh, subdomain_data=gm.cell_tags)
        self.dS = ufl.Measure("dS", domain=mesh, subdomain_data=[(1, self._interface())])(1)
        self.n = ufl.FacetNormal(mesh)("+")
        h = ufl.avg(cell_size(mesh))
        gamma = NITSCHE * degree**2 * material.E / h
        eps = ufl.sym
        a = sum(
            ufl.inner(material.stress(u), eps(ufl.grad(v))) * dx(k + 1)
            for k, (u, v) in enumerate(((u1, v1), (u2, v2)))
        )
        a += (
            -ufl.inner(self.traction(u1, u2), self.jump(v1, v2))
            - ufl.inner(self.traction(v1, v2), self.jump(u1, u2))
            + gamma * ufl.inner(self.jump(u1, u2), self.jump(v1, v2))
        ) * self.dS
        self.a = a
        self.loads = [ufl.ZeroBaseForm((v1,)), ufl.ZeroBaseForm((v2,))]
        self._pressures: list[tuple[int, np.ndarray, float]] = []
        self.bcs = []

    def _interface(self) -> np.ndarray:
        """Interior-facet integration entities of the interface with body 1 on the
        '+' side."""
        mesh, gm, tdim = self.mesh, self.gm, self.mesh.topology.dim
        mesh.topology.create_connectivity(tdim - 1, tdim)
        facets = gm.facet_tags.find(gm.parts["interface"])
        entities = dolfinx.fem.compute_integration_domains(
            dolfinx.fem.IntegralType.interior_facet, mesh.topology, facets
        ).reshape(-1, 4)
        imap = mesh.topology.index_map(tdim)
        body = np.zeros(imap.size_local + imap.num_ghosts, dtype=np.int32)
        body[gm.cell_tags.indices] = gm.cell_tags.values
        swap = body[entities[:, 0]] != 1
        entities[swap] = entities[swap][:, [2, 3, 0, 1]]
        return entities.ravel().astype(np.int32)

    def jump(self, w1, w2):
        """``[w]`` (or its normal part) on the interface."""
        jump = w1("+") - w2("-")
        return ufl.dot(jump, self.n) * self.n if self.normal_only else jump

    def traction(self, w1, w2):
        """``{sigma(w) n}`` (or its normal part) on the interface."""
        t = 0.5 * (self.material.stress(w1)("+") + self.material.stress(w2)("-")) * self.n
        return ufl.dot(t, self.n) * self.n if self.normal_only else t

    def add_pressure(self, body: int, where, pressure: float) -> None:
        """Pressure (Pa) on the exterior facets of ``body`` (1 or 2) that ``where`` selects."""
        tdim = self.mesh.topology.dim
        facets = dolfinx.mesh.locate_entities_boundary(self.mesh, tdim - 1, where)
        self._pressures.append((body, facets, pressure))

    def _load_forms(self) -> list:
        """The loads as one form per body (one ``ds`` measure: one set of facet tags)."""
        mesh, tdim = self.mesh, self.mesh.topology.dim
        facets = [f for _, f, _ in self._pressures]
        values = [np.full(f.size, k + 1, dtype=np.int32) for k, f in enumerate(facets)]
        facets = np.concatenate(facets or [np.zeros(0, dtype=np.int32)])
        values = np.concatenate(values or [np.zeros(0, dtype=np.int32)])
        order = np.argsort(facets)
        tags = dolfinx.mesh.meshtags(mesh, tdim - 1, facets[order], values[order])
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
        loads = list(self.loads)
        n = ufl.FacetNormal(mesh)
        for k, (body, _, pressure) in enumerate(self._pressures):
            loads[body - 1] += -pressure * ufl.inner(n, self.v[body - 1]) * ds(k + 1)
        return loads

    def fix(self, body: int, where, component: int | None = None) -> None:
        """Zero displacement (or one component) at the nodes of ``body`` that ``where``
        selects (a callable of the coordinates)."""
        V = self.V[body - 1]
        if component is None:
            dofs = dolfinx.fem.locate_dofs_geometrical(V, where)
            self.bcs.append(dolfinx.fem.dirichletbc(np.zeros(2), dofs, V))
            return
        sub = V.sub(component)
        Vc, _ = sub.collapse()
        dofs = dolfinx.fem.locate_dofs_geometrical((sub, Vc), where)
        self.bcs.append(dolfinx.fem.dirichletbc(dolfinx.fem.Function(Vc), dofs, sub))

    def solve(self):
        """One linear solve (MUMPS LU); returns the two displacements. Collective."""
        prefix = unique_prefix("xfem_fitted_nitsche_")
        problem = dolfinx.fem.petsc.LinearProblem(
            ufl.extract_blocks(self.a),
            self._load_forms(),
            bcs=self.bcs,
            petsc_options_prefix=prefix,
            petsc_options=preset("fitted"),
            entity_maps=self.entity_maps,
            kind="mpi",
        )
        try:
            return problem.solve()
        finally:
            remove_options(prefix)  # nothing of ours outlives the solve

    def pressure_error(self, w, exact) -> float:
        """Relative L2 error of ``n . {sigma(w) n}`` on the interface (collective)."""
        p = ufl.dot(
            self.n,
            0.5 * (self.material.stress(w[0])("+") + self.material.stress(w[1])("-")) * self.n,
        )

        def total(expr):
            f = dolfinx.fem.form(expr * self.dS, entity_maps=self.entity_maps)
            return self.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(f), op=MPI.SUM)

        return float(np.sqrt(total((p - exact) ** 2) / total(exact**2)))

    def dofs(self) -> int:
        return sum(V.dofmap.index_map.size_global * V.dofmap.bs for V in self.V)


def _run(gm, bodies: TwoBodies, exact, timings: dict, timer: Timer) -> dict:
    timings["build"] = seconds(timer)
    timer = phase("fitted Nitsche solve")
    w = bodies.solve()
    timings["solve"] = seconds(timer)
    timer = phase("fitted Nitsche post")
    error = bodies.pressure_error(w, exact)
    timings["post"] = seconds(timer)
    return {"error": error, "dofs": bodies.dofs(), "timings": timings}


def nitsche_inclusion(
    h: float, degree: int, radius: float = paper.INCLUSION_RADIUS, comm: MPI.Comm = MPI.COMM_WORLD
) -> dict:
    """Paper case 2, the inclusion and the plate as two meshes tied by Nitsche (cell
    size ``h``, m): pressure error against ``-3/2 + cos(2 theta)/2`` Pa, dofs and wall
    times (s) of meshing, building, solving and post-processing. Collective."""
    cx, cy = paper.INCLUSION_CENTRE
    timer = phase("fitted Nitsche mesh")
    gm = mesh_geo(INCLUSION_GEO.format(h=h, cx=cx, cy=cy, r=radius), degree, "triangle", comm)
    timings = {"mesh": seconds(timer)}
    timer = phase("fitted Nitsche build")
    bodies = TwoBodies(gm, degree, Material(paper.INCLUSION_E, 0.0))
    sxx, syy = paper.LOADINGS["paper"]
    bodies.add_pressure(1, lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0), -sxx)
    bodies.add_pressure(1, lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), -syy)
    for point, component in (((0.5, 0.0), 0), ((0.5, 1.0), 0), ((0.0, 0.5), 1)):
        bodies.fix(1, lambda x, p=point: np.isclose(x[0], p[0]) & np.isclose(x[1], p[1]), component)
    x = ufl.SpatialCoordinate(gm.mesh)("+")
    exact = -1.5 + 0.5 * ufl.cos(2 * ufl.atan2(x[1] - cy, x[0] - cx))
    return _run(gm, bodies, exact, timings, timer)


def nitsche_annulus(h: float, degree: int, comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    """Paper case 3 at alpha = 0, the inner and outer rings as two meshes with a
    frictionless (normal) Nitsche tie: pressure error against -1825/1636 MPa, as
    :func:`nitsche_inclusion`."""
    timer = phase("fitted Nitsche mesh")
    gm = mesh_geo(annulus_geo(h), degree, "triangle", comm)
    timings = {"mesh": seconds(timer)}
    timer = phase("fitted Nitsche build")
    bodies = TwoBodies(gm, degree, Material(paper.ANNULUS_E, 0.0), normal_only=True)
    r_in, _, r_out = paper.ANNULUS_RADII
    tol = 1e-6 * r_out
    bodies.fix(1, lambda x: np.abs(np.hypot(x[0], x[1]) - r_in) < tol)
    bodies.add_pressure(
        2, lambda x: np.abs(np.hypot(x[0], x[1]) - r_out) < tol, paper.ANNULUS_PRESSURE
    )
    bodies.fix(2, lambda x: np.isclose(x[0], r_out) & np.isclose(x[1], 0.0), 1)
    return _run(gm, bodies, paper.ANNULUS_CONTACT_PRESSURE, timings, timer)
