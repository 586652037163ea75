"""Plain (uncut) linear elasticity: what a scene without interfaces builds.

One displacement field on the whole mesh, standard DOLFINx forms and one
linear solve; no level set, no cut, no enrichment, no multiplier.
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.mechanics.loading import Facets, LoadFactor, boundary_facets
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.options import remove_options, unique_prefix


class PlainElasticityProblem:
    """Small-strain elasticity with Dirichlet data and boundary loads (SI units)."""

    #: One linear solve
    linear = True

    def __init__(self, mesh: dolfinx.mesh.Mesh, degree: int, material: Material):
        self.mesh, self.material = mesh, material
        self.V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (mesh.geometry.dim,)))
        self._bcs, self._rhs, self._facet_sets, self._body = [], [], [], []
        self._x = ufl.SpatialCoordinate(mesh)
        #: Scales every load and prescribed displacement (see :mod:`xfem_contact.mechanics.loading`)
        self.load_factor = LoadFactor(mesh)

    def _ufl(self, value):
        """A load as UFL: numbers and expressions as they are, callables of ``x`` applied."""
        if isinstance(value, ufl.core.expr.Expr) or not callable(value):
            return ufl.as_ufl(value)
        return value(self._x)

    def facets(self, part: Facets) -> np.ndarray:
        """Local exterior facet indices of a boundary part; error if it is empty."""
        return boundary_facets(self.mesh, part)

    def add_displacement(self, locator, value, component: int | None = None) -> None:
        fdim, facets = self.mesh.topology.dim - 1, self.facets(locator)
        if component is None:
            g = dolfinx.fem.Function(self.V)
            _fill(g, value)
            self.load_factor.track(g)
            dofs = dolfinx.fem.locate_dofs_topological(self.V, fdim, facets)
            self._bcs.append(dolfinx.fem.dirichletbc(g, dofs))
            return
        sub = self.V.sub(component)
        V, _ = sub.collapse()
        g = dolfinx.fem.Function(V)
        _fill(g, value)
        self.load_factor.track(g)
        dofs = dolfinx.fem.locate_dofs_topological((sub, V), fdim, facets)
        self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))

    def add_point_displacement(self, point, value: float, component: int) -> None:
        sub = self.V.sub(component)
        V, _ = sub.collapse()
        dofs = dolfinx.fem.locate_dofs_geometrical(
            (sub, V), lambda x: np.isclose(x[0], point[0]) & np.isclose(x[1], point[1])
        )
        if self.mesh.comm.allreduce(dofs[0].size, op=MPI.SUM) == 0:
            raise ValueError(f"No mesh node at {list(point)} to fix")
        g = dolfinx.fem.Function(V)
        g.x.array[:] = value
        self.load_factor.track(g)
        self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))

    def add_traction(self, locator, traction) -> None:
        facets = self.facets(locator)
        self._facet_sets.append(facets)
        self._rhs.append((len(self._facet_sets), self.load_factor.scaled(self._ufl(traction))))

    def add_pressure(self, locator, pressure) -> None:
        self.add_traction(locator, -self._ufl(pressure) * ufl.FacetNormal(self.mesh))

    def add_body_force(self, force) -> None:
        """Body force density (N/m^3), scaled by the load factor."""
        self._body.append(self.load_factor.scaled(self._ufl(force)))

    def solve(self, petsc_options: dict | None = None) -> dolfinx.fem.Function:
        """One linear solve (PETSc LU unless ``petsc_options`` say otherwise). Collective."""
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        a = ufl.inner(self.material.stress(u), ufl.sym(ufl.grad(v))) * ufl.dx
        entities = [(k + 1, self._pairs(f)) for k, f in enumerate(self._facet_sets)]
        ds = ufl.Measure("ds", domain=self.mesh, subdomain_data=entities)
        L = sum((ufl.inner(t, v) * ds(k) for k, t in self._rhs), ufl.ZeroBaseForm((v,)))
        L += sum((ufl.inner(f, v) * ufl.dx for f in self._body), ufl.ZeroBaseForm((v,)))
        prefix = unique_prefix("xfem_plain_")
        problem = dolfinx.fem.petsc.LinearProblem(
            a,
            L,
            bcs=self._bcs,
            petsc_options_prefix=prefix,
            petsc_options={"ksp_type": "preonly", "pc_type": "lu", **(petsc_options or {})},
        )
        try:
            return problem.solve()
        finally:
            remove_options(prefix)  # nothing of ours outlives the solve

    def _pairs(self, facets):
        tdim = self.mesh.topology.dim
        self.mesh.topology.create_connectivity(tdim - 1, tdim)
        return dolfinx.fem.compute_integration_domains(
            dolfinx.fem.IntegralType.exterior_facet, self.mesh.topology, facets
        )


def _fill(g: dolfinx.fem.Function, value) -> None:
    """Interpolate a callable or set a constant."""
    if callable(value):
        g.interpolate(value)
    else:
        g.x.array[:] = value
