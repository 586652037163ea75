"""Hexahedra cut by Q1/Q2 level sets (Saye's rules): exact moments for planes in any position
(tests/cut3d_reference.py), a trilinear level set against a fine reference, a sphere's volume
and area converging at rate >= 3.8, refusals."""

import basix
import numpy as np
import pytest
from cut3d_reference import box_edges, box_planes, box_vertices, clip, exponents, simplex_moments

from xfem_contact.geometry.tensor_levelset import coefficients
from xfem_contact.quadrature.saye import classify_hexes, hex_cut_rules, saye_points

EXPS = exponents(4)
UNIT = box_planes((0, 0, 0), (1, 1, 1)), box_vertices((0, 0, 0), (1, 1, 1)), box_edges()


def nodes(degree: int) -> np.ndarray:
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, degree, basix.LagrangeVariant.gll_warped
    )
    return element.points


def moments(rule, row, x_of=lambda X: X, scale=1.0):
    lo, hi = rule.offsets[row], rule.offsets[row + 1]
    x = x_of(rule.points[lo:hi])
    f = np.array([x[:, 0] ** a * x[:, 1] ** b * x[:, 2] ** c for a, b, c in EXPS])
    return f @ (rule.weights[lo:hi] * scale)


def check_planes(normals, offsets, degree, h=(1.0, 1.0, 1.0), tol=1e-13):
    """Planes ``n.X = c`` in the box ``[0, h]`` (reference ``X`` in the unit cube)."""
    h = np.asarray(h)
    phi = np.array([nodes(degree) @ n - c for n, c in zip(normals, offsets, strict=True)])
    J = np.broadcast_to(np.diag(h), (len(phi), 3, 3))
    rules = hex_cut_rules(phi, degree, 4, jacobian=lambda rows, X: J[rows])
    side = classify_hexes(phi, degree)
    planes, vertices, edges = box_planes((0, 0, 0), h), box_vertices((0, 0, 0), h), box_edges()
    for row, (n, c) in enumerate(zip(normals, offsets, strict=True)):
        g = np.asarray(n) / h  # the plane in physical coordinates x = h X
        minus, face = clip(planes, vertices, edges, (g, -c), -1)
        plus, _ = clip(planes, vertices, edges, (g, -c), +1)
        exact = [simplex_moments(t, EXPS) for t in (minus, plus, face)]
        got = [
            moments(r, row, lambda X: X * h, h.prod())
            for r in (rules.minus, rules.plus, rules.interface)
        ]
        for name, g_, e in zip(("minus", "plus", "interface"), got, exact, strict=True):
            assert np.abs(g_ - e).max() <= tol * max(1.0, np.abs(e).max()), (name, n, c, g_ - e)
        total = sum(
            r.weights[r.offsets[row] : r.offsets[row + 1]].sum() for r in (rules.minus, rules.plus)
        )
        assert abs(total - 1.0) <= 1e-14
        gamma = rules.interface
        normals = gamma.normals[gamma.offsets[row] : gamma.offsets[row + 1]]
        np.testing.assert_allclose(
            normals, np.broadcast_to(g / np.linalg.norm(g), normals.shape), atol=1e-13
        )
        if side[row] == -1:  # a certificate: sound, not complete (0 = possibly cut)
            assert exact[1][0] == 0 and exact[2][0] == 0
        if side[row] == 1:
            assert exact[0][0] == 0
    for r in (rules.minus, rules.plus, rules.interface):
        assert (r.weights > 0).all()
    assert rules.reduced.size == 0


@pytest.mark.parametrize("degree", [1, 2])
def test_random_planes(degree):
    rng = np.random.default_rng(10 + degree)
    normals = rng.normal(size=(30, 3))
    offsets = np.einsum("ij,ij->i", normals, rng.uniform(0.1, 0.9, size=(30, 3)))
    check_planes(normals, offsets, degree)
    check_planes(normals, offsets, degree, h=(0.5, 2.0, 1.5))


@pytest.mark.parametrize("degree", [1, 2])
def test_degenerate_planes(degree):
    """Through a vertex, along an edge, along a face diagonal, through four vertices, on a
    face (either side), touching at a vertex or an edge only."""
    cases = [
        ((1.0, 1.0, 1.0), 1.0),  # through three vertices
        ((1.0, 2.0, 3.0), 0.0),  # touching at the origin, cell on +1
        ((-1.0, -2.0, -3.0), 0.0),  # touching at the origin, cell on -1
        ((1.0, 1.0, 0.0), 1.0),  # along the face diagonals through (1,0,z), (0,1,z)
        ((1.0, -1.0, 0.0), 0.0),  # through four vertices (x = y)
        ((1.0, 1.0, 0.0), 2.0),  # touching along the edge x = y = 1, cell on -1
        ((1.0, 1.0, 0.0), 0.0),  # touching along the edge x = y = 0, cell on +1
        ((1.0, 0.0, 0.0), 1.0),  # on the face x = 1, cell on -1: the face is interface
        ((1.0, 0.0, 0.0), 0.0),  # on the face x = 0, cell on +1: no interface
        ((0.0, 1.0, 0.0), 0.5),  # axis-aligned through the middle
        ((2.0, 1.0, 1.0), 1.0),  # through a vertex and two edge midpoints
        ((1.0, 1.0, 1.0), 1.5),  # through the centre, hexagonal section
    ]
    normals, offsets = zip(*cases, strict=True)
    check_planes(normals, offsets, degree)


def test_trilinear_level_set_against_a_fine_reference():
    """psi = z - g(x, y), g bilinear: side -1 is under the clipped height g."""
    corners = nodes(1)
    g = lambda x, y: 0.2 + 0.9 * x - 0.5 * y + 0.6 * x * y  # noqa: E731
    phi = (corners[:, 2] - g(corners[:, 0], corners[:, 1]))[None]
    rules = hex_cut_rules(phi, 1, 6)
    m = 1000
    x, w = np.polynomial.legendre.leggauss(3)
    x, w = 0.5 * (x + 1) / m, 0.5 * w / m
    s = (np.arange(m)[:, None] / m + x).reshape(-1)
    ws = np.tile(w, m)
    height = np.clip(g(s[:, None], s[None, :]), 0.0, 1.0)
    reference = ws @ height @ ws
    assert abs(rules.minus.weights.sum() - reference) <= 2e-7
    assert abs(rules.minus.weights.sum() + rules.plus.weights.sum() - 1.0) <= 1e-14


def sphere(
    n: int, degree: int = 2, centre=(0.5, 0.5, 0.5), radius: float = 0.3, quadric: bool = False
) -> tuple[float, float]:
    """Relative errors of the volume and area of a sphere in the unit cube (by its signed
    distance, or with ``quadric`` by ``|x - c|^2 - R^2``, which Q2 interpolates exactly)."""
    h = 1.0 / n
    origins = np.stack(np.meshgrid(*[np.arange(n) * h] * 3, indexing="ij"), -1).reshape(-1, 3)
    x = origins[:, None] + h * nodes(degree)[None]
    arm = x - np.asarray(centre)
    phi = (arm**2).sum(axis=-1) - radius**2 if quadric else np.linalg.norm(arm, axis=-1) - radius
    side = classify_hexes(phi, degree)
    cut = np.flatnonzero(side == 0)
    J = h * np.eye(3)
    rules = hex_cut_rules(
        phi[cut], degree, 4, jacobian=lambda rows, X: np.broadcast_to(J, (rows.size, 3, 3))
    )
    volume = ((side == -1).sum() + rules.minus.weights.sum()) * h**3
    area = rules.interface.weights.sum() * h**3
    exact_v, exact_a = 4 / 3 * np.pi * radius**3, 4 * np.pi * radius**2
    return abs(volume - exact_v) / exact_v, abs(area - exact_a) / exact_a


@pytest.mark.parametrize(
    "centre, radius", [((0.3351, 0.458, 0.6494), 0.1708), ((0.6501, 0.6767, 0.4047), 0.1018)]
)
def test_shallow_slopes_are_subdivided(centre, radius):
    """Spheres of 0.4 to 0.7 cells (h = 1/4; two of bench/robustness3d.py's, exact
    quadrics): boxes whose certified slopes score below ``MIN_SLOPE`` are subdivided,
    where Gauss rules along steep roots converge slowly (area errors 5.3e-4 and 2.2e-4 at
    a threshold of 0.2)."""
    errors = sphere(4, centre=centre, radius=radius, quadric=True)
    print(f"quadric sphere {centre}, R = {radius}: volume {errors[0]:.2e}, area {errors[1]:.2e}")
    assert errors[0] <= 1e-6 and errors[1] <= 1e-5


def test_sphere_q2_converges_at_rate_4():
    sizes = [4, 8, 16, 32]
    errors = np.array([sphere(n) for n in sizes])
    rates = np.log(errors[:-1] / errors[1:]) / np.log(2)
    for n, (ev, ea), r in zip(sizes, errors, [(np.nan, np.nan), *rates], strict=True):
        print(f"h = 1/{n}: volume {ev:.3e} (rate {r[0]:.2f}), area {ea:.3e} (rate {r[1]:.2f})")
    assert (rates[-1] >= 3.8).all(), rates
    # at or below the isoparametric peer on hexes: 5.5e-5 (1/16), 3.7e-6 (1/32)
    assert errors[2, 0] <= 5.5e-5 and errors[3, 0] <= 3.7e-6


def test_round_off_does_not_change_the_rules():
    """Spheres centred on the cube's diagonal (or its x = y plane) give axis choices of
    equal scores; a few ulps of change in the level set's coefficients (as a different
    cell numbering gives) must keep the chosen axes, hence the rules to round-off."""
    rng = np.random.default_rng(1)
    a, b = rng.uniform(-0.8, 1.8, size=(2, 200))
    centres = np.stack([a, a, np.where(np.arange(200) % 2, a, b)], axis=1)
    radii = rng.uniform(0.2, 1.5, size=200)
    phi = np.linalg.norm(nodes(2)[None] - centres[:, None], axis=2) - radii[:, None]
    phi = phi[classify_hexes(phi, 2) == 0]
    C = coefficients(phi, 2)
    ulps = rng.integers(-4, 5, size=C.shape) * np.finfo(float).eps
    rules, moved = saye_points(C, 3), saye_points(C * (1.0 + ulps), 3)
    for side in ("minus", "plus", "interface"):
        ours, theirs = getattr(rules, side), getattr(moved, side)
        assert np.array_equal(ours[0], theirs[0]), side  # the same points per cell
        for column, other in zip(ours[1:], theirs[1:], strict=True):
            np.testing.assert_allclose(column, other, rtol=0, atol=1e-12, err_msg=side)


def test_singular_point_refused():
    x = nodes(2)
    phi = ((x[:, 0] - 0.5) ** 2 + (x[:, 1] - 0.5) ** 2 - (x[:, 2] - 0.5) ** 2)[None]
    with pytest.raises(ValueError, match="hexahedron 0: the level set has a singular point"):
        hex_cut_rules(phi, 2, 2, max_depth=3)


@pytest.mark.parametrize(
    "args, match",
    [
        ((np.zeros((2, 8)), 3), "degree must be 1 or 2"),
        ((np.zeros((2, 27)), 1), r"shape \(ncells, 8\) for a Q1"),
        ((np.full((1, 8), np.nan), 1), "hexahedron 0 are not finite"),
    ],
)
def test_bad_input(args, match):
    with pytest.raises(ValueError, match=match):
        hex_cut_rules(*args)


def test_bad_order():
    with pytest.raises(ValueError, match="order must be a positive int"):
        hex_cut_rules(np.ones((1, 8)), 1, 0)
