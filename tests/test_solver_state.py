"""Solvers that cannot go stale or lie: what changes after a solve is used or refused,
a failed solve keeps the last good state, Newton starts from ``w``, success means the
tolerances hold, and no PETSc option of ours outlives its solve."""

import inspect

import xfem_contact  # noqa: F401

# isort: split
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact import LinearSolveFailure, Material, NewtonFailure, SolveError
from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.mechanics.plain import PlainElasticityProblem
from xfem_contact.solvers.callback_errors import PETSC_ERR_PYTHON, callback_exception

#: A Krylov solve that cannot converge: one unpreconditioned CG iteration
ONE_CG_STEP = {"ksp_type": "cg", "pc_type": "none", "ksp_max_it": 1, "ksp_rtol": 1e-12}


def multipliers(problem) -> np.ndarray:
    return np.asarray(problem.interface_samples(problem.w)["lambda_n"])


def our_options() -> list[str]:
    return [k for k in PETSc.Options().getAll() if k.startswith("xfem_")]


def sides(x):
    return np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0)


def test_loads_added_after_a_solve_are_used():
    """Sticking is linear in the loads: adding the same loads again doubles lambda."""
    problem = inclusion_problem(8, 1, "sticking")
    problem.solve()
    once = multipliers(problem)
    problem.loads.add_pressure(sides, 1.0)
    problem.loads.add_pressure(lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), 2.0)
    problem.solve()
    assert np.allclose(multipliers(problem), 2.0 * once, rtol=1e-8, atol=1e-10)


def test_solver_options_given_after_a_solve_are_used():
    problem = inclusion_problem(8, 1, "sticking")
    problem.solve()
    problem.petsc_options = {"snes_rtol": 1e-6, "snes_atol": 1e-9}
    problem.solve()
    rtol, atol, _, _ = problem.newton.snes.getTolerances()
    assert (rtol, atol) == (1e-6, 1e-9)


def test_a_new_cut_is_refused():
    problem = inclusion_problem(8, 1, "sticking")
    problem.solve()
    problem.cut.update(lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.25)
    with pytest.raises(ValueError, match="cut.update"):
        problem.solve()


def test_failure_keeps_the_state_before_the_solve():
    problem = inclusion_problem(10, 2, "coulomb", loading="pull", friction=1.0)
    problem.loads.add_pressure(sides, -0.5)  # a harder load, several Newton steps
    before = problem.w.x.array.copy()
    with pytest.raises(NewtonFailure, match="restored") as failure:
        problem.petsc_options = {"snes_max_it": 1}
        problem.solve()
    assert failure.value.report.iterations == 1
    assert np.array_equal(problem.w.x.array, before)
    assert problem.last_report is failure.value.report
    assert isinstance(failure.value, SolveError)
    assert our_options() == []


def test_a_callback_exception_is_raised_as_itself(monkeypatch):
    """An exception raised in a Newton callback comes out of the solve as itself, not as
    PETSc's "error code 101" (``PETSC_ERR_PYTHON``, which petsc4py chains the exception
    to): Ctrl-C during a factorisation is delivered in the next callback, and an ``except
    Exception`` around the solve must not take that interrupt for a failed solve. The
    state before the solve is kept, and the same solver solves again (SNES had left its
    solution vector read-locked)."""
    problem = inclusion_problem(8, 1, "sticking")
    original, fault = type(problem).interface_status, [KeyboardInterrupt()]

    def status(self, w, name=None):  # the Newton monitor's callback, at every iterate
        counts = original(self, w, name)
        if fault and self.newton.snes.getIterationNumber() > 0:  # after a Newton step
            raise fault[0]
        return counts

    monkeypatch.setattr(type(problem), "interface_status", status)
    before = problem.w.x.array.copy()
    with pytest.raises(KeyboardInterrupt):
        problem.solve()
    assert np.array_equal(problem.w.x.array, before)
    fault[0] = RuntimeError("the status callback broke")
    with pytest.raises(RuntimeError, match="the status callback broke"):
        problem.solve()
    fault.clear()
    assert problem.solve().converged  # and the same solver solves again
    assert our_options() == []


def test_callback_exception_through_nested_solves():
    """A Python preconditioner's own solve nests PETSc's error: the innermost cause is
    the callback's exception; PETSc's own errors report none."""
    inner = PETSc.Error(PETSC_ERR_PYTHON)
    inner.__cause__ = KeyError("deep")
    outer = PETSc.Error(PETSC_ERR_PYTHON)
    outer.__cause__ = inner
    assert callback_exception(outer) is inner.__cause__
    assert callback_exception(PETSc.Error(76)) is None
    assert callback_exception(PETSc.Error(PETSC_ERR_PYTHON)) is None


def plain_problem() -> PlainElasticityProblem:
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    problem = PlainElasticityProblem(mesh, 1, Material(1e3, 0.3))
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 0.0), 0.0)
    problem.loads.add_traction(lambda x: np.isclose(x[1], 1.0), (0.0, -10.0))
    return problem


@pytest.mark.parametrize(
    "make", [lambda: inclusion_problem(8, 1, "bonded"), plain_problem], ids=["cut", "plain"]
)
def test_a_linear_solve_fails_as_newton_does(make):
    """Every problem kind: the same error type, the state before the solve, the failed
    solve's report in ``last_report``, no option of ours left behind."""
    problem = make()
    problem.solve()
    assert problem.last_report.converged
    before = problem.w.x.array.copy()
    problem.loads.set_time(2.0)
    with pytest.raises(LinearSolveFailure, match="KSP converged reason -3") as failure:
        problem.petsc_options = ONE_CG_STEP
        problem.solve()
    assert isinstance(failure.value, SolveError)
    assert failure.value.report.reason < 0
    assert problem.last_report is failure.value.report
    assert np.array_equal(problem.w.x.array, before)
    assert our_options() == []
    problem.petsc_options = {}
    problem.solve()  # and the problem solves again
    assert problem.last_report.converged


def test_newton_starts_from_w():
    """A converged w given to a new problem: converged before any step."""
    solved = inclusion_problem(10, 2, "coulomb", loading="pull", friction=1.0)
    assert solved.solve().iterations > 1
    fresh = inclusion_problem(10, 2, "coulomb", loading="pull", friction=1.0)
    fresh.w.x.array[:] = solved.w.x.array
    assert fresh.solve().iterations == 0


def test_ksponly_cannot_pass_as_converged():
    """One linear step of a problem that needs several does not meet the tolerances."""
    problem = inclusion_problem(10, 2, "coulomb", loading="pull", friction=1.0)
    with pytest.raises(NewtonFailure, match="final residual"):
        problem.petsc_options = {"snes_type": "ksponly"}
        problem.solve()


def test_no_option_outlives_its_solve():
    problem = inclusion_problem(8, 1, "sticking", lbb="stabilized")
    problem.petsc_options = {"snes_linesearch_type": "bt"}
    problem.solve()
    assert our_options() == []
    bonded = inclusion_problem(8, 1, "bonded")
    bonded.petsc_options = {"ksp_type": "preonly"}
    bonded.solve()
    assert our_options() == []
    # DOLFINx's LinearProblem writes its own options: plain elasticity and the
    # body-fitted baselines remove them after the solve
    from xfem_contact.cases.body_fitted import fitted_inclusion
    from xfem_contact.cases.fitted_nitsche import nitsche_inclusion

    fitted_inclusion(0.2, 1)
    nitsche_inclusion(0.2, 1)
    assert our_options() == []


def test_options_given_at_construction_reach_petsc_under_the_prefix():
    options = {"snes_rtol": 1e-7, "snes_max_it": 17, "ksp_type": "gmres"}
    problem = inclusion_problem(
        8, 1, "sticking", petsc_options=options, petsc_options_prefix="mine_"
    )
    problem.solve()
    snes = problem.newton.snes
    assert snes.getOptionsPrefix() == "mine_"
    assert snes.getKSP().getOptionsPrefix() == "mine_"
    rtol, _, _, max_it = snes.getTolerances()
    assert (rtol, max_it) == (1e-7, 17)
    assert snes.getKSP().getType() == "gmres"
    assert problem.solver_options()["snes_max_it"] == 17
    # a new value is an explicit change: the next solve rebuilds the solver with it
    problem.petsc_options = {"snes_max_it": 9}
    problem.solve()
    assert problem.newton.snes is not snes
    assert problem.newton.snes.getTolerances()[3] == 9
    assert [k for k in PETSc.Options().getAll() if k.startswith("mine_")] == []
    # the plain problem too (its KSP)
    plain = PlainElasticityProblem(
        dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 2, 2),
        1,
        Material(1e3, 0.3),
        petsc_options=ONE_CG_STEP,
        petsc_options_prefix="plain_mine_",
    )
    plain.loads.add_displacement(lambda x: np.isclose(x[1], 0.0), 0.0)
    plain.loads.add_traction(lambda x: np.isclose(x[1], 1.0), (0.0, -10.0))
    with pytest.raises(LinearSolveFailure, match="reason -3"):  # one CG step: the options
        plain.solve()


def test_problems_without_a_prefix_get_different_ones():
    first, second = inclusion_problem(4, 1, "sticking"), inclusion_problem(4, 1, "sticking")
    assert first.petsc_options_prefix != second.petsc_options_prefix
    assert first.petsc_options_prefix.startswith("xfem_problem_")
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 2, 2)
    plains = [PlainElasticityProblem(mesh, 1, Material(1e3, 0.3)) for _ in range(2)]
    assert plains[0].petsc_options_prefix != plains[1].petsc_options_prefix


def test_an_empty_prefix_is_refused():
    with pytest.raises(ValueError, match="petsc_options_prefix must be a non-empty string, got ''"):
        inclusion_problem(4, 1, "sticking", petsc_options_prefix="")
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 2, 2)
    with pytest.raises(ValueError, match="petsc_options_prefix must be a non-empty string"):
        PlainElasticityProblem(mesh, 1, Material(1e3, 0.3), petsc_options_prefix="")


def test_options_at_solve_are_deprecated_and_used_for_that_solve():
    problem = inclusion_problem(8, 1, "sticking")
    with pytest.warns(DeprecationWarning, match=r"Problem\(\.\.\., petsc_options=\.\.\.\)"):
        problem.solve({"snes_max_it": 13})
    assert problem.newton.snes.getTolerances()[3] == 13
    assert problem.petsc_options == {}
    problem.solve()  # the problem's own options again
    assert problem.newton.snes.getTolerances()[3] == 30
    plain = plain_problem()
    with pytest.warns(DeprecationWarning, match=r"PlainElasticityProblem\(\.\.\., petsc_"):
        plain.solve({"ksp_type": "preonly"})


def test_the_interface_methods_share_one_signature():
    """``(w, name=None)`` each: the state is explicit, the interface optional."""
    problem = inclusion_problem(6, 1, "sticking")
    problem.solve()
    methods = (problem.interface_state, problem.interface_status, problem.interface_samples)
    for method in methods:
        assert list(inspect.signature(method).parameters) == ["w", "name"], method.__name__
    (name,) = problem.laws
    assert problem.interface_status(problem.w, name) == problem.interface_status(problem.w)
    samples = problem.interface_samples(problem.w, name)
    state = problem.interface_state(problem.w, name)
    assert len(samples["lambda_n"]) == MPI.COMM_WORLD.allreduce(len(state["lambda_n"]))
    zero = problem.w.copy()
    zero.x.array[:] = 0.0
    assert np.all(problem.interface_state(zero)["lambda_n"] == 0.0)


def test_a_scene_problem_takes_the_scene_options_and_a_prefix():
    from test_scenes import base

    from xfem_contact.scenes.builder import build
    from xfem_contact.scenes.scene import load_scene

    scene = load_scene(base(law="sticking") | {"solver": {"max_iterations": 12}})
    problem, _ = build(scene, petsc_options_prefix="scene_")
    assert problem.petsc_options_prefix == "scene_"
    assert problem.petsc_options == scene.petsc_options
    assert problem.solver_options()["snes_max_it"] == 12
    problem.loads.set_time(1.0)
    problem.solve()
    assert problem.newton.snes.getOptionsPrefix() == "scene_"
    assert problem.newton.snes.getTolerances()[3] == 12
