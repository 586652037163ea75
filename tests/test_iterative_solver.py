"""The iterative linear solver of the Newton steps gives the direct solver's answer.

GMRES with the band multigrid (``LINEAR_PRESETS["iterative"]``): the band and the
displacement fieldsplit cover what they should, the interpolation from the vertices is
exact on bilinear fields, the Krylov iterations are reported and do not grow with N,
and a scene selects the preset with ``[solver] preset``.
"""

import numpy as np
import pytest
from test_scenes import base

from xfem_contact.cases.paper import inclusion_errors, inclusion_problem
from xfem_contact.scenes.scene import SceneError, load_scene
from xfem_contact.solvers.assembly import aij
from xfem_contact.solvers.options import LINEAR_PRESETS, applied_options, preset


@pytest.mark.mpi
@pytest.mark.filterwarnings("ignore::xfem_contact.mechanics.rigid_modes.RigidModeWarning")
@pytest.mark.parametrize("law", ["sticking", "frictionless"])
def test_iterative_equals_direct(law):
    direct = inclusion_problem(10, 2, law)
    direct.solve()
    iterative = inclusion_problem(10, 2, law)
    iterative.petsc_options = preset("iterative")
    report = iterative.solve()
    assert report.iterations == direct.last_report.iterations
    assert all(k > 1 for k in report.linear_iterations)  # a Krylov method, not one LU
    assert direct.last_report.linear_iterations == [1] * direct.last_report.iterations
    scale = np.abs(direct.w.x.array).max()
    assert np.allclose(iterative.w.x.array, direct.w.x.array, rtol=0.0, atol=1e-8 * scale)
    e_direct = inclusion_errors(direct, direct.w).pressure
    assert inclusion_errors(iterative, iterative.w).pressure == pytest.approx(e_direct, rel=1e-6)


def _context(problem):
    return problem.newton.snes.getKSP().getPC().getPythonContext()


def test_band_and_interpolation():
    """The band holds every multiplier and lies in the cut region; the interpolation
    from the vertex unknowns reproduces a bilinear displacement exactly, in the
    scaled reduced unknowns the solver works with; the set-up keeps no copies it
    does not need (the band's rows once, no ``R^T R`` kept)."""
    problem = inclusion_problem(10, 2, "sticking")
    problem.petsc_options = preset("iterative")
    problem.solve()
    context, newton = _context(problem), problem.newton
    dofs = problem.space.dof_counts()
    assert context.u.getSize() + dofs.multiplier == newton.J_r.getSize()[0]
    assert dofs.multiplier < context.band.getSize() < context.u.getSize()
    w = problem.w.copy()
    for field in (0, 1):
        w.sub(field).interpolate(lambda x: np.vstack([1 + 2 * x[0] + 3 * x[0] * x[1], x[1]]))
    x = newton.jacobian.selection.columns
    owned = newton.R.getOwnershipRangeColumn()
    values = np.zeros(owned[1] - owned[0])
    n_owned = problem.space.W.dofmap.index_map.size_local * problem.space.W.dofmap.index_map_bs
    mine = (x[:n_owned] >= owned[0]) & (x[:n_owned] < owned[1])
    values[x[:n_owned][mine] - owned[0]] = w.x.array[:n_owned][mine]
    values /= newton.D.getArray(readonly=True)  # y = D^-1 x
    fine = values[context.u.getIndices() - owned[0]]
    coarse = context.P.createVecRight()
    coarse.setArray(fine[context.coarse_positions])
    interpolated = context.P.createVecLeft()
    context.P.mult(coarse, interpolated)
    assert np.allclose(interpolated.getArray(), fine, rtol=1e-12, atol=1e-12 * np.abs(fine).max())
    # what the set-up keeps (memory): one restriction, the scaled one; P a view of
    # P_full; no interpolation arrays once the prolongations are built
    assert newton.jacobian.R is None
    assert context.P.getType() == "submatrix" and context._interpolation is None
    # the blocks and the factorisation released after the Krylov solve, the modes once
    # restricted to the coarse unknowns; the Jacobian stored by node blocks (BAIJ)
    assert not context._built and context._modes == [] and len(context._coarse_modes) == 6
    assert newton.J_r.getType() == "seqbaij" and newton.J_r.getBlockSize() == 2
    pc = newton.snes.getKSP().getPC()
    with applied_options(newton._prefix, newton.options):  # as in a Newton step's set-up
        context.setUp(pc)  # extracted again
    assert context.B is None  # the multipliers' rows serve the set-up only
    # the band's block released once factored LDL^T (the factor keeps its own copy),
    # (J x)_b taken from J itself: no copy of the band's rows
    assert context.J_bb is None and context.ksp_band is None
    assert not hasattr(context, "J_bo")
    J, copied = aij(newton.J_r)  # BAIJ extracts whole blocks only
    J_bb = J.createSubMatrix(context.band, context.band)
    b = J_bb.createVecLeft()
    b.setRandom()
    x = J_bb.createVecRight()
    context._solve_band(b, x)
    check = J_bb.createVecLeft()
    J_bb.mult(x, check)
    assert np.allclose(check.getArray(), b.getArray(), rtol=0.0, atol=1e-8 * b.norm())
    assert copied
    for obj in (J, J_bb, b, x, check):
        obj.destroy()
    # the start of a solve from w keeps no R^T R nor its solver, and recovers y from w
    assert not hasattr(newton, "_projection")
    y = newton.y.copy()
    newton._start_from_w()
    assert np.allclose(newton.y.getArray(), y.getArray(), rtol=0.0, atol=1e-12 * y.norm())


@pytest.mark.parametrize("degree, bound", [(2, 20), (1, 18)])
def test_krylov_iterations_do_not_grow(degree, bound):
    """Case 2 at N = 10, 20, 40 and with a tiny cut: at most ``bound`` iterations
    (measured: 17, 17, 17 and 17 for degree 2, 10, 13, 15 and 15 for degree 1; without
    the band solve GMRES does not converge in 500)."""
    for n, radius in ((10, 0.25), (20, 0.25), (40, 0.25), (40, 0.25 + 1e-7 / 40)):
        problem = inclusion_problem(
            n, degree, "sticking", radius=radius, petsc_options=preset("iterative")
        )
        report = problem.solve()
        assert max(report.linear_iterations) <= bound, (n, radius)


def test_scene_selects_the_preset():
    scene = load_scene(base(law="sticking") | {"solver": {"preset": "iterative"}})
    assert scene.petsc_options["pc_type"] == "python"
    assert load_scene(base(law="sticking")).petsc_options.get("pc_type") is None
    with pytest.raises(SceneError, match=r"solver.preset.*direct"):
        load_scene(base(law="sticking") | {"solver": {"preset": "multigrid"}})
    with pytest.raises(ValueError, match="Unknown solver preset 'cg'"):
        preset("cg")
    assert set(LINEAR_PRESETS) == {"direct", "iterative"}


def test_large_sliding_iterative_equals_direct():
    """Case 3 turned by pi/2 in 2 steps: the couplings grow the Jacobian's pattern, and
    the preconditioner extracts its blocks afresh (``reset``)."""
    from xfem_contact.cases.rotation import rotating_annulus_problem
    from xfem_contact.mechanics.loads import load_steps

    solutions = []
    for solver in ("direct", "iterative"):
        problem = rotating_annulus_problem(6, 2, np.pi / 2)
        for t in load_steps(2):
            problem.loads.set_time(t)
            problem.petsc_options = preset(solver)
            report = problem.solve()
        # direct: a fresh LU at a solve's first iterate (1 Krylov iteration), reused after
        assert (report.linear_iterations[0] > 1) == (solver == "iterative")
        solutions.append(problem.w.x.array.copy())
    scale = np.abs(solutions[0]).max()
    assert np.allclose(solutions[1], solutions[0], rtol=0.0, atol=1e-9 * scale)


def test_a_bonded_interface_beside_a_contact_one():
    """Bonded (a pure multiplier: each side floats in the displacement block) next to
    Coulomb: the preconditioner's augmented block couples the sides (without it GMRES
    stalled at 1e-1 after 500 iterations); a linear problem is refused in one line."""
    import pathlib
    import tomllib

    import xfem_contact.scenes
    from xfem_contact.scenes.builder import build

    path = pathlib.Path(xfem_contact.scenes.__file__).parent / "two_inclusions.toml"
    data = tomllib.loads(path.read_text())
    data["solver"] = data.get("solver", {}) | {"preset": "iterative"}
    scene = load_scene(data)
    problem = build(scene)
    problem = problem[0] if isinstance(problem, tuple) else problem
    assert {law.name for law in problem.laws.values()} == {"bonded", "coulomb"}
    problem.loads.set_time(0.5)
    problem.petsc_options = scene.petsc_options
    report = problem.solve()
    assert max(report.linear_iterations) <= 20
    with pytest.raises(ValueError, match="linear problem"):
        inclusion_problem(6, 2, "bonded", petsc_options=preset("iterative")).solve()


@pytest.mark.mpi
def test_prolongation_from_entries_only_another_process_has():
    """A fine unknown whose interpolation only another process has, and a vertex unknown
    that only another process interpolates from (their owner holds no cell on which the
    field is active around them): the owner's row of the prolongation comes from the
    other process and the vertex is a coarse unknown of its owner (before, the other
    process raised alone and the owner hung in the next collective call)."""
    from mpi4py import MPI
    from petsc4py import PETSc

    from xfem_contact.solvers.band_multigrid import _prolongation

    comm = MPI.COMM_WORLD
    if comm.size != 2:
        pytest.skip("needs 2 processes")
    first = 2 * comm.rank  # two unknowns a process: 0, 1 on rank 0; 2, 3 on rank 1
    J = PETSc.Mat().createAIJ(((2, 4), (2, 4)), nnz=1, comm=comm)
    for i in range(first, first + 2):
        J.setValue(i, i, 1.0)
    J.assemble()
    u = PETSc.IS().createGeneral(np.arange(first, first + 2, dtype=PETSc.IntType), comm=comm)
    # rank 0 has row 0 only; rank 1 has rank 0's row 1 (the vertex 1 itself) and its row
    # 2 takes half of column 1
    rows, cols, weights = {
        0: ([0], [0], [1.0]),
        1: ([1, 2, 2, 3], [1, 1, 2, 3], [1.0, 0.5, 0.5, 1.0]),
    }[comm.rank]
    P, P_full, positions = _prolongation(
        J, u, np.array(rows), np.array(cols, dtype=PETSc.IntType), np.array(weights)
    )
    assert P_full.getSize() == (4, 4)
    coarse, fine = P_full.createVecs()
    coarse.setArray([1.0, 10.0] if comm.rank == 0 else [100.0, 1000.0])
    P_full.mult(coarse, fine)
    assert np.allclose(np.concatenate(comm.allgather(fine.array)), [1.0, 10.0, 55.0, 1000.0])
    assert list(positions) == [0, 1]
    for obj in (P, P_full, coarse, fine, u, J):
        obj.destroy()
