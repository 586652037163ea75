"""Contact on hexahedra against exact solutions: the sphere (quadric level set, which the
Q2 interpolant holds exactly) in the unit cube under a uniform stress, on Q1 and Q2
hexahedra. The exact displacement is linear and the exact multiplier (the Cartesian
``sigma (x - c) / R`` of the sticking law, the constant pressure of the frictionless
law under hydrostatic stress) lies in the multiplier space: a patch test, so what is
left is the cut rules' error on the curved pieces. The interface passes through 8
cells at n = 4 (its centre is a mesh vertex).

Measured (n = 4, the default cut rules of degree 6; ``python -m pytest -s``): sticking,
relative pressure error Q1 2.6e-7, Q2 3.6e-7 (rules of degree 4: Q1 8.5e-6, Q2 2.7e-5;
degree 3: Q2 0.38: Q2 needs the 4 Gauss points per interval of degree 6); frictionless
under hydrostatic stress, Q1 2.6e-7, Q2 3.8e-7. The bound 3e-6 is ten times the
largest of these and below what a rule one step lower gives."""

import warnings

import numpy as np
import pytest
from mpi4py import MPI
from parallel import all_ranks_against_one

from xfem_contact.cases.solid import hold_spins, patch_residual, sphere_errors, sphere_problem

#: The pressure error of the patch test, relative to the exact pressure's L2 norm
PATCH_BOUND = 3e-6


def hex_sphere(degree, law, n=4, comm=MPI.COMM_WORLD, **options):
    """The quadric sphere on Q``degree`` hexahedra, solved."""
    problem = sphere_problem(n, degree, law, "hexahedron", comm, levelset="quadric", **options)
    if law == "frictionless":  # its three spins: held at nodes the exact field meets
        hold_spins(problem, 1.0 / n)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no rigid-mode warning: the spins are held
        report = problem.solve()
    assert report.converged and report.iterations <= 2
    return problem


@pytest.mark.parametrize("degree", [1, 2])
def test_sticking_sphere_on_hexahedra_is_a_patch_test(degree):
    """Triaxial compression diag(-1, -2, -3) Pa, sticking: ``lambda_n = n.sigma.n`` and
    the tangential traction ``(I - n n) sigma n`` to the cut rules' accuracy; the exact
    solution's residual is as small."""
    problem = hex_sphere(degree, "sticking")
    e_n, e_t = sphere_errors(problem)
    residual = patch_residual(problem)
    print(
        f"\nsticking sphere Q{degree} n=4: pressure {e_n:.2e}, tangential {e_t:.2e}, "
        f"residual {residual:.2e}"
    )
    assert e_n < PATCH_BOUND and e_t < PATCH_BOUND and residual < PATCH_BOUND


def test_frictionless_sphere_on_hexahedra_is_a_patch_test():
    """Hydrostatic compression 1 Pa, frictionless, the spins held: the uniform pressure
    -1 Pa (the scalar multiplier's constant), Q1 (Q2 takes 16 s for the same check)."""
    problem = hex_sphere(1, "frictionless", stress=(-1.0, -1.0, -1.0))
    e_n, _ = sphere_errors(problem)
    state = problem.interface_state(problem.w)
    print(f"\nfrictionless sphere Q1 n=4: pressure {e_n:.2e}")
    assert e_n < PATCH_BOUND
    assert np.all(state["P_n"] < 0.0)  # closed everywhere


@pytest.mark.mpi
@pytest.mark.parallel
@pytest.mark.parametrize("law, options", [("sticking", {}), ("coulomb", {"friction": 0.1})])
def test_hex_sphere_parallel_equals_serial(law, options):
    """The triaxial sphere on Q1 hexahedra, sticking and slipping (Coulomb, mu = 0.1),
    n = 6 (32 cut cells): the fields of all ranks against one rank's,
    gathered and sorted by position."""
    differences = all_ranks_against_one(
        lambda comm: sphere_problem(6, 1, law, "hexahedron", comm, levelset="quadric", **options)
    )
    if MPI.COMM_WORLD.rank == 0:
        print(law, {k: f"{v:.1e}" for k, v in differences.items()})
    assert all(v <= 1e-10 for v in differences.values()), differences
