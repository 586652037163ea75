"""Large sliding: closest-point pairing, the hybrid element's Jacobian, objectivity and
paper case 3 with rotation (against the exact pressure of the same bulk model)."""

import xfem_contact  # noqa: F401

# isort: split
import dolfinx.fem
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from xfem_contact.cases.paper import ANNULUS_CONTACT_PRESSURE, ANNULUS_RADII, annulus_problem
from xfem_contact.cases.rotation import (
    pressure_errors,
    rotating_annulus_problem,
    svk_annulus_pressure,
)
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.geometry.cut_topology import seg3_basis
from xfem_contact.io.meshes import annulus
from xfem_contact.mechanics.laws import make_law
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem
from xfem_contact.mechanics.sliding import element
from xfem_contact.mechanics.sliding.lips import CurvePoint
from xfem_contact.mechanics.sliding.projection import closest_points
from xfem_contact.mechanics.sliding.segments import break_pieces
from xfem_contact.solvers.newton import NewtonFailure, ReducedNewton
from xfem_contact.solvers.options import preset


class ArcLip:
    """A lip of SEG3 pieces whose nodes lie on a circle of radius R (physical nodes,
    identity map): the projection sees the same interface as a MasterLip's."""

    def __init__(self, R, angles):
        a, b = angles[:-1], angles[1:]
        c = 0.5 * (a + b)
        self.nodes = R * np.stack(
            [np.c_[np.cos(t), np.sin(t)] for t in (a, b, c)], axis=1
        )  # (P, 3, 2): a, b, mid
        self.size = self.nodes.shape[0]

    def curve(self, pieces, s):
        N, dN = seg3_basis(s)
        nodes = self.nodes[pieces]
        x = np.einsum("mk,mkd->md", N, nodes)
        t = np.einsum("mk,mkd->md", dN, nodes)
        t2 = np.einsum("k,mkd->md", np.array([4.0, 4.0, -8.0]), nodes)
        return CurvePoint(x, t, t2, N, dN)


@pytest.fixture
def circle():
    return ArcLip(2.0, np.linspace(0.0, 2 * np.pi, 13))


def test_points_on_curved_pieces_are_their_own_feet(circle):
    rng = np.random.default_rng(0)
    pieces = rng.integers(0, circle.size, 50)
    s = rng.uniform(0.0, 1.0, 50)
    x = circle.curve(pieces, s).x
    pairing = closest_points(circle, x, radius=0.5)
    assert np.all(pairing.paired)
    assert np.abs(pairing.distance).max() < 1e-12
    feet = circle.curve(pairing.piece, pairing.s).x
    assert np.abs(feet - x).max() < 1e-12


def test_points_off_the_curve_project_along_its_normal(circle):
    rng = np.random.default_rng(1)
    pieces = rng.integers(0, circle.size, 40)
    s = rng.uniform(0.05, 0.95, 40)
    c = circle.curve(pieces, s)
    n = np.c_[c.t[:, 1], -c.t[:, 0]] / np.linalg.norm(c.t, axis=1)[:, None]
    offset = rng.uniform(-0.1, 0.1, 40)
    pairing = closest_points(circle, c.x + offset[:, None] * n, radius=0.5)
    assert np.array_equal(pairing.piece, pieces)
    assert np.abs(pairing.s - s).max() < 1e-10
    assert np.abs(pairing.distance - np.abs(offset)).max() < 1e-12


def test_beyond_the_piece_ends_the_foot_is_the_end():
    lip = ArcLip(2.0, np.linspace(0.0, np.pi / 2, 4))  # an open quarter circle
    end = lip.curve(np.array([2]), np.array([1.0]))
    tangent = end.t[0] / np.linalg.norm(end.t[0])
    # nearly tangent: a point along the tangent line past the end, slightly outside
    x = end.x + 0.05 * tangent + 1e-6 * np.array([[-tangent[1], tangent[0]]])
    pairing = closest_points(lip, x, radius=0.5)
    assert pairing.piece[0] == 2 and pairing.s[0] == 1.0
    assert abs(pairing.distance[0] - np.linalg.norm(x - end.x)) < 1e-14
    far = closest_points(lip, end.x + 0.6 * tangent, radius=0.5)
    assert far.piece[0] == -1 and far.distance[0] > 0.5


def test_no_master_found_is_reported_not_raised(circle):
    x = np.array([[10.0, 0.0], [0.0, -7.5]])
    pairing = closest_points(circle, x, radius=0.5)
    assert np.all(pairing.piece == -1)
    assert np.all(pairing.distance > 5.0)
    empty = ArcLip(2.0, np.array([0.0]))
    assert np.all(closest_points(empty, x, radius=0.5).piece == -1)


def test_master_lip_is_the_interface_of_the_cut():
    """With no displacement, every slave point of case 3 lies on the master lip
    (distance at round-off, gap zero)."""
    problem = rotating_annulus_problem(5, 2, 0.0)
    coupling = next(iter(problem.couplings.values()))
    coupling.bind(np.arange(problem.w.x.array.size), [])
    pairing, terms = coupling.evaluate(problem.w)
    assert np.all(pairing.paired)
    assert np.abs(pairing.distance).max() < 1e-12
    r = np.hypot(*coupling.x_ref.T)  # on the circle up to the SEG3 interpolation (h^3)
    assert np.abs(r - ANNULUS_RADII[1]).max() < 2e-4


def _perturbed_state(problem, alpha, rng):
    """The inner ring turned by alpha, both rings compressed a little, random noise,
    multipliers in compression; Dirichlet dofs at their values."""
    for f, a in ((0, alpha), (1, 0.0)):
        V, dofs = problem.space.field_space(f)
        X = V.tabulate_dof_coordinates()[:, :2]
        Q = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
        u = X @ (Q - np.eye(2)).T - 0.004 * X + 1e-3 * rng.standard_normal(X.shape)
        problem.w.x.array[dofs] = u.ravel()
    _, dofs = problem.space.field_space(2)
    problem.w.x.array[dofs] = -1e6 * (1 + 0.1 * rng.standard_normal(len(dofs)))
    for bc in problem.loads.bcs:
        bc.set(problem.w.x.array)


def _jacobian_error(problem, eps, seed=0):
    """|FD - J dy| / |J dy| of the reduced (scaled) residual along a random
    direction relative to each unknown."""
    rng = np.random.default_rng(seed)
    _perturbed_state(problem, 0.3, rng)
    newton = ReducedNewton(
        problem.residual(problem.w),
        problem.w,
        problem.loads.bcs,
        problem.prolongation(),
        couplings=list(problem.couplings.values()),
    )
    newton._start_from_w()
    y, J = newton.y.copy(), newton.J_r
    F = newton.F_r.duplicate()
    newton._residual(None, y, F)
    newton._jacobian(None, y, J, J)
    dy = y.duplicate()
    dy.setArray(rng.standard_normal(dy.getLocalSize()) * np.abs(y.getArray()))
    Jdy = y.duplicate()
    J.mult(dy, Jdy)

    def at(s):
        ys = y.copy()
        ys.axpy(s, dy)
        newton._residual(None, ys, F)
        return F.getArray().copy()

    fd = (at(eps) - at(-eps)) / (2 * eps)
    comm = problem.mesh.comm
    num = comm.allreduce(float(np.sum((fd - Jdy.getArray()) ** 2)), op=MPI.SUM)
    den = comm.allreduce(float(np.sum(Jdy.getArray() ** 2)), op=MPI.SUM)
    state = problem.interface_state(problem.w)
    contact = comm.allreduce(int(np.sum(state["P_n"] < 0)), op=MPI.SUM)
    newton.destroy()
    return np.sqrt(num / den), contact


@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("lbb", ["stabilized", "none"])
def test_jacobian_matches_central_differences(degree, lbb):
    """All linearisation terms kept: the foot's and the master normal's variations
    (the inner ring turned by 0.3 rad: slave and master cells differ)."""
    problem = rotating_annulus_problem(5, degree, 0.3, lbb=lbb)
    error, contact = _jacobian_error(problem, 1e-5)
    assert contact > 0
    assert error < 1e-6, error


def test_central_differences_catch_a_missing_curvature_term(monkeypatch):
    """The check fails when the gap's Hessian (the foot and normal variations) is
    dropped: what the Jacobian test guards."""
    gap_derivatives = element.gap_derivatives

    def without_hessian(*args):
        g, grad, H = gap_derivatives(*args)
        return g, grad, H.scaled(0.0)

    monkeypatch.setattr(element, "gap_derivatives", without_hessian)
    problem = rotating_annulus_problem(5, 2, 0.3, lbb="none")
    error, _ = _jacobian_error(problem, 1e-5)
    assert error > 1e-4, error


def test_svk_reference_tends_to_lame_for_small_strains():
    """The radial ODE of the Saint Venant-Kirchhoff ring against the exact Lame
    pressure when the strains vanish (E 1e6 times stiffer)."""
    p = svk_annulus_pressure(E=1e12)
    assert abs(p / ANNULUS_CONTACT_PRESSURE - 1.0) < 1e-6
    # and the model error at the paper's strains (~1 %) is of the order of the strain
    assert 1e-4 < abs(svk_annulus_pressure() / ANNULUS_CONTACT_PRESSURE - 1.0) < 2e-2


def test_rigid_rotation_by_a_right_angle_carries_no_stress():
    """Patch test: both boundaries of the annulus turned by pi/2, no load: the
    solution is the rotation, with zero stress and zero multipliers."""
    r_in, r_gamma, r_out = ANNULUS_RADII
    mesh = annulus(MPI.COMM_WORLD, r_in, r_out, 5, 20, 2)
    cut = CutMesh(mesh, lambda x: np.hypot(x[0], x[1]) - r_gamma, degree=2)
    material = Material(100e6, 0.3)
    problem = Problem(cut, 2, material, make_law("frictionless"), kinematics="large")
    tol = 1e-6 * r_out
    for r in (r_in, r_out):
        problem.loads.add_rotation(
            lambda x, r=r: np.abs(np.hypot(x[0], x[1]) - r) < tol, angle=np.pi / 2
        )
    for t in (0.5, 1.0):
        problem.loads.set_time(t)
        # no load: the rotation's residual is round-off (4e-9), not to be reduced 1e10 times
        problem.petsc_options = {"snes_atol": 1e-7}
        problem.solve()
        problem.accept_step()
    lam = problem.interface_state(problem.w)["lambda_n"]
    scale = 1e6  # the load scale of case 3 (Pa)
    assert np.abs(lam).max(initial=0.0) < 1e-10 * scale
    u = problem.space.field(problem.w, 0)
    stress = sum(
        ufl.inner(
            material.piola(problem.space.field(problem.w, i)),
            material.piola(problem.space.field(problem.w, i)),
        )
        * cut.dx(s)
        for i, s in ((0, -1), (1, 1))
    )
    area = np.pi * (r_out**2 - r_in**2)
    energy = MPI.COMM_WORLD.allreduce(dolfinx.fem.assemble_scalar(form(stress)), op=MPI.SUM)
    assert np.sqrt(energy / area) < 1e-10 * scale
    X = u.function_space.tabulate_dof_coordinates()[:, :2]
    rotated = np.c_[-X[:, 1], X[:, 0]] - X
    inside = np.hypot(*X.T) < r_gamma - 2.0  # nodes of side -1's own cells
    assert np.abs(u.x.array.reshape(-1, 2)[inside] - rotated[inside]).max() < 1e-10 * r_gamma


def _solve(problem, steps):
    reports = []
    for k in range(1, steps + 1):
        problem.loads.set_time(k / steps)
        reports.append(problem.solve())
        problem.accept_step()
    return reports


@pytest.mark.parametrize("degree, bound", [(2, 2e-3), (1, 1e-2)])
def test_case3_turned_by_a_quarter_of_pi(degree, bound):
    problem = rotating_annulus_problem(10, degree, np.pi / 4)
    reports = _solve(problem, 2)
    assert all(r.iterations <= 10 for r in reports)
    errors = pressure_errors(problem)
    assert errors["error"] < bound, errors
    counts = problem.pairing_counts()["interface"]
    assert counts["unpaired"] == 0 and counts["changed"] > 0


@pytest.fixture(scope="module")
def unturned_pressures():
    """lambda_n of case 3 (n = 10, P2) not turned, one step: the objectivity tests'
    reference, solved once."""
    still = rotating_annulus_problem(10, 2, 0.0)
    _solve(still, 1)
    return np.array(still.interface_state(still.w)["lambda_n"])


def test_objectivity_a_right_angle_gives_the_unturned_pressures(unturned_pressures):
    turned = rotating_annulus_problem(10, 2, np.pi / 2)
    _solve(turned, 4)
    a, b = turned.interface_state(turned.w)["lambda_n"], unturned_pressures
    assert np.abs(a - b).max() < 1e-8 * abs(ANNULUS_CONTACT_PRESSURE)


@pytest.mark.parametrize(
    "build, message",
    [
        (lambda: rotating_annulus_problem(4, 2, 0.1, law="sticking"), "not available in large"),
        (lambda: rotating_annulus_problem(4, 2, 0.1, lbb="restriction"), "lbb 'restriction'"),
        (lambda: rotating_annulus_problem(4, 2, 0.1, slave=0), "slave must be"),
        (lambda: rotating_annulus_problem(4, 2, 0.1, pairing="sometimes"), "pairing must be"),
        (lambda: rotating_annulus_problem(4, 2, 0.1, outer="glue"), "outer support"),
        (
            lambda: rotating_annulus_problem(4, 2, 0.1, stabilization_length="cut"),
            "stabilization_length 'cut' is not available in large sliding",
        ),
    ],
)
def test_bad_input_is_one_clear_error(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_rotation_of_a_missing_part_is_an_error():
    problem = rotating_annulus_problem(4, 2, 0.0)
    with pytest.raises(ValueError, match="holds no boundary facet"):
        problem.loads.add_rotation(lambda x: np.hypot(x[0], x[1]) > 100.0, angle=0.5)


def test_unknown_kinematics_names_the_valid_ones():
    mesh = annulus(MPI.COMM_WORLD, 3.0, 20.0, 3, 12, 2)
    cut = CutMesh(mesh, lambda x: np.hypot(x[0], x[1]) - 8.0, degree=2)
    with pytest.raises(ValueError, match=r"valid: \('small', 'large'\)"):
        Problem(cut, 2, Material(1e8, 0.0), "frictionless", kinematics="huge")


@pytest.mark.mpi
@pytest.mark.parallel
def test_masters_on_the_other_process_are_paired():
    """On 2 ranks some slave points pair with a master piece the other rank owns
    (the field equality against one rank is in test_parallel)."""
    comm = MPI.COMM_WORLD
    if comm.size < 2:
        pytest.skip("needs 2 processes")
    problem = rotating_annulus_problem(6, 2, 0.3)
    _solve(problem, 1)
    coupling = next(iter(problem.couplings.values()))
    pairing, _ = coupling.evaluate(problem.w)
    remote = pairing.paired & (coupling.lip.owners[np.maximum(pairing.piece, 0)] != comm.rank)
    assert comm.allreduce(int(remote.sum()), op=MPI.SUM) > 0


def test_complex_step_element_equals_the_analytic_frictionless_one():
    """Two derivations of the frictionless hybrid element (the analytic Jacobian with
    the foot and normal variations, and the complex-step derivative of the residual
    the Coulomb element uses) agree to round-off."""
    problem = rotating_annulus_problem(5, 2, 0.3, lbb="none")
    _perturbed_state(problem, 0.3, np.random.default_rng(2))
    coupling = problem.couplings["interface"]
    coupling.bind(np.arange(problem.w.x.array.size), [])
    _, analytic = coupling.evaluate(problem.w)
    coupling.complex_step, coupling._evaluated = True, None
    _, stepped = coupling.evaluate(problem.w)
    scale = np.abs(analytic.jacobian).max()
    assert np.abs(stepped.jacobian - analytic.jacobian).max() < 1e-12 * scale
    assert (
        np.abs(stepped.residual - analytic.residual).max() < 1e-12 * np.abs(analytic.residual).max()
    )


@pytest.mark.parametrize("friction, status", [(0.3, "slip"), (1e3, "stick")])
def test_coulomb_jacobian_matches_central_differences(friction, status):
    problem = rotating_annulus_problem(5, 2, 0.3, law="coulomb", friction=friction)
    error, contact = _jacobian_error(problem, 1e-5)
    counts = problem.interface_status(problem.w)
    assert contact > 0 and counts[status] == counts["contact"]
    assert error < 1e-6, error


def test_coulomb_in_large_sliding_slides_on_the_cone():
    """Case 3 with friction 0.3, the outer ring held tangentially: the whole interface
    slides, the applied tangential traction is on the cone (|P_t| = 0.3 |P_n|) and,
    by the rotational symmetry, uniform; it opposes the slip increment."""
    problem = rotating_annulus_problem(
        8, 2, 0.3, law="coulomb", friction=0.3, outer="tangential_spring"
    )
    reports = _solve(problem, 2)
    assert all(r.iterations <= 10 for r in reports)
    state = problem.interface_state(problem.w)
    counts = problem.interface_status(problem.w)
    assert counts["slip"] == counts["contact"] > 0
    P_n, P_t = state["P_n"], state["P_t"]
    assert np.abs(np.abs(P_t) - 0.3 * np.abs(P_n)).max() < 1e-9 * np.abs(P_n).max()
    assert np.ptp(state["lambda_t"]) < 1e-8 * np.abs(state["lambda_t"]).max()
    assert np.all(P_t * state["slip_increment"] > 0)


def test_a_failing_step_reports_its_history_and_keeps_the_accepted_state():
    """A half turn in one step with two Newton iterations allowed: the failure
    carries the history, ``w`` is the accepted state (not the diverged iterate,
    not the rigidly turned predictor) and the next, smaller step succeeds."""
    problem = rotating_annulus_problem(5, 2, np.pi)
    problem.loads.set_time(0.25)
    problem.solve()
    problem.accept_step()
    accepted = problem.w.x.array.copy()
    problem.loads.set_time(1.0)
    with pytest.raises(NewtonFailure, match="iterate  1") as failure:
        problem.petsc_options = {"snes_max_it": 1}
        problem.solve()
    assert failure.value.report.iterations == 1
    assert np.array_equal(problem.w.x.array, accepted)
    problem.petsc_options = {}
    problem.loads.set_time(0.5)
    assert problem.solve().iterations <= 10


def test_segments_keep_every_gauss_rule_on_one_master_piece():
    """The inner ring turned rigidly by 1 rad (not a multiple of the cell angle): each
    sub-segment's Gauss points have their closest points on the sub-segment's own
    master piece, never across a piece end (where the master field has a kink); the
    sub-segments tile every slave piece. The interface rule's own points do not."""
    problem = rotating_annulus_problem(5, 2, 1.0)
    coupling = problem.couplings["interface"]
    coupling.bind(np.arange(problem.w.x.array.size), [])
    problem.loads.set_time(1.0)
    problem.loads.rotate_bodies(problem.w, 0.0, 1.0)
    values, lip, pieces = problem.w.x.array, coupling.lip, coupling.pieces
    lip.refresh(problem.w)
    whole = pieces.whole()

    def spread(segments):
        """Per sub-segment: do the closest points of its Gauss points lie on more
        than one master piece?"""
        segment, t, _ = pieces.parameters(segments)
        _, _, weights = pieces.rule(segments)
        x, _ = pieces.curve(values, segments.piece[segment], t)
        feet = closest_points(lip, x, coupling.radius)
        assert np.all(feet.paired)
        first = np.full(segments.piece.size, -1)
        first[segment[::-1]] = feet.piece[::-1]
        return np.any(feet.piece != first[segment]), weights.sum()

    segments = break_pieces(pieces, values, lip, coupling.radius)
    assert segments.piece.size > whole.piece.size
    assert np.all(segments.master >= 0)
    across, length = spread(segments)
    assert not across
    # the same total length, up to the rules' error on the arc length (not polynomial)
    assert abs(length - spread(whole)[1]) < 1e-9 * length
    assert spread(whole)[0]  # the unbroken rule crosses master kinks


@pytest.mark.parametrize("segments", [True, False])
def test_a_turn_by_one_radian_gives_the_unturned_pressures(unturned_pressures, segments):
    """Objectivity at an angle that does not map the mesh onto itself (1 rad, 4
    steps): with segment-to-segment integration the P2 pressures equal the unturned
    ones (the oscillation is that of round-off and quadrature); the interface rule
    integrating across master kinks oscillates by 3e-4 (the test's negative)."""
    turned = rotating_annulus_problem(10, 2, 1.0, segments=segments)
    reports = _solve(turned, 4)
    assert all(r.iterations <= 6 for r in reports)
    a, b = turned.interface_state(turned.w)["lambda_n"], unturned_pressures
    difference = np.abs(a - b).max() / abs(ANNULUS_CONTACT_PRESSURE)
    if segments:
        assert difference < 1e-8, difference
        assert pressure_errors(turned)["oscillation"] < 1e-8
    else:
        assert difference > 1e-5, difference


def test_newton_reuses_a_factorisation_and_takes_the_exact_steps(monkeypatch):
    """Large sliding's default Newton steps: GMRES on the LU of the solve's first
    iterate. The same residual history and solution as an LU at every iterate (preonly),
    more than one Krylov iteration after the first iterate of a step (the factorisation
    reused), and one everywhere when GMRES may take none before refactoring."""
    runs = {}
    for name, options in (("exact", {"ksp_type": "preonly"}), ("reused", None)):
        problem = rotating_annulus_problem(6, 2, 1.0)
        assert (problem.solver_options(options)["ksp_type"] == "gmres") == (options is None)
        problem.petsc_options = options
        reports = []
        for k in (1, 2):
            problem.loads.set_time(k / 2)
            reports.append(problem.solve())
            problem.accept_step()
        runs[name] = (reports, problem.w.x.array.copy())
    (exact, w_exact), (reused, w_reused) = runs["exact"], runs["reused"]
    assert np.abs(w_reused - w_exact).max() < 1e-9 * np.abs(w_exact).max()
    for a, b in zip(exact, reused, strict=True):
        assert a.iterations == b.iterations
        assert np.allclose(a.residuals[:-1], b.residuals[:-1], rtol=1e-6)
        assert b.linear_iterations[0] == 1 and max(b.linear_iterations[1:]) > 1
    monkeypatch.setattr("xfem_contact.solvers.newton.REFACTOR_AFTER", 0)
    problem = rotating_annulus_problem(6, 2, 1.0)
    problem.loads.set_time(0.5)
    assert set(problem.solve().linear_iterations) == {1}


def test_the_reused_lu_only_where_no_linear_solver_is_chosen():
    """Options given are kept as given; small sliding factors at every iterate."""
    problem = rotating_annulus_problem(4, 2, 0.0)
    assert problem.solver_options({"ksp_type": "preonly"})["ksp_type"] == "preonly"
    assert problem.solver_options(preset("iterative"))["pc_type"] == "python"
    assert annulus_problem(4, 16, 2, 2).solver_options()["ksp_type"] == "preonly"


def test_a_reused_factorisation_that_fails_is_refactored_not_fatal():
    """GMRES allowed 3 iterations where a reused LU needs about 5: the linear solve
    fails at the second iterate, Newton goes on, the next iterate refactors and the
    step converges to the solution of LU at every iterate."""
    solutions = []
    for options in ({"ksp_type": "preonly"}, {**preset("reused_lu"), "ksp_max_it": 3}):
        problem = rotating_annulus_problem(6, 2, 1.0)
        problem.loads.set_time(0.5)
        problem.petsc_options = options
        report = problem.solve()
        solutions.append(problem.w.x.array.copy())
    assert max(report.linear_iterations) == 3 and report.linear_iterations.count(1) >= 2
    assert np.abs(solutions[1] - solutions[0]).max() < 1e-9 * np.abs(solutions[0]).max()


@pytest.mark.parametrize("touch", [None, 0.0])
def test_aligned_pieces_keep_the_pattern_and_the_factorisation(monkeypatch, touch):
    """Turned by whole cells at every step (n = 20: 4.5 degree cells, steps of 22.5
    degrees) slave nodes sit over master nodes: crossings within round-off of a
    slave-piece end are not breakpoints, so the Jacobian's pattern grows only where
    a step brings new pairs and the factorisation is reused within the steps. Broken at
    such crossings (``TOUCH = 0``, the negative), slivers paired with either
    neighbour in turn grow the pattern at every iterate and each refactors."""
    if touch is not None:
        monkeypatch.setattr("xfem_contact.mechanics.sliding.segments.TOUCH", touch)
    problem = rotating_annulus_problem(20, 2, np.pi / 4)
    reports = _solve(problem, 2)
    reused = max(reports[-1].linear_iterations[1:]) > 1
    assert reused == (touch is None), reports[-1].linear_iterations
    assert pressure_errors(problem)["oscillation"] < 1e-8
