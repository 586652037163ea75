"""Each stability test fails with the guard it checks switched off.

Guards: the ghost penalty (cut fractions), cell aggregation (cut fractions without the
ghost penalty; the stabilised pair's inf-sup constant; a crack's slivers next to its
tip; the Williams rate with gathered tip dofs; roots off a crack's tip cells), the
harmonic-mean augmentation
(stiffness contrast), the Coulomb clamp (friction cone), the objective bulk (a large
rotation in one step or ten). The LBB check carries its own counter-test (``lbb="none"``).
Marked ``guards``: ``pytest -m guards`` runs these alone.
"""

import dolfinx.la
import pytest
import test_aggregation
import test_cuts
import test_friction
import test_inf_sup
import test_materials
import test_rotation

import xfem_contact.fem.aggregation as aggregation_module
import xfem_contact.fem.enrichment as enrichment_module
import xfem_contact.mechanics.problem as problem_module
from xfem_contact.mechanics.bulk import SmallStrain
from xfem_contact.mechanics.laws import contact
from xfem_contact.solvers.newton import NewtonFailure


def without_ghost_penalty(monkeypatch):
    solve_at = test_cuts.solve_at
    monkeypatch.setattr(
        test_cuts, "solve_at", lambda f, d, comm=None, **o: solve_at(f, d, ghost_penalty=0.0)
    )
    return lambda: test_cuts.test_condition_and_error_stay_bounded_as_the_cut_vanishes(2)


def without_aggregation(monkeypatch):
    make = test_aggregation.aggregated_problem
    monkeypatch.setattr(test_aggregation, "aggregated_problem", lambda: make(aggregation=None))
    return test_aggregation.test_aggregation_bounds_the_condition_without_ghost_penalty


def without_aggregation_in_the_inf_sup_test(monkeypatch):
    betas = test_inf_sup.betas
    monkeypatch.setattr(
        test_inf_sup,
        "betas",
        lambda *args, **options: betas(*args, **options | {"aggregation": None}),
    )
    return test_inf_sup.test_aggregation_keeps_the_stabilised_constant_bounded


def without_aggregation_next_to_a_tip(monkeypatch):
    eligible = aggregation_module._eligible_cells

    def away_from_tied_dofs(space):  # cells holding a tied dof never badly cut
        cells = eligible(space)
        tied = dolfinx.la.vector(space.W.dofmap.index_map, space.W.dofmap.index_map_bs)
        tied.array[space.ties.ravel()] = 1.0
        tied.scatter_forward()
        for field in (0, 1):
            cells &= ~(tied.array[space.W.sub(field).dofmap.list[: cells.size]] > 0).any(axis=1)
        return cells

    monkeypatch.setattr(aggregation_module, "_eligible_cells", away_from_tied_dofs)
    return lambda: test_aggregation.test_a_sliver_next_to_a_crack_tip_is_aggregated("triangle")


def with_a_degree_one_ramp_under_aggregation(monkeypatch):
    monkeypatch.setattr(enrichment_module, "ramp_degree", lambda tip_dofs, degree, aggregated: 1)
    return test_aggregation.test_aggregation_keeps_the_williams_rate


def with_roots_at_a_crack_tip(monkeypatch):
    codes = aggregation_module._cell_codes

    def tip_cells_are_roots(*args):  # a tip or extension cell as any well cut cell
        out = codes(*args)
        out[out == aggregation_module._SHARED] = aggregation_module._WELL
        return out

    monkeypatch.setattr(aggregation_module, "_cell_codes", tip_cells_are_roots)
    return test_aggregation.test_a_root_is_never_a_tip_cell


def with_arithmetic_mean_augmentation(monkeypatch):
    monkeypatch.setattr(
        contact.ContactLaw,
        "augmentation_coefficient",
        lambda self, m, h: self.augmentation * 0.5 * (m[-1].E + m[1].E) / h,
    )
    return lambda: test_materials.test_stiffness_contrast_keeps_the_interface_closed_and_smooth(1e6)


def without_coulomb_clamp(monkeypatch):
    monkeypatch.setattr(contact.Coulomb, "friction_bound", lambda self, P_n, ops: None)
    return lambda: test_friction.test_any_friction_converges_inside_the_cone(0.3)


def with_small_strain_bulk(monkeypatch):
    monkeypatch.setattr(
        problem_module, "BULK_MODELS", dict(problem_module.BULK_MODELS, large=SmallStrain)
    )
    return test_rotation.test_one_step_or_ten_give_the_same_pressures


GUARDS = {
    "ghost penalty": without_ghost_penalty,
    "cell aggregation": without_aggregation,
    "cell aggregation (inf-sup)": without_aggregation_in_the_inf_sup_test,
    "cell aggregation next to a crack tip": without_aggregation_next_to_a_tip,
    "cell aggregation's ramp of the displacement degree": with_a_degree_one_ramp_under_aggregation,
    "cell aggregation's roots off a crack tip": with_roots_at_a_crack_tip,
    "harmonic-mean augmentation": with_arithmetic_mean_augmentation,
    "Coulomb clamp": without_coulomb_clamp,
    "objective bulk": with_small_strain_bulk,
}


@pytest.mark.guards
@pytest.mark.parametrize("guard", GUARDS)
def test_a_stability_test_fails_without_its_guard(guard, monkeypatch):
    check = GUARDS[guard](monkeypatch)
    with pytest.raises((AssertionError, NewtonFailure)):
        check()
