"""The crack-tip enrichment's change of unknowns (xfem_contact.solvers.block_scaling):
bounded conditioning, the same solution, and no extra MUMPS workspace.

Williams case, geometric enrichment r_e = 0.4, triangles, 2-norm condition numbers of
the matrix the solver factors (dense eigenvalues). Measured with the change of unknowns
at n = 8, 16: P1 46, 198; P2 1.7e3, 1.4e5 (the latter set by a small cut far from the
tip, not by the enrichment). With the Jacobi scaling alone (the check fails so):
P1 1.2e5, 1.7e7; P2 1.7e6, 7.1e7, growing like h^-6.
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import numpy as np
import pytest

import xfem_contact.mechanics.problem as problem_module
from xfem_contact.cases.cracks import frictional_crack_case, williams_case
from xfem_contact.fem.forms import form
from xfem_contact.solvers.block_scaling import scaled, tip_transform
from xfem_contact.solvers.linear import assemble_restricted, solve_restricted

BOUND = 1e6


def factored_condition(problem) -> float:
    """2-norm condition number of ``Z^T A Z``, the matrix the linear solve factors."""
    R = problem.restriction()
    a, L = form(problem.bilinear_form()), form(problem.loads.linear_form())
    A, b = assemble_restricted(a, L, problem.loads.bcs, R)
    Z = tip_transform(problem.space)(R, A)
    J = scaled(A, Z)
    eigenvalues = np.abs(np.linalg.eigvalsh(J.convert("dense").getDenseArray()))
    for obj in (A, b, Z, J, R):
        obj.destroy()
    return float(eigenvalues.max() / eigenvalues.min())


@pytest.mark.serial
@pytest.mark.parametrize("degree", [1, 2])
def test_tip_enrichment_condition_is_bounded(degree):
    kappa = [factored_condition(williams_case(n, degree, tip_radius=0.4).problem) for n in (8, 16)]
    assert max(kappa) < BOUND
    if degree == 1:  # no small cut in the way: standard FEM's h^-2 (at most h^-3 allowed)
        assert kappa[1] / kappa[0] < 8


def test_tip_scaling_keeps_the_linear_solution():
    problem = williams_case(8, 2, tip_radius=0.4).problem
    a, L = form(problem.bilinear_form()), form(problem.loads.linear_form())
    solutions = [
        solve_restricted(a, L, problem.loads.bcs, problem.space, tip_scaling=on)[0].x.array
        for on in (True, False)
    ]
    scale = np.abs(solutions[1]).max()
    assert np.abs(solutions[0] - solutions[1]).max() < 1e-9 * scale


def test_tip_scaling_keeps_the_newton_solution(monkeypatch):
    """The closed crack with friction (an unsymmetric Jacobian), with and without."""
    w = []
    for on in (True, False):
        if not on:
            monkeypatch.setattr(problem_module, "tip_transform", lambda space, off=False: None)
        case = frictional_crack_case(4, 2, friction=0.3, tip_radius=0.5)
        case.problem.solve()
        assert (case.problem.newton.tip is not None) == on
        w.append(case.problem.w.x.array.copy())
    assert np.abs(w[0] - w[1]).max() < 1e-8 * np.abs(w[1]).max()


def test_no_extra_workspace_with_the_change_of_unknowns():
    problem = williams_case(8, 1, tip_radius=0.4).problem
    assert "mat_mumps_icntl_14" not in problem.solver_options()
    assert problem.solver_options({"pc_type": "python"})["mat_mumps_icntl_14"] == 100
