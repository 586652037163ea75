"""Parallel = serial, on the fields: the multipliers at the interface points and the
displacements at the dofs, gathered and sorted by position, on all ranks against
each rank alone (MPI suite only: on one rank it would compare a run with itself)."""

import xfem_contact  # noqa: F401

# isort: split
import pytest
from mpi4py import MPI
from parallel import gathered_fields, max_relative_difference

from xfem_contact.cases.paper import annulus_problem, inclusion_problem

pytestmark = [pytest.mark.mpi, pytest.mark.parallel]

CASES = {
    "case2 P2 quadrilaterals, sticking": lambda comm: inclusion_problem(
        10, 2, "sticking", comm=comm
    ),
    "case2 P1 triangles, sticking": lambda comm: inclusion_problem(
        10, 1, "sticking", "triangle", comm=comm
    ),
    "case2 P2, Coulomb stick-slip": lambda comm: inclusion_problem(
        10, 2, "coulomb", loading="pull", friction=0.3, comm=comm
    ),
    "case2 P2, bonded (one linear solve)": lambda comm: inclusion_problem(
        10, 2, "bonded", comm=comm
    ),
    "case3 annulus P2, curved cells": lambda comm: annulus_problem(6, 24, 2, comm=comm),
    "case3 annulus P1": lambda comm: annulus_problem(6, 24, 1, comm=comm),
}


#: Relative tolerance per case. On the curved-cell annulus the fields differ by 5e-9
#: between 1 and 2 ranks (P1 on straight cells: 2.5e-10), and that is not the solver:
#: its factored matrix has condition 2.1e4 there and other orderings or factorisations
#: move the fields by 1e-13; the sides, cut rules and cell areas agree to 1e-15. The
#: source is not found yet (see the issue note); case 2 meshes meet 1e-10.
TOLERANCE = {case: 2e-8 if case.startswith("case3") else 1e-10 for case in CASES}


@pytest.mark.parametrize("case", list(CASES))
def test_fields_equal_serial(case):
    fields = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        problem = CASES[case](comm)
        problem.solve()
        fields.append(gathered_fields(problem))
    differences = max_relative_difference(*fields)
    if MPI.COMM_WORLD.rank == 0:
        print(case, {k: f"{v:.1e}" for k, v in differences.items()})
    assert all(v <= TOLERANCE[case] for v in differences.values()), differences
