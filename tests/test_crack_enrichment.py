"""Cracks in the enriched space against exact solutions (xfem_contact.cases.cracks).

The Williams near-tip field (mixed mode, a crack from the boundary to a tip near the
centre of [-1, 1]^2), the Griffith crack (two tips, Westergaard's displacement on the
boundary) and the closed inclined crack with Coulomb friction on its lips. Small
meshes here; the convergence studies are in bench/crack_*.py. Each check fails with
what it guards switched off: the branch functions (topological instead of geometric
enrichment: energy error x3), the ties of the tip nodes (a spurious discontinuity
ahead of the tip), the lip term of the interaction integral (K_I/K_II = 0.97 without).
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from xfem_contact.cases.cracks import (
    frictional_crack_case,
    frictional_slip,
    griffith_case,
    williams_case,
    williams_energy_error,
)
from xfem_contact.fem.forms import form
from xfem_contact.geometry.crack import CROSSED, TIP
from xfem_contact.mechanics.fracture import (
    InteractionIntegral,
    Piece,
    TipIntegrals,
)
from xfem_contact.mechanics.fracture.tips import lip_tractions
from xfem_contact.solvers.linear import assemble_reduced
from xfem_contact.solvers.scaling import saddle_point_scaling


def total(expr) -> float:
    return MPI.COMM_WORLD.allreduce(dolfinx.fem.assemble_scalar(form(expr)), op=MPI.SUM)


def test_crack_cut_is_exact_for_a_straight_crack():
    case = griffith_case(4, 2, tip_radius=0.5)
    cut = case.problem.cut
    # lips of length 2a, both sides fill the square of half width 2
    assert total(1 * cut.dGamma) == pytest.approx(2.0, abs=1e-12)
    area = total(1 * cut.dx(-1)) + total(1 * cut.dx(1))
    assert area == pytest.approx(16.0, abs=1e-11)
    d = np.array([math.cos(0.3), math.sin(0.3)])
    centre = np.array([0.0123, 0.0271])
    expected = np.array(sorted([tuple(centre + d), tuple(centre - d)]))
    tips = np.array(sorted(map(tuple, cut.crack.tips)))
    assert np.abs(tips - expected).max() < 1e-13
    for tip, direction in zip(cut.crack.tips, cut.crack.directions, strict=True):
        assert direction == pytest.approx((tip - centre) / np.linalg.norm(tip - centre))
    assert sorted(cut.crack.upper_sides.tolist()) == [-1, 1]  # opposite frames
    # the r^-1/2 singularity of the lips' tractions is integrated exactly
    x = ufl.SpatialCoordinate(cut.mesh)
    for tip in cut.crack.tips:
        r = ufl.sqrt((x[0] - tip[0]) ** 2 + (x[1] - tip[1]) ** 2)
        assert total(r**-0.5 * cut.dGamma) == pytest.approx(2 * math.sqrt(2), rel=1e-10)
    kinds = MPI.COMM_WORLD.allreduce(np.bincount(cut.crack.kind, minlength=3), op=MPI.SUM)
    assert kinds[TIP] == 2 and kinds[CROSSED] > 0


def test_ties_and_dof_counts():
    case = williams_case(16, 1)
    space = case.problem.space
    counts = space.dof_counts()
    ties = MPI.COMM_WORLD.allreduce(len(space.ties), op=MPI.SUM)
    assert ties > 0
    # every tied pair is one unknown: the reduced system has standard + enriched dofs
    R = case.problem.prolongation()
    assert R.getSize()[1] == counts.total
    R.destroy()


@pytest.mark.parametrize("enrichment", ["geometric", "topological"])
def test_williams_field_p2(enrichment):
    case = williams_case(16, 2, tip_radius=0.3 if enrichment == "geometric" else None)
    case.problem.solve()
    error = williams_energy_error(case)
    if enrichment == "topological":  # the tip cells' nodes only: the error stays large
        assert error > 2.5e-2  # 3.5e-2, three times the geometric enrichment's
        return
    assert error < 1.2e-2  # 1.07e-2 measured; 4e-2 with the cut cells' default degree 6
    integrals = TipIntegrals(case.problem, [(0.2, 0.6)])
    (ring,) = integrals.evaluate()[0]
    assert ring.K_I == pytest.approx(1.0, abs=1.5e-4)
    assert ring.K_II == pytest.approx(0.5, abs=1.5e-4)
    assert ring.J == pytest.approx(ring.G, rel=2e-4)
    # each side owns its moduli: one side changed, K (one material) is refused
    case.problem.materials[-1].E = 2.0 * case.problem.materials[1].E
    with pytest.raises(ValueError, match="one material around the tips"):
        integrals.evaluate()


@pytest.mark.serial
def test_ramp_leaves_no_null_vector():
    """The ramp makes the P1 partition complete around the tip, where the branch functions
    times linear functions are dependent (4 null vectors of the stiffness); dropping F_1
    and F_2 at one node removes them (smallest eigenvalue of the Jacobi-scaled reduced
    stiffness 5.5e-16 of the largest with all dofs)."""
    problem = williams_case(8, 1, tip_radius=0.4).problem
    R = problem.prolongation()
    a, L = form(problem.bilinear_form()), form(problem.loads.linear_form())
    A, b = assemble_reduced(a, L, problem.loads.bcs, R)
    D = saddle_point_scaling(A)
    A.diagonalScale(D, D)
    eigenvalues = np.abs(np.linalg.eigvalsh(A.convert("dense").getDenseArray()))
    assert eigenvalues.min() > 1e-9 * eigenvalues.max()


def test_williams_field_p1_converges():
    errors = []
    for n in (16, 32):
        case = williams_case(n, 1)
        case.problem.solve()
        errors.append(williams_energy_error(case))
    rate = math.log(errors[0] / errors[1]) / math.log(2)
    # with the ramp (corrected X-FEM): 0.086, 0.049 (rate 0.81), 0.027 at n = 64 (0.88);
    # without: 0.103, 0.056 (0.89), 0.029 (0.97): lower everywhere, most on coarse meshes
    assert rate > 0.78, errors
    assert errors[1] < 0.052, errors


def test_griffith_crack_both_tips():
    case = griffith_case(4, 2, tip_radius=0.5)
    case.problem.solve()
    results = TipIntegrals(case.problem, [(0.4, 0.8), (0.5, 0.95)]).evaluate()
    (K_I, K_II) = case.K[0]
    for rings in results:
        for ring in rings:
            assert ring.K_I == pytest.approx(K_I, rel=3e-4)  # 1.4e-4 at worst
            assert abs(ring.K_II) < 3e-4 * K_I
            assert ring.J == pytest.approx(ring.G, rel=1e-3)


@pytest.fixture(scope="module")
def frictional():
    """The closed crack with friction 0.3, solved, and its Newton report."""
    case = frictional_crack_case(8, 2, friction=0.3, tip_radius=0.3)
    return case, case.problem.solve()


def test_closed_crack_with_coulomb_friction(frictional):
    case, report = frictional
    assert report.converged
    samples = case.problem.interface_samples(case.problem.w)
    centre, d = np.array([0.0123, 0.0271]), np.array([math.cos(0.3), math.sin(0.3)])
    s = (np.asarray(samples["x"]) - centre[0]) * d[0] + (np.asarray(samples["y"]) - centre[1]) * d[
        1
    ]
    slip, sigma_n = frictional_slip(s, friction=0.3)
    # the lips stick together in the normal direction, slide under friction
    # to 2 % (0.85 % at worst, near a tip; 9.7 % without the branch functions' ramp)
    assert np.asarray(samples["lambda_n"]) == pytest.approx(sigma_n, abs=2e-2 * abs(sigma_n))
    assert np.abs(samples["gap"]).max() < 1e-3 * np.abs(slip).max()
    # the law's tangent is -d: its slip is minus the slip along the crack
    assert -np.asarray(samples["slip"]) == pytest.approx(slip, abs=5e-3 * np.abs(slip).max())
    K_I, K_II = case.K[0]
    results = TipIntegrals(case.problem, [(0.4, 0.8)]).evaluate()
    for (ring,) in results:
        assert ring.K_II == pytest.approx(K_II, rel=1e-3)
        assert abs(ring.K_I) < 3e-3 * abs(K_II)


def test_lip_term_carries_the_friction(frictional):
    """Without the lips' tractions the interaction integral reads K_I ~ K_II."""
    case, _ = frictional
    problem = case.problem
    cut, u = problem.cut, problem.space.split(problem.w)
    pieces = [Piece(u[0], cut.dx(-1)), Piece(u[1], cut.dx(1))]
    K_II = case.K[0][1]
    for tip, direction, upper in zip(
        cut.crack.tips, cut.crack.directions, cut.crack.upper_sides, strict=True
    ):
        material = problem.bulk.materials[1]
        for lips, small in (([], False), (lip_tractions(problem, upper), True)):
            integral = InteractionIntegral(pieces, material, tip, direction, [(0.4, 0.8)], lips)
            (ring,) = integral.evaluate()
            assert (abs(ring.K_I) < 1e-2 * abs(K_II)) == small


@pytest.mark.mpi
@pytest.mark.parallel
@pytest.mark.parametrize(
    "build, options",
    [
        (griffith_case, {}),
        (frictional_crack_case, {}),
        (frictional_crack_case, {"lbb": "restriction"}),
    ],
    ids=["griffith", "friction", "friction, LBB restriction"],
)
def test_cracks_equal_serial(build, options):
    """K of every tip and the lips' fields are the same on all ranks as on one (the
    restriction's vital vertices chosen by position, not by partition-dependent number:
    2e-3 apart before)."""
    from parallel import gathered_fields, max_relative_difference

    runs = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        case = build(4, 2, tip_radius=0.5, comm=comm, **options)
        case.problem.solve()
        results = TipIntegrals(case.problem, [(0.4, 0.8)]).evaluate()
        K = np.array([[r.K_I, r.K_II] for (r,) in results])
        fields = gathered_fields(case.problem) if build is frictional_crack_case else None
        runs.append((K, fields))
    (K_all, fields_all), (K_one, fields_one) = runs
    assert np.abs(K_all - K_one).max() <= 1e-10 * np.abs(K_one).max()
    if fields_one is not None:
        differences = max_relative_difference(fields_all, fields_one)
        assert all(v <= 1e-10 for v in differences.values()), differences


def test_crack_without_tip_is_refused():
    from xfem_contact.fem.cutmesh import CutMesh

    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    with pytest.raises(ValueError, match="no tip in the body"):
        CutMesh(mesh, lambda x: x[1] - 0.51, degree=1, tangent=lambda x: -1.0 - x[0])
    with pytest.raises(ValueError, match="tip_radius must be a positive length"):
        williams_case(8, 1, tip_radius=-1.0)
