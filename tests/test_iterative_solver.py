"""The iterative linear solver of the Newton steps gives the direct solver's answer.

FGMRES with the Schur field split (``LINEAR_PRESETS["iterative"]``): the splits cover
the reduced unknowns once, the displacement split keeps nodes as blocks of 2 with the
six rigid modes as its near null space, the Krylov iterations are reported, and a
scene selects the preset with ``[solver] linear``.
"""

import numpy as np
import pytest
from test_scenes import base

from xfem_contact.cases.paper import inclusion_errors, inclusion_problem
from xfem_contact.scenes.scene import SceneError, load_scene
from xfem_contact.solvers.options import LINEAR_PRESETS, preset


@pytest.mark.mpi
@pytest.mark.filterwarnings("ignore::xfem_contact.mechanics.problem.RigidModeWarning")
@pytest.mark.parametrize("law", ["sticking", "frictionless"])
def test_iterative_equals_direct(law):
    direct = inclusion_problem(10, 2, law)
    direct.solve()
    iterative = inclusion_problem(10, 2, law)
    report = iterative.solve(preset("iterative"))
    assert report.iterations == direct.last_report.iterations
    assert all(k > 1 for k in report.linear_iterations)  # a Krylov method, not one LU
    assert direct.last_report.linear_iterations == [1] * direct.last_report.iterations
    scale = np.abs(direct.w.x.array).max()
    assert np.allclose(iterative.w.x.array, direct.w.x.array, rtol=0.0, atol=1e-8 * scale)
    e_direct = inclusion_errors(direct, direct.w).pressure
    assert inclusion_errors(iterative, iterative.w).pressure == pytest.approx(e_direct, rel=1e-6)


def test_splits_cover_the_reduced_unknowns_once():
    problem = inclusion_problem(10, 2, "sticking")
    problem.solve(preset("iterative"))
    pc = problem._newton.snes.getKSP().getPC()
    ksp_u, ksp_lambda = pc.getFieldSplitSubKSP()
    A_u, A_l = ksp_u.getOperators()[0], ksp_lambda.getOperators()[0]
    n_reduced = problem._newton.J_r.getSize()[0]
    assert A_u.getSize()[0] + A_l.getSize()[0] == n_reduced
    dofs = problem.space.dof_counts()
    assert A_l.getSize()[0] == dofs.multiplier
    assert A_u.getBlockSize() == 2
    space = A_u.getNearNullSpace()
    assert space.handle != 0  # set (reading the vectors of an unset one crashes)
    assert len(space.getVecs()) == 6


def test_scene_selects_the_preset():
    scene = load_scene(base(law="sticking") | {"solver": {"linear": "iterative"}})
    assert scene.petsc_options["pc_type"] == "fieldsplit"
    assert load_scene(base(law="sticking")).petsc_options.get("pc_type") is None
    with pytest.raises(SceneError, match=r"solver.linear.*direct"):
        load_scene(base(law="sticking") | {"solver": {"linear": "multigrid"}})
    with pytest.raises(ValueError, match="Unknown linear solver 'cg'"):
        preset("cg")
    assert set(LINEAR_PRESETS) == {"direct", "iterative"}
