"""The matrix the direct solver factors is well conditioned: 2-norm condition numbers
(SVD) of the scaled reduced Jacobian of paper case 2, P1 and P2, quadrilaterals and
triangles, for interfaces cutting cells down to a fraction 1e-10 of a cell; and of
the annulus, whose interface follows the cells' reference coordinates.

Measured (n = 6 and 12, cut fractions 0.5 .. 1e-10): at most 3.0e5; unscaled, the
same matrices had 4e18 .. 1e21 (see xfem_contact.solvers.scaling)."""

import xfem_contact  # noqa: F401

# isort: split
import numpy as np
import pytest

from xfem_contact.cases.paper import annulus_problem, inclusion_problem

BOUND = 1e6


def factored_condition(problem) -> float:
    """2-norm condition number of the Jacobian the last Newton solve factored (serial)."""
    J = problem.newton.J_r.convert("dense").getDenseArray()
    s = np.linalg.svd(J, compute_uv=False)
    return float(s[0] / s[-1])


@pytest.mark.serial
@pytest.mark.parametrize("cut_fraction", [0.5, 1e-4, 1e-10])
@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("cell", ["quadrilateral", "triangle"])
def test_case2_condition_is_bounded(cell, degree, cut_fraction):
    """n = 12: the circle's leftmost point is ``cut_fraction`` of a cell left of the
    mesh line x = 1/4."""
    problem = inclusion_problem(12, degree, "sticking", cell, radius=0.25 + cut_fraction / 12)
    problem.solve()
    assert factored_condition(problem) < BOUND


@pytest.mark.serial
@pytest.mark.parametrize("degree", [1, 2])
def test_annulus_condition_is_bounded(degree):
    """The multiplier modes with no trace on the circle (it is a line of the polar
    cells' reference coordinates) are fixed by a term of normal weight: 1.5e4 instead
    of 2.5e10 with the 1e-12 weight alone."""
    problem = annulus_problem(4, 16, degree, geometry_degree=degree)
    problem.solve()
    assert factored_condition(problem) < BOUND
