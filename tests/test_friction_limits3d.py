"""The friction limits in 3D on an exact solution: a cube cut by an inclined plane, the
sides pressed together and slipping along it (``sliding_plane_problem``: linear fields,
a constant multiplier, so P1/Q1 hold the solution). Coulomb with ``mu = 0`` and the
frictionless law both give it to round-off; Coulomb with ``mu = 1e3`` gives the
sticking law's (other) solution.

On the sphere under triaxial compression the two limits differ by a discretisation
error instead (``bench/friction_limits3d.py``): there the Coulomb multiplier is
Cartesian and the frictionless one a scalar, and ``lambda.n`` of a P1 vector field on a
curved surface is another discrete pressure than a P1 scalar. On this plane the normal
is constant, both spaces hold the exact pressure, and the limits coincide."""

import numpy as np
import pytest

from xfem_contact.cases.sliding_plane import sliding_plane_errors, sliding_plane_problem

CELLS = ["tetrahedron", "hexahedron"]


def solved(cell, law, **options):
    problem = sliding_plane_problem(2, 1, law, cell, **options)
    report = problem.solve()
    assert report.converged
    return problem


@pytest.mark.parametrize("cell", CELLS)
def test_coulomb_without_friction_is_the_frictionless_solution(cell):
    """mu = 0 and frictionless: the exact displacement and pressure, no tangential
    traction (P1 tets: 4e-16 and 2e-13; Q1 hexes 5e-15 and 6e-13); mu = 0.3 holds part
    of the slip back (pressure 8e-4, tangential traction 0.26 of the pressure: the
    check sees friction)."""
    for law, options in (("frictionless", {}), ("coulomb", {"friction": 0.0})):
        errors = sliding_plane_errors(solved(cell, law, **options))
        print(f"\nsliding plane {cell} {law} {options}: {errors}")
        assert max(v for v in errors.values() if not np.isnan(v)) < 1e-10
    errors = sliding_plane_errors(solved(cell, "coulomb", friction=0.3))
    assert errors["tangential"] > 0.1 and errors["u_minus"] > 1e-3


@pytest.mark.parametrize("cell", CELLS)
def test_coulomb_with_a_large_friction_is_the_sticking_solution(cell):
    """mu = 1e3 sticks everywhere: the sticking law's multiplier to round-off (which
    holds the slip back: tangential traction 6 times the pressure)."""
    sticking = solved(cell, "sticking")
    coulomb = solved(cell, "coulomb", friction=1e3)
    a, b = (p.interface_state(p.w) for p in (coulomb, sticking))
    scale = np.abs(b["lambda_t"]).max()
    assert np.abs(a["lambda_n"] - b["lambda_n"]).max() < 1e-10 * scale
    assert np.abs(a["lambda_t"] - b["lambda_t"]).max() < 1e-10 * scale
    assert coulomb.interface_status(coulomb.w)["slip"] == 0
    assert sliding_plane_errors(sticking)["tangential"] > 1.0
