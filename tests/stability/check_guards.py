"""Each stability test fails with the guard it checks switched off.

Run ``python tests/stability/check_guards.py`` (not collected by pytest): every line
must print ``FAILS as it should``. Guards: the ghost penalty (cut fractions), the
harmonic-mean augmentation (stiffness contrast), the Coulomb clamp (friction cone),
the objective bulk (a large rotation in one step or ten). The LBB check carries its
own counter-test (``lbb="none"``).
"""

import pathlib
import sys

import xfem_contact  # noqa: F401  (before dolfinx)

sys.path.insert(0, str(pathlib.Path(__file__).parent))

# isort: split
import test_cuts  # noqa: E402
import test_friction  # noqa: E402
import test_materials  # noqa: E402
import test_rotation  # noqa: E402

import xfem_contact.mechanics.problem as problem_module  # noqa: E402
from xfem_contact.mechanics.bulk import SmallStrain  # noqa: E402
from xfem_contact.mechanics.laws import contact  # noqa: E402


def attempt(name, check) -> None:
    try:
        check()
        print(f"{name}: PASSED (the guard is not what the test checks)")
    except BaseException as error:  # noqa: BLE001  (assertion or solver failure alike)
        text = str(error).splitlines()[0][:160] if str(error) else ""
        print(f"{name}: FAILS as it should: {type(error).__name__} {text}")


def main() -> None:
    solve_at = test_cuts.solve_at
    test_cuts.solve_at = lambda f, d, comm=None, **o: solve_at(f, d, ghost_penalty=0.0)
    attempt(
        "cut fractions without the ghost penalty",
        lambda: test_cuts.test_condition_and_error_stay_bounded_as_the_cut_vanishes(2),
    )
    test_cuts.solve_at = solve_at

    harmonic = contact.ContactLaw.augmentation_coefficient
    contact.ContactLaw.augmentation_coefficient = lambda self, m, h: (
        self.augmentation * 0.5 * (m[-1].E + m[1].E) / h
    )
    attempt(
        "contrast 1e6 with the arithmetic-mean augmentation",
        lambda: test_materials.test_stiffness_contrast_keeps_the_interface_closed_and_smooth(1e6),
    )
    contact.ContactLaw.augmentation_coefficient = harmonic

    bound = contact.Coulomb.friction_bound
    contact.Coulomb.friction_bound = lambda self, P_n, ops: None
    attempt(
        "friction 0.3 without the clamp",
        lambda: test_friction.test_any_friction_converges_inside_the_cone(0.3),
    )
    contact.Coulomb.friction_bound = bound

    models = problem_module.BULK_MODELS
    problem_module.BULK_MODELS = dict(models, large=SmallStrain)
    attempt(
        "rotation with the small-strain bulk",
        test_rotation.test_one_step_or_ten_give_the_same_pressures,
    )
    problem_module.BULK_MODELS = models


if __name__ == "__main__":
    main()
