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
from xfem_contact.cases.cracks import frictional_crack_case, williams_case, williams_energy_error
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


@pytest.mark.serial
def test_shifted_tip_basis_keeps_the_rate_on_a_large_zone():
    """Williams field on Q2 quadrilaterals, tip zone r_e = 0.9 (most of the square): with
    the default basis (``"shifted"`` for P2) the energy error falls at about Q2's rate 2
    from n = 22 to 44 (2.42e-4, 6.63e-5: 1.87); with ``"plain"`` (the same space) it does
    not (rounding in the stiffness' cancellation of ``R F_k`` against the standard
    functions: 1.4e-3 at n = 44, 0.20 at n = 64)."""
    errors = []
    for n in (22, 44):
        case = williams_case(n, 2, tip_radius=0.9, cell="quadrilateral")
        case.problem.solve()
        errors.append(williams_energy_error(case))
    rate = math.log2(errors[0] / errors[1])
    assert rate > 1.8, f"energy errors {errors}, rate {rate:.2f}"


def test_tip_bases_span_one_space():
    """The closed crack with friction (P2, contact on the lips): ``"plain"`` and
    ``"shifted"`` give the same displacement field and the same jump of the lips at the
    rule points (the interpolants' jump taken out)."""
    from xfem_contact.cases.cracks import _square

    mesh = _square(2.0, 16, "triangle", MPI.COMM_WORLD)
    problems = []
    for basis in ("plain", "shifted"):
        case = frictional_crack_case(4, 2, friction=0.3, tip_radius=0.5, mesh=mesh, tip_basis=basis)
        case.problem.solve()
        problems.append(case.problem)
    (u0, u1) = (p.space.split(p.w) for p in problems)
    cut = problems[0].cut

    def energy(f) -> float:
        return MPI.COMM_WORLD.allreduce(
            sum(
                dolfinx.fem.assemble_scalar(
                    form(ufl.inner(ufl.grad(f[i]), ufl.grad(f[i])) * cut.dx(s))
                )
                for i, s in enumerate((-1, 1))
            ),
            op=MPI.SUM,
        )

    difference = [u0[i] - u1[i] for i in (0, 1)]
    assert math.sqrt(energy(difference) / energy(u0)) < 1e-8
    (name,) = problems[0].laws
    jumps = [p.contexts[name].jump_at(p.w) for p in problems]
    assert np.abs(jumps[0] - jumps[1]).max() < 1e-8 * np.abs(jumps[0]).max()


def test_tip_basis_is_checked():
    with pytest.raises(
        ValueError, match=r"tip_basis must be one of \('auto', 'plain', 'shifted'\)"
    ):
        williams_case(4, 2, tip_basis="stable")
    with pytest.raises(ValueError, match="tip_basis='shifted' needs displacement degree 2"):
        williams_case(4, 1, tip_basis="shifted")
    with pytest.raises(ValueError, match="got degree 2, aggregation on: use 'plain'"):
        williams_case(4, 2, tip_basis="shifted", aggregation=0.25)
    # the default: shifted where it applies (P2 without aggregation), else plain
    assert williams_case(4, 1).problem.space.tip_basis == "plain"
    assert williams_case(4, 2).problem.space.tip_basis == "shifted"
    assert williams_case(4, 2, aggregation=0.25).problem.space.tip_basis == "plain"


def test_shifted_functions_vanish_at_a_vertex_on_a_tip():
    """Tips on vertices whose coordinates carry round-off (x = -1 - 2e-16, y = -5e-18 on
    one process): the shifted basis' interpolants are 0 there, as ``F_k(0)``. The square
    root made them 1e-9 .. 5e-9 at an angle set by the round-off, which differs between
    1 and 2 processes: the standard dofs then differed by 5.6e-10 (relative) between them,
    the field by 1e-14 (the same span)."""
    from xfem_contact.cases.cracks import griffith_case

    space = griffith_case(4, 2, tip_radius=0.5, angle=0.0, offset=(0.0, 0.0)).problem.space
    P1 = space.interpolants[1][0].function_space
    x = P1.tabulate_dof_coordinates()[:, :2]
    distance = np.linalg.norm(x[:, None, :] - space.cut.crack.tips[None], axis=2).min(axis=1)
    on_tip = distance < 1e-9
    assert MPI.COMM_WORLD.allreduce(int(on_tip.sum()), op=MPI.SUM) >= 2  # the case is present
    for functions in space.interpolants.values():
        for f in functions:
            assert np.all(f.x.array[on_tip] == 0.0)
