"""Heaviside-enriched elasticity: paper case 1 (open straight interface), a
bonded inclusion, conditioning under tiny cuts, dof counts, input errors."""

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

import xfem_contact
from xfem_contact.cases.paper import (
    inclusion_errors,
    inclusion_problem,
    straight_interface_exact,
    straight_interface_problem,
)
from xfem_contact.fem.prolongation import prolongation_matrix
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.presets import ElasticityProblem
from xfem_contact.solvers.linear import assemble_reduced, solve_reduced


def integrate(expr):
    form = xfem_contact.form(expr)
    return form.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(form), op=MPI.SUM)


# -- paper case 1 -----------------------------------------------------------------
def case1(nx, ny, cell, degree):
    """Paper case 1 errors: interface and upper block (relative L2), lower block
    norm, minimum gap, dof counts."""
    problem = straight_interface_problem(nx, ny, degree, cell)
    cut, mesh = problem.cut, problem.mesh
    solution = problem.solve()
    x = ufl.SpatialCoordinate(mesh)
    exact = ufl.as_vector(straight_interface_exact(x))
    lower, upper = ufl.split(solution.w)[:2]
    e_interface = np.sqrt(
        integrate(ufl.inner(upper - exact, upper - exact) * cut.dGamma)
        / integrate(ufl.inner(exact, exact) * cut.dGamma)
    )
    e_upper = np.sqrt(
        integrate(ufl.inner(upper - exact, upper - exact) * cut.dx(1))
        / integrate(ufl.inner(exact, exact) * cut.dx(1))
    )
    lower_norm = np.sqrt(integrate(ufl.inner(lower, lower) * cut.dx(-1)))
    gap = _interface_values(cut, solution.w, 1)[:, 1] - _interface_values(cut, solution.w, 0)[:, 1]
    min_gap = mesh.comm.allreduce(np.min(gap, initial=np.inf), op=MPI.MIN)
    return e_interface, e_upper, lower_norm, min_gap, problem.space.dof_counts()


def _interface_values(cut, w, field):
    """Field values at the interface quadrature points, shape (npoints, 2)."""
    from xfem_contact.fem.evaluation import evaluate_at_rules

    return evaluate_at_rules(w.sub(field), cut, cut.interface_rules)


@pytest.mark.mpi
@pytest.mark.parametrize("cell", ["quadrilateral", "triangle"])
def test_case1_quadratic_is_exact(cell):
    e_interface, e_upper, lower_norm, min_gap, dofs = case1(20, 29, cell, 2)
    assert e_interface < 1e-10
    assert e_upper < 1e-10
    assert lower_norm < 1e-20
    assert min_gap >= 3.875e-6 * (1 - 1e-8)
    # Enriched dofs: both components of the 3 node rows of the cut cell row (Q2/P2)
    assert dofs.enriched == 2 * 3 * 41
    assert dofs.multiplier == 0


def test_case1_linear_converges():
    sizes = [(10, 15), (20, 29), (40, 59), (80, 119)]
    errors = np.array([case1(nx, ny, "quadrilateral", 1)[:2] for nx, ny in sizes])
    h = np.array([1.0 / nx for nx, _ in sizes])
    rates = [np.polyfit(np.log(h), np.log(errors[:, k]), 1)[0] for k in range(2)]
    print("\ncase 1, Q1: interface / upper-block L2 errors", errors.tolist(), "rates", rates)
    assert rates[0] > 1.8 and rates[1] > 1.8


# -- bonded inclusion (paper case 2 geometry) ------------------------------------------
def bonded_inclusion(n, degree):
    """Multiplier (pressure) and displacement relative errors of the bonded inclusion."""
    problem = inclusion_problem(n, degree, "bonded")
    w = problem.solve().w
    x = ufl.SpatialCoordinate(problem.mesh)
    exact = ufl.as_vector([-1e-8 * (x[0] - 0.5), -2e-8 * (x[1] - 0.5)])
    um, up = ufl.split(w)[:2]
    cut = problem.cut
    e_u = np.sqrt(
        (
            integrate(ufl.inner(um - exact, um - exact) * cut.dx(-1))
            + integrate(ufl.inner(up - exact, up - exact) * cut.dx(1))
        )
        / integrate(ufl.inner(exact, exact) * (cut.dx(-1) + cut.dx(1)))
    )
    return inclusion_errors(problem, w).pressure, e_u


@pytest.mark.parametrize("degree, min_rate", [(1, 1.0), (2, 1.5)])
def test_bonded_inclusion_multiplier_rate(degree, min_rate):
    sizes = [10, 20, 40, 80]
    errors = np.array([bonded_inclusion(n, degree) for n in sizes])
    rate = -np.polyfit(np.log(sizes), np.log(errors[:, 0]), 1)[0]
    print(
        f"\nbonded inclusion degree {degree}: multiplier errors {errors[:, 0]}, rate {rate:.2f};"
        f" displacement errors {errors[:, 1]}"
    )
    assert rate >= min_rate
    assert errors[-1, 1] < 1e-4


# -- conditioning under tiny cuts ------------------------------------------------------
def condition_number(eta, degree, n=6):
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, n, n, dolfinx.mesh.CellType.quadrilateral)
    y0 = (3 + eta) / n
    cut = xfem_contact.CutMesh(mesh, lambda x: x[1] - y0, degree=1)
    problem = ElasticityProblem(cut, degree, Material(1.0, 0.3), "free")
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), 0.0)
    R = prolongation_matrix(problem.space)
    A, b = assemble_reduced(
        xfem_contact.form(problem.bilinear_form()),
        xfem_contact.form(problem.loads.linear_form()),
        problem.loads.bcs,
        R,
    )
    dense = A.convert("dense").getDenseArray().copy()
    for obj in (A, b, R):
        obj.destroy()
    return np.linalg.cond(dense)


@pytest.mark.parametrize("degree", [1, 2])
def test_condition_number_bounded_under_tiny_cuts(degree):
    reference = condition_number(0.5, degree)
    ratios = [condition_number(eta, degree) / reference for eta in 10.0 ** -np.arange(1, 11)]
    print(f"\ndegree {degree}: cond(eta)/cond(0.5) for eta = 1e-1..1e-10:", np.round(ratios, 2))
    assert max(ratios) < 10.0


@pytest.mark.mpi
def test_solve_with_a_given_restriction_operator():
    """An explicit R (here the default one) gives the same solution and is not destroyed."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 6, 6)
    cut = xfem_contact.CutMesh(mesh, lambda x: x[1] - 0.55, degree=1)
    problem = ElasticityProblem(cut, 1, Material(1.0, 0.3), "bonded")
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 0.0), 0.0)
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 1.0), 0.01)
    a = xfem_contact.form(problem.bilinear_form())
    L = xfem_contact.form(problem.loads.linear_form())
    w, _ = solve_reduced(a, L, problem.loads.bcs, problem.space)
    R = prolongation_matrix(problem.space)
    w_R, reason = solve_reduced(a, L, problem.loads.bcs, problem.space, R=R)
    assert reason > 0
    scale = mesh.comm.allreduce(np.abs(w.x.array).max(), op=MPI.MAX)
    assert scale > 0.0
    np.testing.assert_allclose(w_R.x.array, w.x.array, rtol=0, atol=1e-12 * scale)
    assert R.getSize()[1] == problem.space.dof_counts().total
    R.destroy()


# -- input errors --------------------------------------------------------------------
def test_bad_input_raises():
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    cut = xfem_contact.CutMesh(mesh, lambda x: x[1] - 0.55, degree=1)
    with pytest.raises(ValueError, match="Unknown interface law"):
        ElasticityProblem(cut, 1, Material(1.0, 0.3), "glued")
    with pytest.raises(ValueError, match="Young's modulus"):
        Material(-1.0, 0.3)
    with pytest.raises(ValueError, match="Poisson"):
        Material(1.0, 0.5)
    problem = ElasticityProblem(cut, 1, Material(1.0, 0.3), "free")
    with pytest.raises(ValueError, match="no boundary facet"):
        problem.loads.add_pressure(lambda x: np.isclose(x[0], 7.0), 1.0)


@pytest.mark.mpi
def test_mesh_without_ghost_cells_is_refused_in_parallel():
    """The ghost penalty needs the cells across shared facets: a mesh distributed
    without ghosts would silently drop the facets between processes."""
    partitioner = dolfinx.mesh.create_cell_partitioner(dolfinx.mesh.GhostMode.none, 2)
    mesh = dolfinx.mesh.create_rectangle(
        MPI.COMM_WORLD,
        [[0.0, 0.0], [1.0, 1.0]],
        [8, 8],
        dolfinx.mesh.CellType.quadrilateral,
        partitioner=partitioner,
    )
    cut = xfem_contact.CutMesh(mesh, lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.3, degree=2)
    if MPI.COMM_WORLD.size == 1:  # nothing to ghost
        assert ElasticityProblem(cut, 1, Material(1.0, 0.3)).ghost_penalty > 0
    else:
        with pytest.raises(ValueError, match="without ghost cells"):
            ElasticityProblem(cut, 1, Material(1.0, 0.3))
