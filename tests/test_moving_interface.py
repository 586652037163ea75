"""Interfaces that move: ``problem.update_interface`` re-cuts, keeps the loads, laws and
parameters, compiles nothing and warm-starts Newton; the result is the problem built
afresh at the new position."""

import numpy as np
import pytest

from xfem_contact.cases.paper import INCLUSION_CENTRE, inclusion_problem
from xfem_contact.fem import forms
from xfem_contact.mechanics.materials import Material

#: A stiffer inclusion, so that the solution depends on where the interface is
MATERIALS = {-1: Material(300e6, 0.2), 1: Material(100e6, 0.0)}
N = 16


def circle(radius: float):
    cx, cy = INCLUSION_CENTRE
    return lambda x: np.hypot(x[0] - cx, x[1] - cy) - radius


def moved_and_fresh(law: str, **options):
    """Case 2 (16 x 16, P2, two materials) solved at radius 0.2, moved to 0.23 and
    solved again; and the same problem built at 0.23 and solved from zero."""
    moved = inclusion_problem(N, 2, law, materials=MATERIALS, **options)
    moved.solve()
    moved.accept_step()
    compiled = forms.compiled_forms()
    moved.update_interface(circle(0.23))
    warm = moved.solve()
    assert forms.compiled_forms() == compiled, "moving the interface compiled a form"
    fresh = inclusion_problem(N, 2, law, materials=MATERIALS, radius=0.23, **options)
    cold = fresh.solve()
    return moved, warm, fresh, cold


@pytest.mark.mpi
@pytest.mark.parametrize("law", ["sticking", "frictionless"])
def test_a_moved_interface_solves_as_a_problem_built_there(law):
    """Same active dofs and the same fields as the problem built at the new position;
    the warm start takes no more Newton steps than the cold one."""
    moved, warm, fresh, cold = moved_and_fresh(law)
    np.testing.assert_array_equal(moved.space.active, fresh.space.active)
    scale = np.abs(fresh.w.x.array).max()
    assert np.abs(moved.w.x.array - fresh.w.x.array).max() < 1e-8 * scale
    assert warm.iterations <= cold.iterations, (warm.iterations, cold.iterations)


@pytest.mark.mpi
def test_a_moved_coulomb_interface_keeps_its_history_and_the_cone():
    """Coulomb carries its last accepted state onto the new cut (its slip increments
    start from there), converges warm and stays inside the cone."""
    moved, warm, _, cold = moved_and_fresh("coulomb", friction=0.3)
    assert warm.converged and cold.converged
    state = moved.interface_state(moved.w)
    bound = 0.3 * np.abs(state["P_n"])
    assert np.all(np.abs(state["P_t"]) <= bound + 1e-10 * np.abs(state["P_n"]).max())
    assert np.abs(moved.w_old.x.array[~moved.space.active]).max(initial=0.0) == 0.0


def test_a_cut_updated_behind_the_problem_is_refused_by_name():
    problem = inclusion_problem(4, 1, "bonded")
    problem.cut.update(circle(0.25))
    with pytest.raises(ValueError, match="update_interface"):
        problem.solve()


def path(k: int):
    """Position k of a path that moves and grows the inclusion (centre, radius in m)."""
    return lambda x: np.hypot(x[0] - 0.42 - 0.016 * k, x[1] - 0.46 - 0.008 * k) - 0.15 - 0.01 * k


@pytest.mark.mpi
@pytest.mark.parametrize(("law", "options", "most"), [("sticking", {}, 1), ("coulomb", {}, 6)])
def test_a_moving_contact_interface_starts_without_spurious_gaps(law, options, most):
    """Moved and resized along a path (n = 20), each position converges warm: sticking
    in one Newton step as from zero, Coulomb (its history carried) in a few. The two
    sides' fields carried as they were differ across the new interface by a spurious
    gap and slip (Coulomb then took 7 steps at one of these 7 positions and did not
    converge at two, sticking took 2 steps at one)."""
    options = {"friction": 0.3} if law == "coulomb" else options
    problem = inclusion_problem(20, 2, law, materials=MATERIALS, **options)
    problem.update_interface(path(0))
    problem.solve()
    problem.accept_step()
    for k in range(1, 8):
        problem.update_interface(path(k))
        report = problem.solve()
        assert report.iterations <= most, (k, report.iterations)
        problem.accept_step()


@pytest.mark.mpi
def test_the_scale_of_the_cut_follows_the_interface():
    """``stabilization_length="cut"``: the sides' trace lengths are made anew on the new
    cut, with no compile; the moved problem is the one built there."""
    moved, _, fresh, _ = moved_and_fresh("sticking", stabilization_length="cut")
    scale = np.abs(fresh.w.x.array).max()
    assert np.abs(moved.w.x.array - fresh.w.x.array).max() < 1e-8 * scale
