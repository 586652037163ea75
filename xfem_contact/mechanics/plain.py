"""Plain (uncut) linear elasticity: what a scene without interfaces builds.

It follows the protocol of :class:`~xfem_contact.mechanics.problem.Problem` with no
interface: ``loads``, ``space`` (one field), ``w``, ``laws`` (none), ``solve()``
returning a :class:`~xfem_contact.solvers.report.SolveReport`, ``accept_step()``, so
that the scene runner, the outputs and the reactions treat both alike.

One displacement field on the whole mesh, standard DOLFINx forms and one
linear solve; no level set, no cut, no enrichment, no multiplier. Its loads are a
:class:`~xfem_contact.mechanics.loads.Loads` as a cut problem's (``problem.loads``).
"""

from __future__ import annotations

import warnings

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import numpy as np
import numpy.typing as npt
import ufl

from xfem_contact._timers import phase, seconds
from xfem_contact.fem.enrichment import DofCounts
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.loads import Loads, PlainFields
from xfem_contact.mechanics.materials import Material, Moduli
from xfem_contact.solvers.options import applied_options, checked_prefix, preset
from xfem_contact.solvers.report import LinearSolveFailure, SolveReport


class PlainSpace:
    """One displacement field on the whole mesh, seen as an enriched space with no
    enrichment (the names and methods of :class:`~xfem_contact.fem.enrichment.EnrichedSpace`
    that a runner reads)."""

    #: The displacement fields (one) and their sides
    fields = (0,)
    multiplier_fields: list = []

    def __init__(self, V: dolfinx.fem.FunctionSpace):
        self.W = V
        imap = V.dofmap.index_map
        self._all = np.arange((imap.size_local + imap.num_ghosts) * V.dofmap.index_map_bs)

    def field_names(self) -> list[str]:
        """``["u"]``."""
        return ["u"]

    def displacement_sides(self) -> list[tuple[str, int]]:
        """``(label, side)`` of each displacement field: one, side +1."""
        return [("", 1)]

    def field_space(self, field: int) -> tuple[dolfinx.fem.FunctionSpace, npt.NDArray]:
        """The space itself and the identity map of its local dofs."""
        return self.W, self._all

    def test(self) -> tuple:
        return (ufl.TestFunction(self.W),)

    def trial(self) -> tuple:
        return (ufl.TrialFunction(self.W),)

    def split(self, w) -> tuple:
        """The one field of ``w``: ``(w,)``."""
        return (w,)

    def dof_counts(self) -> DofCounts:
        """Global dof counts (all standard)."""
        n = self.W.dofmap.index_map.size_global * self.W.dofmap.index_map_bs
        return DofCounts(n, 0, 0)


class _Bulk:
    """The bulk model's view a runner reads: the material of the one side."""

    def __init__(self, material: Moduli):
        self.materials = {1: material}


class PlainElasticityProblem:
    """Small-strain elasticity with Dirichlet data, loads and supports (SI units).

    Args:
        mesh: The mesh.
        degree: Displacement degree (Lagrange).
        material: The material (its moduli become Constants: ``problem.material.E``).
        petsc_options: PETSc options (names without prefix) of the KSP, over the preset
            ``plain`` of :data:`~xfem_contact.solvers.options.PRESETS` (PETSc's LU);
            settable later as :attr:`petsc_options`.
        petsc_options_prefix: The KSP's options prefix; ``None``: a prefix unique in the
            process (``"xfem_plain_3_"``); an empty one is refused.

    Collective.
    """

    #: One linear solve; no interface, no law, small kinematics
    linear, symmetric, kinematics, cut = True, True, "small", None

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        degree: int,
        material: Material,
        *,
        petsc_options: dict | None = None,
        petsc_options_prefix: str | None = None,
    ):
        #: The options prefix of the KSP
        self.petsc_options_prefix = checked_prefix(petsc_options_prefix, "xfem_plain_")
        #: The PETSc options the user gave (names without prefix)
        self.petsc_options = dict(petsc_options or {})
        self.mesh = mesh
        self.material = Moduli(material, mesh)
        self.V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (mesh.geometry.dim,)))
        self.space = PlainSpace(self.V)
        self.bulk = _Bulk(self.material)
        self.laws: dict = {}
        self.couplings: dict = {}
        #: The solution (m)
        self.w = dolfinx.fem.Function(self.V, name="u")
        #: Loads, supports and Dirichlet data (``loads.bcs``), and the pseudo-time
        self.loads = Loads(PlainFields(self.V))
        self.last_report: SolveReport | None = None

    def bilinear_form(self) -> ufl.Form:
        """``a(u, v)``: the bulk and the springs' terms (UFL)."""
        u, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        a = ufl.inner(self.material.stress(u), ufl.sym(ufl.grad(v))) * ufl.dx
        springs = self.loads.spring_terms((u,), (v,))
        return a if springs is None else a + springs

    def solve(self, petsc_options: dict | None = None, log=None) -> SolveReport:
        """One linear solve (PETSc LU unless :attr:`petsc_options` say otherwise); ``w``
        holds the result and :attr:`last_report` the report. ``petsc_options``:
        deprecated (give them at construction), options for this solve only. ``log`` is
        unused (no iterates). Collective.

        Raises:
            LinearSolveFailure: the KSP diverged; ``w`` then holds the state from before
                this solve and :attr:`last_report` the failed solve's report.
        """
        if petsc_options is not None:
            warnings.warn(
                "PlainElasticityProblem.solve(petsc_options=...) is deprecated and will be "
                "removed in the next release: give the options at construction, "
                "PlainElasticityProblem(..., petsc_options=...), or set "
                "problem.petsc_options",
                DeprecationWarning,
                stacklevel=2,
            )
        timer = phase("plain linear solve")
        accepted = self.w.x.array.copy()
        options = {**preset("plain"), **self.petsc_options, **(petsc_options or {})}
        # the options in the database while PETSc reads them (MUMPS's at the solve)
        with applied_options(self.petsc_options_prefix, options):
            problem = dolfinx.fem.petsc.LinearProblem(
                form(self.bilinear_form()),
                form(self.loads.linear_form()),
                bcs=self.loads.bcs,
                u=self.w,
                petsc_options_prefix=self.petsc_options_prefix,
            )
            try:
                problem.solver.setFromOptions()
                problem.solve()
                reason = problem.solver.getConvergedReason()
            finally:
                del problem  # its KSP, matrix and vectors (LinearProblem.__del__)
        self.last_report = SolveReport(
            reason=reason, total_time=seconds(timer), w=self.w, space=self.space
        )
        if reason < 0:
            self.w.x.array[:] = accepted
            raise LinearSolveFailure(
                f"Linear solve failed: KSP converged reason {reason}; w restored to the state"
                " before this solve",
                self.last_report,
            )
        return self.last_report

    def accept_step(self) -> None:
        """Nothing to accept: no interface law has a history."""

    def interface_status(self, w: dolfinx.fem.Function, name: str | None = None) -> dict:
        """No interface: ``{}``."""
        return {}
