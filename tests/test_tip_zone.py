"""The tip zone (xfem_contact.fem.tip_zone): a cracked problem's uncut cells outside the
cells of the branch functions take the integrand's polynomial degree, those inside the
cut's; the stiffness is the one of every uncut cell at the cut's degree."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.fem.petsc

from xfem_contact.cases.cracks import williams_case
from xfem_contact.fem.forms import form
from xfem_contact.fem.tip_zone import TipZone, branch_cells


def _matrix(problem):
    A = dolfinx.fem.petsc.assemble_matrix(form(problem.bilinear_form()))
    A.assemble()
    return A


def _gap(A, B) -> float:
    C = A.copy()
    C.axpy(-1.0, B)
    return C.norm() / B.norm()


def test_tip_zone_keeps_the_stiffness():
    problem = williams_case(12, 2).problem
    zone = branch_cells(problem.space)
    assert 0 < zone.size < problem.cut.cell_sides.size  # some cells in, most out
    with_zone = _matrix(problem)
    bulk = problem.bulk
    saved, bulk.zone = bulk.zone, None  # every uncut cell at the cut's degree
    everywhere = _matrix(problem)
    assert _gap(with_zone, everywhere) < 1e-12
    # a zone that misses cells of the branch functions integrates them at degree 4
    bulk.zone = TipZone(problem.cut, lambda: zone[::2], saved.metadata)
    assert _gap(_matrix(problem), everywhere) > 1e-8
    bulk.zone = saved
