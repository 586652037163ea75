"""The crack-tip enrichment's change of unknowns (xfem_contact.solvers.block_scaling):
bounded conditioning, the same solution, and no extra MUMPS workspace.

Williams case, geometric enrichment r_e = 0.4 with the ramp, triangles, 2-norm
condition numbers of the matrix the solver factors (dense eigenvalues); the ramp's 4
null vectors per tip are removed by the pinned F_1, F_2 dofs of one node
(:func:`xfem_contact.fem.branch.null_pins`), so none is left. Measured with the change
of unknowns at n = 8, 16: P1 1.9e3, 8.6e3; P2 6.5e3, 1.6e5 (the P2 n = 16 one set by a
small cut far from the tip). With the Jacobi scaling alone (the check fails so): P1
4.5e7, 1.5e9; P2 5.2e7, 1.7e9 (measured with the null vectors left out).
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import dolfinx.fem
import numpy as np
import pytest
import ufl
from mpi4py import MPI

import xfem_contact.mechanics.solving as solving_module
from xfem_contact.cases.cracks import frictional_crack_case, williams_case
from xfem_contact.fem.forms import form
from xfem_contact.solvers.block_scaling import scaled, tip_transform
from xfem_contact.solvers.linear import assemble_reduced, solve_reduced

BOUND = 1e6


def factored_condition(problem) -> tuple[float, int]:
    """2-norm condition number of ``Z^T A Z``, the matrix the linear solve factors,
    without its null modes (eigenvalues below 1e-12 of the largest), and their number."""
    R = problem.prolongation()
    a, L = form(problem.bilinear_form()), form(problem.loads.linear_form())
    A, b = assemble_reduced(a, L, problem.loads.bcs, R)
    Z = tip_transform(problem.space)(R, A)
    J = scaled(A, Z)
    eigenvalues = np.abs(np.linalg.eigvalsh(J.convert("dense").getDenseArray()))
    for obj in (A, b, Z, J, R):
        obj.destroy()
    eigenvalues.sort()
    null = int(np.sum(eigenvalues < 1e-12 * eigenvalues[-1]))
    return float(eigenvalues[-1] / eigenvalues[null]), null


@pytest.mark.serial
@pytest.mark.parametrize("degree", [1, 2])
def test_tip_enrichment_condition_is_bounded(degree):
    cases = [williams_case(n, degree, tip_radius=0.4) for n in (8, 16)]
    measured = [factored_condition(case.problem) for case in cases]
    kappa = [k for k, _ in measured]
    assert all(null == 0 for _, null in measured)  # the pins removed the null vectors
    assert max(kappa) < BOUND
    if degree == 1:  # no small cut in the way: standard FEM's h^-2 (at most h^-3 allowed)
        assert kappa[1] / kappa[0] < 8


def strain_energy(problem, w) -> float:
    """``sum_s int eps(u_s) : eps(u_s)`` of the displacements of ``w`` (a Function on W;
    the dofs are not unique along the ramp's null vectors, the field is)."""
    u = problem.space.split(w)
    local = sum(
        dolfinx.fem.assemble_scalar(
            form(ufl.inner(ufl.sym(ufl.grad(u[i])), ufl.sym(ufl.grad(u[i]))) * problem.cut.dx(s))
        )
        for i, s in enumerate((-1, 1))
    )
    return MPI.COMM_WORLD.allreduce(local, op=MPI.SUM)


def relative_difference(problem, w0, w1) -> float:
    difference = dolfinx.fem.Function(problem.space.W)
    difference.x.array[:] = w0.x.array - w1.x.array
    return math.sqrt(strain_energy(problem, difference) / strain_energy(problem, w1))


def test_tip_scaling_keeps_the_linear_solution():
    problem = williams_case(8, 2, tip_radius=0.4).problem
    a, L = form(problem.bilinear_form()), form(problem.loads.linear_form())
    w = [
        solve_reduced(a, L, problem.loads.bcs, problem.space, tip_scaling=on)[0]
        for on in (True, False)
    ]
    assert relative_difference(problem, *w) < 1e-9


def test_tip_scaling_keeps_the_newton_solution(monkeypatch):
    """The closed crack with friction (an unsymmetric Jacobian), with and without."""
    w = []
    for on in (True, False):
        if not on:
            monkeypatch.setattr(solving_module, "tip_transform", lambda space, off=False: None)
        case = frictional_crack_case(4, 2, friction=0.3, tip_radius=0.5)
        case.problem.solve()
        assert (case.problem.newton.tip is not None) == on
        w.append(case.problem.w.copy())
    assert relative_difference(case.problem, *w) < 1e-8


def test_no_extra_workspace_with_the_change_of_unknowns():
    problem = williams_case(8, 1, tip_radius=0.4).problem
    assert "mat_mumps_icntl_14" not in problem.solver_options()
    assert problem.solver_options({"pc_type": "python"})["mat_mumps_icntl_14"] == 100
