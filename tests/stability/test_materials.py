"""Material extremes stay stable: stiffness contrast 1 .. 1e6 both ways, and nu up
to 0.499 in plane strain.

Measured (case 2, 16 x 16, P2, hydrostatic pressure 1 Pa, sticking): every contrast
converges in one Newton step with the whole interface closed; the pressure tends to
the rigid-inclusion limit (range [-1.794, -1.657] Pa at 1e4 and 1e6) and to zero for a
soft inclusion. The guard is the augmentation coefficient ``r = a E / h`` with the
harmonic mean of the moduli: with the arithmetic mean the 1e6-stiff inclusion took 7
Newton steps and opened 48 of its 112 points. nu (20 x 20, paper loading, exact
uniform stress whatever nu): pressure error 1.35e-3 (nu = 0) to 3.8e-3 (0.499) for P2,
1.44e-3 to 4.3e-3 for P1: no locking blow-up.
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import numpy as np
import pytest

from xfem_contact.cases.paper import (
    INCLUSION_E,
    inclusion_errors,
    inclusion_problem,
    pressure_fourier_misfit,
)
from xfem_contact.mechanics.materials import Material

CONTRASTS = [1.0, 1e2, 1e4, 1e6, 1e-2, 1e-4, 1e-6]


@pytest.mark.mpi
@pytest.mark.parametrize("contrast", CONTRASTS)
def test_stiffness_contrast_keeps_the_interface_closed_and_smooth(contrast):
    materials = {-1: Material(contrast * INCLUSION_E, 0.0), 1: Material(INCLUSION_E, 0.0)}
    problem = inclusion_problem(16, 2, "sticking", loading="hydrostatic", materials=materials)
    report = problem.solve()
    counts = problem.interface_status(problem.w)
    state = problem.interface_state(problem.w)
    print(f"contrast {contrast:g}: Newton {report.iterations}, {counts}")
    assert report.iterations <= 30
    assert counts["contact"] == problem.mesh.comm.allreduce(state["P_n"].size)
    assert np.all(np.isfinite(state["lambda_n"]))
    assert np.all(state["lambda_n"] > -2.0)  # below the rigid-inclusion limit (-1.79 Pa)
    if contrast >= 1e-2:  # softer ones carry ~nothing: relative smoothness means nothing
        assert pressure_fourier_misfit(problem) < 5e-2


def patch_misfit(contrast: float, higher: float = 1.0) -> float:
    """The Fourier misfit of :func:`test_stiffness_contrast_keeps_the_interface_closed_and_smooth`
    with the scale of the cut credited through the ghost penalty, whose jumps of second
    derivatives weigh ``higher`` times the gradient's."""
    materials = {-1: Material(contrast * INCLUSION_E, 0.0), 1: Material(INCLUSION_E, 0.0)}
    problem = inclusion_problem(
        16,
        2,
        "sticking",
        loading="hydrostatic",
        materials=materials,
        stabilization_length="patch",
        ghost_penalty_higher=higher,
    )
    problem.solve()
    return pressure_fourier_misfit(problem)


@pytest.mark.mpi
@pytest.mark.parametrize("contrast", [1e2, 1e4, 1e6])
def test_the_patch_length_keeps_a_stiff_inclusion_smooth(contrast):
    """``stabilization_length="patch"``: misfit 0.047, 0.048, 0.048 (the cut's own
    lengths: 0.054, 0.055, 0.055)."""
    assert patch_misfit(contrast) < 5e-2


@pytest.mark.xfail(strict=True, reason="the soft inclusion's slivers: misfit 0.123")
def test_the_patch_length_keeps_a_soft_inclusion_smooth():
    assert patch_misfit(1e-2) < 5e-2


@pytest.mark.mpi
@pytest.mark.parametrize("contrast", [1e-2, 1e2, 1e6])
def test_weak_higher_ghost_jumps_keep_every_contrast_smooth(contrast):
    """``ghost_penalty_higher=0.01`` with the patch length: misfit 0.041, 0.023, 0.023
    (0.123, 0.047, 0.048 with the full second-derivative jumps, whose consistency
    error biases the matrix's traction on the interface)."""
    assert patch_misfit(contrast, higher=0.01) < 5e-2


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45, 0.49, 0.499])
def test_nearly_incompressible_keeps_the_pressure(degree, nu):
    problem = inclusion_problem(20, degree, "sticking", materials=Material(INCLUSION_E, nu))
    report = problem.solve()
    assert report.iterations <= 30
    assert inclusion_errors(problem, problem.w).pressure < 5e-3
