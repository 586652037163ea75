"""Friction from 0 to 1e3 stays stable, through a stick-slip transition.

Measured (case 2 pulled in x, 16 x 16, P2, Coulomb): 4 Newton steps for every
coefficient; the open part of the interface shrinks and sticking spreads as mu
grows: mu = 0 to 0.1 all slip (44 points in contact), 0.3: 4 stick / 44 slip (the
transition), 1: 16 / 32, 10: 52 / 4, 1e3: 56 stick. The limits are the
frictionless and the sticking solutions. The cone ``|P_t| <= mu |P_n|`` holds on the
applied tractions to round-off; it is the clamp of the augmented tangential
traction that guards it.
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.cases.paper import inclusion_problem

FRICTIONS = [0.0, 1e-3, 0.1, 0.3, 1.0, 10.0, 1e3]


def solved(law, loading="pull", **options):
    problem = inclusion_problem(16, 2, law, loading=loading, **options)
    report = problem.solve()
    return problem, report


@pytest.mark.mpi
@pytest.mark.parametrize("friction", FRICTIONS)
def test_any_friction_converges_inside_the_cone(friction):
    problem, report = solved("coulomb", friction=friction)
    state = problem.interface_state(problem.w)
    counts = problem.interface_status(problem.w)
    print(f"mu {friction:g}: Newton {report.iterations}, {counts}")
    assert report.iterations <= 30
    assert np.all(np.isfinite(state["lambda_n"])) and np.all(np.isfinite(state["lambda_t"]))
    scale = np.abs(state["P_n"]).max(initial=0.0) + 1e-300
    assert np.all(np.abs(state["P_t"]) <= friction * np.abs(state["P_n"]) + 1e-12 * scale)
    if friction == 0.3:  # the transition: part sticks, part slips
        assert counts["stick"] > 0 and counts["slip"] > 0


@pytest.mark.mpi
@pytest.mark.parametrize(
    "friction, limit, tolerance", [(0.0, "frictionless", 1e-3), (1e3, "sticking", 1e-8)]
)
def test_friction_limits_are_the_frictionless_and_sticking_solutions(friction, limit, tolerance):
    """Under the paper's compression (closed all round). mu = 0 differs from the
    frictionless law by the tangential part of the multiplier stabilisation (measured
    2e-4 relative); mu = 1e3 sticks everywhere: the sticking law's equations. (Pulled,
    the laws differ where the interface opens: ``sticking`` holds the tangential jump
    there too.)"""
    coulomb, _ = solved("coulomb", "paper", friction=friction)
    other, _ = solved(limit, "paper")
    a = coulomb.interface_state(coulomb.w)["lambda_n"]
    b = other.interface_state(other.w)["lambda_n"]
    scale = MPI.COMM_WORLD.allreduce(np.abs(b).max(initial=0.0), op=MPI.MAX)
    difference = MPI.COMM_WORLD.allreduce(np.abs(a - b).max(initial=0.0), op=MPI.MAX)
    assert difference < tolerance * scale
