"""Contact on crack lips: the default LBB treatment (the vital-vertex restriction) and
quadrilateral meshes with the crack along a row of cells, on the closed crack with
Coulomb friction (exact K_I = 0 and K_II)."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import pytest

from xfem_contact.cases.cracks import frictional_crack_case
from xfem_contact.mechanics.fracture import TipIntegrals


def test_a_crack_law_by_name_takes_the_restriction():
    case = frictional_crack_case(4, 2, tip_radius=0.5)
    (law,) = case.problem.laws.values()
    assert law.lbb == "restriction"


@pytest.mark.mpi
@pytest.mark.parametrize(
    "N, degree, friction, tol, tol_I",
    [(4, 2, 0.0, 2e-5, 3e-3), (4, 2, 0.3, 1e-3, 3e-3), (8, 1, 0.0, 1e-3, 5e-3)],
    ids=["Q2 frictionless", "Q2 Coulomb", "Q1 frictionless"],
)
def test_quadrilaterals_with_the_crack_along_a_row_of_cells(N, degree, friction, tol, tol_I):
    """The crack 0.3 h above a mesh line: the multiplier's trace on a Q1 cell cut along a
    reference line is degenerate, and the restriction's vital vertices of the cells cut
    ahead of a tip acted on no lip (the reduced Jacobian singular: 'not symmetric' for the
    LDL^T, SNES -3 with LU; Newton diverged, SNES -9, without an LBB treatment). Newton
    converges at once (frictionless: the law is linear once closed; Coulomb: two
    iterates), through the symmetric factorisation where the law is symmetric, and K is
    the exact one (errors, tip by tip: Q2 frictionless K_II 4e-6, 1.2e-5, K_I 1.7e-5,
    1.8e-3 K_II; Coulomb K_II 1.2e-5, 6.3e-4; Q1 at h = a/8 K_II 2.5e-4, 1.6e-4)."""
    case = frictional_crack_case(
        N, degree, friction=friction, tip_radius=0.5, cell="quadrilateral", along_row=0.3
    )
    report = case.problem.solve()
    assert report.converged and report.iterations <= 2
    K_I, K_II = case.K[0]
    results = TipIntegrals(case.problem, [(0.4, 0.8)]).evaluate()
    for (ring,) in results:
        assert ring.K_II == pytest.approx(K_II, rel=tol)
        assert abs(ring.K_I) < tol_I * abs(K_II)


def test_without_lbb_treatment_the_aligned_cells_keep_their_normal_gradient_term():
    """On the cells cut along a reference line the multiplier has modes without trace:
    the normal-gradient term that fixes them holds with ``lbb="none"`` too (Newton
    diverged without it, SNES -9)."""
    case = frictional_crack_case(
        4, 2, friction=0.3, tip_radius=0.5, lbb="none", cell="quadrilateral", along_row=0.3
    )
    assert case.problem.solve().converged
