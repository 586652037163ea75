"""The 3D checks against exact solutions beyond the uniform stress: a ball of another
material bonded in a matrix (the composite sphere, 3D Lame), the same two bodies in
frictionless contact (concentric spheres), the multiplier's oscillation with and
without the LBB treatment on the sphere, and the friction limits. The rates and the
finer meshes are in ``bench/composite_sphere.py`` and ``bench/sphere_friction.py``."""

import numpy as np
import pytest

from xfem_contact.cases.solid import (
    COMPOSITE_RADIUS,
    INCLUSION,
    SOLID,
    composite_sphere_coefficients,
    composite_sphere_errors,
    composite_sphere_exact,
    composite_sphere_pressure,
    composite_sphere_problem,
    composite_sphere_traction_errors,
)


def test_composite_sphere_exact_field_is_continuous_and_balanced():
    """The exact field: continuous displacement and radial traction at r = R, the
    pressure 3 K C; the same material on both sides gives the plain strain field."""
    A, B, C = composite_sphere_coefficients()
    R = COMPOSITE_RADIUS
    x = np.array([[0.5 + R], [0.5], [0.5]])
    assert np.allclose(composite_sphere_exact(-1)(x), composite_sphere_exact(1)(x), atol=1e-15)
    k_out = SOLID.lmbda + 2 * SOLID.mu / 3
    sigma_rr_out = 3 * k_out * A - 4 * SOLID.mu * B / R**3
    assert np.isclose(sigma_rr_out, composite_sphere_pressure(), rtol=1e-12)
    assert composite_sphere_pressure() < 0  # closed: a contact law transmits it
    assert composite_sphere_coefficients(SOLID)[1] == 0.0
    assert INCLUSION != SOLID


def test_composite_sphere_bonded_converges():
    """P2 tets, quadric level set, n = 2 and 4: relative L2 displacement errors inside
    0.314 -> 0.060 (rate 2.40), outside 0.0556 -> 0.0142 (1.97); bench gives n = 4..12
    (rates 2.6 to 3.7)."""
    errors = {}
    for n in (2, 4):
        problem = composite_sphere_problem(n, 2)
        problem.solve()
        errors[n] = composite_sphere_errors(problem)
    rates = {s: np.log2(errors[2][s] / errors[4][s]) for s in (-1, 1)}
    print(f"\ncomposite sphere bonded P2 n=2, 4: {errors}, rates {rates}")
    assert max(errors[4].values()) < 0.07
    assert rates[-1] > 2.2 and rates[1] > 1.9


def test_concentric_spheres_frictionless_pressure():
    """The ball in frictionless contact with the matrix: the uniform exact pressure
    (P2, n = 4: 4.2e-2; the bonded multiplier 3.7e-2)."""
    problem = composite_sphere_problem(4, 2, "frictionless")
    report = problem.solve()
    e_n, _ = composite_sphere_traction_errors(problem)
    print(f"\nconcentric spheres frictionless P2 n=4: pressure error {e_n:.3e}")
    assert report.converged and e_n < 0.06
    assert problem.interface_status(problem.w)["contact"] > 0


def test_composite_sphere_contact_needs_an_even_n():
    with pytest.raises(ValueError, match="n must be even with a contact law"):
        composite_sphere_problem(3, 1, "frictionless")
