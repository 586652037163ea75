"""Tetrahedra cut by P1 level sets: moments of both sides and of the interface against
exact references (tests/cut3d_reference.py), degenerate positions, bad input."""

import itertools

import numpy as np
import pytest
from cut3d_reference import TET_EDGES, clip, exponents, simplex_moments, tet_planes

from xfem_contact.geometry.cut_tets import REFERENCE_TET, classify_tets, cut_tets
from xfem_contact.quadrature.cut_tet_rules import tet_interface_rule, tet_side_rules

EXPS = exponents(4)


def monomials(x: np.ndarray) -> np.ndarray:
    """``x^a y^b z^c`` at points ``(N, 3)``, shape ``(len(EXPS), N)``."""
    return np.array([x[:, 0] ** a * x[:, 1] ** b * x[:, 2] ** c for a, b, c in EXPS])


def rule_moments(rule, row, x_of=lambda X: X, scale=1.0):
    lo, hi = rule.offsets[row], rule.offsets[row + 1]
    return monomials(x_of(rule.points[lo:hi])) @ (rule.weights[lo:hi] * scale)


def reference(vertices: np.ndarray, phi: np.ndarray):
    """Exact moments (minus, plus, interface) of the tetrahedron ``vertices`` (physical)
    cut by the linear function with vertex values ``phi``."""
    A = np.column_stack([vertices, np.ones(4)])
    coef = np.linalg.solve(A, phi)
    plane = (coef[:3], coef[3])
    minus, face = clip(tet_planes(vertices), vertices, TET_EDGES, plane, -1)
    plus, _ = clip(tet_planes(vertices), vertices, TET_EDGES, plane, +1)
    return simplex_moments(minus, EXPS), simplex_moments(plus, EXPS), simplex_moments(face, EXPS)


def check_cells(phi: np.ndarray, vertices: np.ndarray | None = None, tol: float = 1e-13):
    """Rules of ``cut_tets(phi)`` against the exact moments, cell by cell; ``vertices``
    ``(ncells, 4, 3)`` physical (default: the reference cell)."""
    ncells = phi.shape[0]
    if vertices is None:
        vertices = np.broadcast_to(REFERENCE_TET, (ncells, 4, 3))
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))  # dx/dX
    cut = cut_tets(phi)
    minus, plus = tet_side_rules(cut, -1, 4), tet_side_rules(cut, +1, 4)
    gamma = tet_interface_rule(cut, 4, lambda rows, X: J[rows])
    assert (minus.weights > 0).all() and (plus.weights > 0).all() and (gamma.weights > 0).all()
    side = classify_tets(phi)
    for row in range(ncells):
        detJ = abs(np.linalg.det(J[row]))

        def x_of(X, row=row):
            return vertices[row, 0] + X @ J[row].T

        exact = reference(vertices[row], phi[row])
        got = [rule_moments(r, row, x_of, detJ) for r in (minus, plus, gamma)]
        for name, g, e in zip(("minus", "plus", "interface"), got, exact, strict=True):
            scale = max(1.0, np.abs(e).max())
            assert np.abs(g - e).max() <= tol * scale, (name, phi[row], np.abs(g - e).max())
        volume = minus.weights[minus.offsets[row] : minus.offsets[row + 1]].sum()
        volume += plus.weights[plus.offsets[row] : plus.offsets[row + 1]].sum()
        assert abs(volume - 1.0 / 6.0) <= 1e-14
        has_minus, has_plus = exact[0][0] > 0, exact[1][0] > 0
        expected = 0 if (has_minus and has_plus) or exact[2][0] > 0 else (-1 if has_minus else 1)
        assert side[row] == expected, (phi[row], side[row])
        lo, hi = gamma.offsets[row], gamma.offsets[row + 1]
        if hi > lo:  # normals: unit, towards phi > 0
            grad = np.linalg.solve(np.column_stack([vertices[row], np.ones(4)]), phi[row])[:3]
            n = gamma.normals[lo:hi]
            assert np.allclose(n, grad / np.linalg.norm(grad), atol=1e-13)


def test_random_planes_reference_cell():
    rng = np.random.default_rng(1)
    phi = rng.uniform(-1, 1, size=(60, 4))
    check_cells(phi)


def test_random_planes_physical_cells():
    rng = np.random.default_rng(2)
    vertices = rng.uniform(-1, 2, size=(40, 4, 3))
    phi = rng.uniform(-1, 1, size=(40, 4))
    check_cells(phi, vertices)


def test_every_sign_pattern_with_zeros():
    """All patterns in {-, 0, +}^4 but four zeros: the plane through a vertex, along an edge,
    on a face, touching at a vertex or an edge, with random magnitudes."""
    rng = np.random.default_rng(3)
    patterns = np.array([p for p in itertools.product((-1, 0, 1), repeat=4) if any(p)])
    phi = patterns * rng.uniform(0.2, 1.5, size=patterns.shape)
    vertices = rng.uniform(-1, 2, size=(len(phi), 4, 3))
    check_cells(phi)
    check_cells(phi, vertices)


def test_face_is_an_interface_piece_of_the_negative_cell_only():
    cut = cut_tets([[-1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])
    assert cut.tri_cell.tolist() == [0]
    np.testing.assert_array_equal(np.sort(cut.tri[0], axis=0), np.sort(REFERENCE_TET[1:], axis=0))
    assert classify_tets([[-1.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]]).tolist() == [0, 1]


def test_near_degenerate_values_give_tiny_positive_sub_cells():
    phi = np.array([[-1.0, 1e-300, 1.0, 2.0], [-1.0, -1e-17, 1e-17, 1.0]])
    check_cells(phi)


@pytest.mark.parametrize(
    "phi, match",
    [
        (np.zeros((2, 3)), r"shape \(ncells, 4\)"),
        ([[0.0, 1.0, np.nan, 2.0]], "tetrahedron 0 are not finite"),
        ([[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0]], "all four vertices of tetrahedron 1"),
    ],
)
def test_bad_input(phi, match):
    with pytest.raises(ValueError, match=match):
        cut_tets(phi)


def test_half_space_in_a_structured_tet_mesh():
    """Volume of ``n.x < c`` and area of its section in the unit cube (n = 5, six tets per
    cube), against inclusion-exclusion formulas; ``c = 0.8`` passes through mesh vertices."""
    dolfinx = pytest.importorskip("dolfinx")
    from mpi4py import MPI

    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, 5, 5, 5, dolfinx.mesh.CellType.tetrahedron)
    x = mesh.geometry.x
    vertices = x[mesh.geometry.dofmaps[0]][:, :4]  # P1 geometry: the vertices, Basix order
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))
    detJ = np.abs(np.linalg.det(J))
    corners = np.array(list(itertools.product((0, 1), repeat=3)), dtype=float)
    for n, c in [((1.0, 1.0, 1.0), 0.8), ((1.0, 1.0, 1.0), 0.77), ((0.3, 0.5, 0.9), 0.71)]:
        n = np.asarray(n)
        phi = vertices @ n - c
        cut = cut_tets(phi)
        minus = tet_side_rules(cut, -1, 1)
        gamma = tet_interface_rule(cut, 1, lambda rows, X: J[rows])
        volume = (minus.weights * detJ[minus.point_rows]).sum()
        area = (gamma.weights * detJ[gamma.point_rows]).sum()
        s = np.maximum(c - corners @ n, 0.0)
        sign = (-1.0) ** corners.sum(axis=1)
        exact_volume = (sign * s**3).sum() / (6 * n.prod())
        exact_area = np.linalg.norm(n) * (sign * s**2).sum() / (2 * n.prod())
        assert abs(volume - exact_volume) <= 1e-14, (n, c, volume - exact_volume)
        assert abs(area - exact_area) <= 1e-13, (n, c, area - exact_area)
