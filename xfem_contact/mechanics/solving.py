"""How a :class:`~xfem_contact.mechanics.problem.Problem` is solved on its active dofs.

A linear problem is one KSP solve of ``R^T A R y = R^T b`` (:func:`linear_solve`); a
problem with a contact law is solved by a generalized Newton method
(:class:`~xfem_contact.solvers.newton.ReducedNewton`, built by :func:`newton_solver`)
whose residual is the problem's UFL residual plus its two-cell couplings. Both return a
:class:`~xfem_contact.solvers.report.SolveReport`; the problem keeps its state."""

from __future__ import annotations

from typing import TYPE_CHECKING

from xfem_contact._timers import phase, seconds
from xfem_contact.fem.forms import form
from xfem_contact.fem.prolongation import prescribed_extension as fem_prescribed_extension
from xfem_contact.mechanics.fieldsplit_data import (
    fieldsplit_dofs,
    rigid_modes,
    vertex_interpolation,
)
from xfem_contact.mechanics.lbb_space import combine_prolongations
from xfem_contact.solvers.linear import solve_reduced, tip_transform
from xfem_contact.solvers.newton import ReducedNewton, weak_method
from xfem_contact.solvers.options import uses_fieldsplit
from xfem_contact.solvers.report import SolveReport

if TYPE_CHECKING:
    from xfem_contact.mechanics.problem import Problem

__all__ = ["linear_solve", "newton_solver", "prescribed_extension", "prolongation_parts"]


def prolongation_parts(problem: Problem) -> tuple:
    """The arguments of ``problem``'s prolongation after its space
    (:func:`~xfem_contact.fem.prolongation.prolongation_matrix`): the laws' combined
    multiplier prolongation and, with cell aggregation, the Dirichlet dofs (which stay
    unknowns). Collective."""
    prolongations = [
        p
        for name, law in problem.laws.items()
        if (p := law.prolongation(problem.contexts[name], problem.space)) is not None
    ]
    fixed = None if problem.space.aggregation is None else problem.loads.dirichlet_dofs()
    return combine_prolongations(prolongations, problem.mesh.comm), fixed


def prescribed_extension(problem: Problem):
    """The prescribed part ``E`` of cell aggregation's extension for ``problem``
    (``x = E g + R y``, ``g`` the Dirichlet values, ``R`` of its
    :meth:`~xfem_contact.mechanics.problem.Problem.prolongation`;
    :func:`~xfem_contact.fem.prolongation.prescribed_extension`), or None. Collective."""
    if problem.space.aggregation is None:
        return None
    return fem_prescribed_extension(problem.space, *prolongation_parts(problem))


def linear_solve(problem: Problem, petsc_options: dict) -> SolveReport:
    """Solve the linear ``problem`` with the full PETSc options ``petsc_options`` (see
    :meth:`~xfem_contact.mechanics.problem.Problem.solver_options`) and copy the solution
    into ``problem.w``. Collective.

    Raises:
        LinearSolveFailure: if the KSP diverged; ``problem.w`` is untouched.
    """
    a = form(problem.bilinear_form())
    L = form(problem.loads.linear_form())
    timer, residuals = phase("linear solve"), []
    R, E = problem.prolongation(), prescribed_extension(problem)
    try:
        w, reason = solve_reduced(
            a,
            L,
            problem.loads.bcs,
            problem.space,
            petsc_options,
            problem.petsc_options_prefix,
            R=R,
            residuals=residuals,
            extension=E,
        )
    finally:
        for matrix in (R, E):
            if matrix is not None:
                matrix.destroy()
    problem.w.x.array[:] = w.x.array
    return SolveReport(
        residuals, reason=reason, total_time=seconds(timer), w=problem.w, space=problem.space
    )


def newton_solver(problem: Problem, petsc_options: dict) -> ReducedNewton:
    """The generalized Newton solver of ``problem`` at its state ``problem.w``: its
    residual, Dirichlet conditions, prolongation and, when the options ask for a field
    split, the split's dofs, rigid modes and vertex interpolation. Collective."""
    space = problem.space
    fieldsplit = uses_fieldsplit(petsc_options)
    return ReducedNewton(
        problem.residual(problem.w),
        problem.w,
        problem.loads.bcs,
        problem.prolongation(),
        petsc_options,
        problem.petsc_options_prefix,
        status=weak_method(problem.interface_status),
        fieldsplit_dofs=fieldsplit_dofs(space) if fieldsplit else None,
        near_nullspace=rigid_modes(space) if fieldsplit else None,
        interpolation=vertex_interpolation(space) if fieldsplit else None,
        couplings=list(problem.couplings.values()),
        field_space=space.field_space,
        transform=tip_transform(space, off=fieldsplit or bool(problem.couplings)),
        extension=prescribed_extension(problem),
    )
