"""Plain (uncut) linear elasticity: what a scene without interfaces builds.

One displacement field on the whole mesh, standard DOLFINx forms and one
linear solve; no level set, no cut, no enrichment, no multiplier. Its loads are a
:class:`~xfem_contact.mechanics.loads.Loads` as a cut problem's (``problem.loads``).
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from xfem_contact.fem.forms import form
from xfem_contact.mechanics.loads import Loads, PlainFields
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.options import remove_options, unique_prefix


class PlainElasticityProblem:
    """Small-strain elasticity with Dirichlet data, loads and supports (SI units).

    Args:
        mesh: The mesh.
        degree: Displacement degree (Lagrange).
        material: The material.

    Collective.
    """

    #: One linear solve
    linear = True

    def __init__(self, mesh: dolfinx.mesh.Mesh, degree: int, material: Material):
        self.mesh, self.material = mesh, material
        self.V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (mesh.geometry.dim,)))
        #: Loads, supports and Dirichlet data (``loads.bcs``), and the pseudo-time
        self.loads = Loads(PlainFields(self.V))

    def bilinear_form(self) -> ufl.Form:
        """``a(u, v)``: the bulk and the springs' terms (UFL)."""
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        a = ufl.inner(self.material.stress(u), ufl.sym(ufl.grad(v))) * ufl.dx
        springs = self.loads.spring_terms((u,), (v,))
        return a if springs is None else a + springs

    def solve(self, petsc_options: dict | None = None) -> dolfinx.fem.Function:
        """One linear solve (PETSc LU unless ``petsc_options`` say otherwise). Collective."""
        prefix = unique_prefix("xfem_plain_")
        problem = dolfinx.fem.petsc.LinearProblem(
            form(self.bilinear_form()),
            form(self.loads.linear_form()),
            bcs=self.loads.bcs,
            u=dolfinx.fem.Function(self.V, name="u"),
            petsc_options_prefix=prefix,
            petsc_options={"ksp_type": "preonly", "pc_type": "lu", **(petsc_options or {})},
        )
        try:
            return problem.solve()
        finally:
            remove_options(prefix)  # nothing of ours outlives the solve
