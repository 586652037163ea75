"""Near-tip and Griffith-crack fields (mechanics/fracture): branch functions and their
derivatives, the Williams fields' equilibrium, lips and textbook stresses, the UFL forms
of the same definitions, and Westergaard's solution against its remote stress, its
free faces, Hooke's law and the Williams limit at its tips."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import math

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from xfem_contact.mechanics.fracture import (
    UFL,
    GriffithCrack,
    TipFrame,
    WilliamsField,
    branch_functions,
    branch_gradients,
    effective_modulus,
    tip_frame,
)
from xfem_contact.mechanics.fracture.williams import hooke, to_global_vector

FRAME = tip_frame((0.3, -0.2), (math.cos(0.4), math.sin(0.4)))
E, NU = 210e9, 0.3
STEP = 1e-6


def points(n=40, seed=0, span=1.0):
    return np.random.default_rng(seed).uniform(-span, span, (2, n))


def central_difference(f, x, h=STEP):
    """``d f / d x_k`` stacked on a new axis after the value axes, by central differences."""
    parts = []
    for k in range(2):
        e = np.zeros((2, 1))
        e[k] = h
        parts.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(parts, axis=-2)  # (..., 2, n)


def divergence(stress, x):
    """``d sigma_ij / d x_j`` by central differences, ``(2, n)``."""
    return np.einsum("ijj...->i...", central_difference(stress, x))


def polar_points(frame, r, theta):
    """Global coordinates of ``(r, theta)`` around ``frame``'s tip."""
    local = (r * np.cos(theta), r * np.sin(theta))
    return np.asarray(frame.origin)[:, None] + np.array(to_global_vector(local, frame))


def test_branch_function_gradients_match_finite_differences():
    x = points()
    fd = central_difference(lambda y: branch_functions(y, FRAME), x)
    exact = branch_gradients(x, FRAME)
    assert exact.shape == (4, 2, x.shape[1])
    assert np.abs(fd - exact).max() < 1e-8 * np.abs(exact).max()


def test_branch_functions_at_the_lips_take_each_side():
    r = np.array([0.01, 0.2])
    upper = branch_functions(polar_points(FRAME, r, np.pi), FRAME, side=1)
    lower = branch_functions(polar_points(FRAME, r, np.pi), FRAME, side=-1)
    np.testing.assert_allclose(upper[0], np.sqrt(r), rtol=1e-12)  # sqrt(r) sin(pi/2)
    np.testing.assert_allclose(lower[0], -np.sqrt(r), rtol=1e-12)
    np.testing.assert_allclose(upper[1:], lower[1:], atol=1e-12)  # continuous across


@pytest.mark.parametrize("plane", ["strain", "stress"])
@pytest.mark.parametrize("K", [(1.0, 0.0), (0.0, 1.0), (1.3, -0.7)])
def test_williams_fields_equilibrium_and_gradient(plane, K):
    field = WilliamsField(FRAME, *K, E, 0.3, plane)
    x = points(seed=1)
    grad = field.gradient(x)
    fd = central_difference(field.displacement, x)
    assert np.abs(fd - grad).max() < 1e-8 * np.abs(grad).max()
    stress = field.stress(x)
    assert np.abs(divergence(field.stress, x)).max() < 1e-6 * np.abs(stress).max()


def test_williams_stresses_are_the_textbook_ones():
    x = points(seed=2)
    r, t = np.hypot(x[0], x[1]), np.arctan2(x[1], x[0])
    c, s2, c2 = 1 / np.sqrt(2 * np.pi * r), np.sin(t / 2), np.cos(t / 2)
    s3, c3 = np.sin(3 * t / 2), np.cos(3 * t / 2)
    frame = tip_frame((0.0, 0.0), (1.0, 0.0))
    mode_I = c * np.array([[c2 * (1 - s2 * s3), s2 * c2 * c3], [s2 * c2 * c3, c2 * (1 + s2 * s3)]])
    mode_II = c * np.array(
        [[-s2 * (2 + c2 * c3), c2 * (1 - s2 * s3)], [c2 * (1 - s2 * s3), s2 * c2 * c3]]
    )
    for plane in ("strain", "stress"):
        np.testing.assert_allclose(
            WilliamsField(frame, 1.0, 0.0, E, NU, plane).stress(x), mode_I, atol=1e-12
        )
        np.testing.assert_allclose(
            WilliamsField(frame, 0.0, 1.0, E, NU, plane).stress(x), mode_II, atol=1e-12
        )


def test_williams_lips_are_free_and_open_as_8K_sqrt_r_over_E():
    K_I = 2e6
    field = WilliamsField(FRAME, K_I, 0.0, E, NU, "strain")
    r = np.array([1e-3, 0.05, 0.4])
    on_lip = polar_points(FRAME, r, np.pi)
    d = np.asarray(FRAME.direction)
    n = np.array([-d[1], d[0]])  # normal of the crack line
    for side in (1, -1):
        traction = np.einsum("ij...,j->i...", field.stress(on_lip, side=side), n)
        assert np.abs(traction).max() < 1e-9 * K_I
    jump = field.displacement(on_lip, side=1) - field.displacement(on_lip, side=-1)
    opening = 8 * K_I * np.sqrt(r / (2 * np.pi)) / effective_modulus(E, NU, "strain")
    np.testing.assert_allclose(n @ jump, opening, rtol=1e-12)
    np.testing.assert_allclose(d @ jump, 0.0, atol=1e-12 * opening.max())


def _sample(mesh, X):
    """Cells of the mesh and the physical points ``(2, cells * len(X))`` of the reference
    points ``X`` in each (so that one compiled Expression evaluates at all of them)."""
    cells = np.arange(mesh.topology.index_map(2).size_local, dtype=np.int32)
    geometry = mesh.geometry.x[mesh.geometry.dofmaps[0][cells], :2]
    cmap = mesh.geometry.cmaps[0]
    x = np.concatenate([cmap.push_forward(X, g) for g in geometry])
    return cells, x.T


def test_ufl_and_numpy_forms_agree_at_points():
    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_SELF, [[-1.0, -1.0], [1.0, 1.0]], [3, 3])
    xs = ufl.SpatialCoordinate(mesh)
    X = np.array([[0.2, 0.3], [0.6, 0.1], [0.15, 0.7]])
    cells, x = _sample(mesh, X)
    field = WilliamsField(FRAME, 1.3, -0.7, E, NU, "strain")
    crack = GriffithCrack.uniaxial(0.4, 1e6, 0.6, center=(0.1, 0.05), direction=(1.0, 0.3))
    pairs = [
        (branch_functions(xs, FRAME, UFL), branch_functions(x, FRAME)),
        (branch_gradients(xs, FRAME, UFL), branch_gradients(x, FRAME)),
        (field.displacement(xs, UFL), field.displacement(x)),
        (field.stress(xs, UFL), field.stress(x)),
        (crack.stress(xs, UFL), crack.stress(x)),
        (crack.displacement(xs, E, NU, ops=UFL), crack.displacement(x, E, NU)),
    ]
    for expr, values in pairs:
        got = dolfinx.fem.Expression(expr, X).eval(mesh, cells).reshape(len(x[0]), -1)
        want = values.reshape(-1, x.shape[1]).T
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("far_field", [True, False])
@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_griffith_crack_hooke_equilibrium_far_field_and_free_faces(plane, far_field):
    crack = GriffithCrack.uniaxial(
        0.7, 2e6, 0.6, center=(0.1, 0.2), direction=(1.0, 0.5), far_field=far_field
    )
    x = points(seed=4, span=2.0)
    grad = central_difference(lambda y: crack.displacement(y, E, NU, plane), x)
    probe = WilliamsField(FRAME, 0.0, 0.0, E, NU, plane)  # its mu and 2D lambda
    stress = crack.stress(x)
    np.testing.assert_allclose(
        np.array(hooke(grad, probe.mu, probe.lmbda)), stress, atol=1e-7 * 2e6
    )
    assert np.abs(divergence(crack.stress, x)).max() < 1e-6 * 2e6
    remote = crack.remote_stress() if far_field else np.zeros((2, 2))
    far = crack.stress(np.array([[3e5], [4e5]]))[..., 0]
    np.testing.assert_allclose(far, remote, atol=1e-5 * 2e6)
    d = np.asarray(crack.direction)
    n = np.array([-d[1], d[0]])
    faces = np.asarray(crack.center)[:, None] + d[:, None] * np.linspace(-0.69, 0.69, 9)
    S11, S22, S12 = crack.remote
    loaded = np.zeros(2) if far_field else np.array(to_global_vector((S12, S22), crack.frame))
    for side, normal in ((1, -n), (-1, n)):  # the body's outward normal on each face
        t = crack.traction(faces, normal, side=side)
        np.testing.assert_allclose(t, side * loaded[:, None] + 0 * t, atol=1e-9 * 2e6)


def test_griffith_crack_tends_to_williams_at_its_tips():
    crack = GriffithCrack.uniaxial(0.7, 2e6, 0.6, center=(0.1, 0.2), direction=(1.0, 0.5))
    K_I, K_II = crack.stress_intensity_factors
    assert K_I == pytest.approx(2e6 * math.sin(0.6) ** 2 * math.sqrt(math.pi * 0.7), rel=1e-14)
    assert K_II == pytest.approx(2e6 * math.sin(0.6) * math.cos(0.6) * math.sqrt(math.pi * 0.7))
    theta = np.linspace(-3.0, 3.0, 13)
    for tip in crack.tips:
        errors = []
        for r in (1e-3, 1e-5):
            x = polar_points(tip, r, theta)
            near = WilliamsField(TipFrame(*tip), K_I, K_II, E, NU).stress(x)
            errors.append(np.abs(crack.stress(x) - near).max() / np.abs(near).max())
        assert errors[1] < 3e-3 and errors[1] < errors[0] / 8  # sqrt(r): T-stress and beyond


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="direction must be a non-zero"):
        tip_frame((0, 0), (0, 0))
    with pytest.raises(ValueError, match="origin must be two finite"):
        tip_frame((0, np.nan), (1, 0))
    with pytest.raises(ValueError, match="plane must be one of"):
        WilliamsField(FRAME, 1.0, 0.0, E, NU, "membrane")
    with pytest.raises(ValueError, match="side must be"):
        branch_functions(points(), FRAME, side=2)
    with pytest.raises(ValueError, match="a .half length"):
        GriffithCrack(-1.0, (0.0, 1.0, 0.0))
    with pytest.raises(ValueError, match="remote must be three"):
        GriffithCrack(1.0, (0.0, 1.0))
