"""Tetrahedra cut by P2 level sets (Saye's rules on truncated boxes of the tetrahedron, or
on its four hexahedra): planes exact in the tetrahedron's frame and converging in the
hexahedra's, the rules' error on an exactly represented sphere, a sphere's volume and
area at rate >= 3.8, refusals."""

import basix
import numpy as np
import pytest
from cut3d_reference import (
    TET_EDGES,
    clip,
    exponents,
    simplex_moments,
    sphere_area_in_polytope,
    tet_planes,
    torus_area_in_polytope,
)

from xfem_contact.geometry.tensor_levelset import bernstein, coefficients
from xfem_contact.quadrature.curved_tet_rules import (
    HEXAHEDRA,
    _cube_coefficients,
    classify_p2_tets,
    hexahedron_map,
    p2_tet_cut_rules,
)
from xfem_contact.quadrature.saye import certified_sides

EXPS = exponents(4)
REFERENCE = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def nodes() -> np.ndarray:
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    return element.points


def moments(rule, row):
    lo, hi = rule.offsets[row], rule.offsets[row + 1]
    x = rule.points[lo:hi]
    f = np.array([x[:, 0] ** a * x[:, 1] ** b * x[:, 2] ** c for a, b, c in EXPS])
    return f @ rule.weights[lo:hi]


def test_the_four_hexahedra_fill_the_tetrahedron_with_positive_jacobians():
    """det dM is Q2 on the cube: its Bernstein coefficients certify its sign everywhere."""
    q2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, 2, basix.LagrangeVariant.gll_warped
    ).points
    x, w = np.polynomial.legendre.leggauss(3)
    x, w = 0.5 * (x + 1), 0.5 * w
    grid = np.stack(np.meshgrid(x, x, x, indexing="ij"), -1).reshape(-1, 3)
    weights = np.einsum("i,j,k->ijk", w, w, w).reshape(-1)
    total = 0.0
    for k in range(len(HEXAHEDRA)):
        det = np.linalg.det(hexahedron_map(q2, k)[1])[None]
        B = bernstein(coefficients(det, 2), np.zeros((1, 3)), np.ones((1, 3)))
        assert B.min() > 0.009
        total += np.linalg.det(hexahedron_map(grid, k)[1]) @ weights
    assert abs(total - 1.0 / 6.0) <= 1e-15


@pytest.mark.parametrize(
    "order, min_depth, tol", [(4, 0, 3e-6), (4, 1, 1e-7), (6, 1, 1e-10), (12, 0, 1e-13)]
)
def test_planes_converge_to_exact_moments(order, min_depth, tol):
    """On the hexahedra the composed level set is not planar: the rules converge in the
    order and in the box size (min_depth), never exactly (the error does not shrink with
    the mesh size)."""
    rng = np.random.default_rng(5)
    normals = rng.normal(size=(12, 3))
    offsets = np.einsum("ij,ij->i", normals, rng.dirichlet(np.ones(4), size=12)[:, 1:])
    phi = normals @ nodes().T - offsets[:, None]
    rules = p2_tet_cut_rules(phi, order, min_depth=min_depth, frame="hexahedra")
    for row, (n, c) in enumerate(zip(normals, offsets, strict=True)):
        minus, face = clip(tet_planes(REFERENCE), REFERENCE, TET_EDGES, (n, -c), -1)
        plus, _ = clip(tet_planes(REFERENCE), REFERENCE, TET_EDGES, (n, -c), +1)
        for rule, cells in ((rules.minus, minus), (rules.plus, plus), (rules.interface, face)):
            exact = simplex_moments(cells, EXPS)
            assert np.abs(moments(rule, row) - exact).max() <= tol, (order, n, c)
        gamma = rules.interface
        normals = gamma.normals[gamma.offsets[row] : gamma.offsets[row + 1]]
        np.testing.assert_allclose(
            normals, np.broadcast_to(n / np.linalg.norm(n), normals.shape), atol=1e-12
        )
        volume = sum(moments(r, row)[0] for r in (rules.minus, rules.plus))
        assert abs(volume - 1.0 / 6.0) <= 1e-14
    for rule in (rules.minus, rules.plus, rules.interface):
        assert (rule.weights > 0).all()


def planes(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Random planes ``n . x = c`` through the reference tetrahedron."""
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(count, 3))
    offsets = np.einsum("ij,ij->i", normals, rng.dirichlet(np.ones(4), size=count)[:, 1:])
    return normals, offsets


@pytest.mark.parametrize("min_depth", [0, 1])
def test_planes_are_exact_in_the_tetrahedron_frame(min_depth):
    """Truncated boxes of the tetrahedron keep every breakpoint affine: four points per
    interval integrate the moments of degree 4 exactly (nested, the outer integrand has
    degree 6; the hexahedra's rules miss them by 1.8e-5 at this order)."""
    normals, offsets = planes(40, 7)
    phi = normals @ nodes().T - offsets[:, None]
    rules = p2_tet_cut_rules(phi, 4, min_depth=min_depth)
    worst = 0.0
    for row, (n, c) in enumerate(zip(normals, offsets, strict=True)):
        minus, face = clip(tet_planes(REFERENCE), REFERENCE, TET_EDGES, (n, -c), -1)
        plus, _ = clip(tet_planes(REFERENCE), REFERENCE, TET_EDGES, (n, -c), +1)
        for rule, cells in ((rules.minus, minus), (rules.plus, plus), (rules.interface, face)):
            worst = max(worst, np.abs(moments(rule, row) - simplex_moments(cells, EXPS)).max())
    print(f"planes, order 4, min_depth {min_depth}: largest moment error {worst:.1e}")
    assert worst <= 1e-14
    for rule in (rules.minus, rules.plus, rules.interface):
        assert (rule.weights > 0).all()


def test_frame_is_checked():
    with pytest.raises(ValueError, match=r"frame must be one of \('tetrahedron', 'hexahedra'\)"):
        p2_tet_cut_rules(nodes()[:, :1].T - 0.5, frame="cube")


KUHN = np.array(
    [
        [(0, 0, 0), (1, 0, 0), (1, 1, 0), (1, 1, 1)],
        [(0, 0, 0), (1, 0, 0), (1, 0, 1), (1, 1, 1)],
        [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 1, 1)],
        [(0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1)],
        [(0, 0, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1)],
        [(0, 0, 0), (0, 0, 1), (0, 1, 1), (1, 1, 1)],
    ],
    dtype=float,
)


def sphere(n: int, level_set=None, centre=(0.5, 0.5, 0.5), radius=0.3, frame="tetrahedron"):
    """Signed relative volume and area errors of the sphere of ``radius`` about ``centre``
    (P2 interpolant of ``level_set``, by default the distance) on the ``6 n^3`` tetrahedra
    of the unit cube, with Saye's rules in ``frame``."""
    if level_set is None:
        level_set = lambda x: np.linalg.norm(x - np.asarray(centre), axis=-1) - radius  # noqa: E731
    exact = (4 / 3 * np.pi * radius**3, 4 * np.pi * radius**2)
    return surface_errors(n, level_set, exact, frame=frame)


def surface_errors(n: int, level_set, exact, **options):
    """Signed relative volume and area errors of the zero set of ``level_set`` (its P2
    interpolant) on the ``6 n^3`` tetrahedra of the unit cube against ``exact`` (volume,
    area), with ``p2_tet_cut_rules(..., 4, **options)``."""
    h = 1.0 / n
    origins = np.stack(np.meshgrid(*[np.arange(n) * h] * 3, indexing="ij"), -1).reshape(-1, 3)
    vertices = (origins[:, None, None] + h * KUHN[None]).reshape(-1, 4, 3)
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))
    detJ = np.abs(np.linalg.det(J))
    x = vertices[:, :1] + np.einsum("qk,ndk->nqd", nodes(), J)
    phi = level_set(x)
    side = classify_p2_tets(phi)
    cut = np.flatnonzero(side == 0)
    rules = p2_tet_cut_rules(phi[cut], 4, jacobian=lambda rows, X: J[cut[rows]], **options)
    volume = detJ[side == -1].sum() / 6 + rules.minus.weights @ detJ[cut[rules.minus.point_rows]]
    area = rules.interface.weights @ detJ[cut[rules.interface.point_rows]]
    exact_v, exact_a = exact
    return (volume - exact_v) / exact_v, (area - exact_a) / exact_a


def ellipsoid_area(axes, m: int = 200) -> float:
    """Area of the ellipsoid with semi-axes ``axes``: Gauss-Legendre in ``cos theta`` times
    the trapezoidal rule in ``phi``, both spectral for this analytic periodic integrand."""
    a, b, c = axes
    t, wt = np.polynomial.legendre.leggauss(m)
    T, P = np.meshgrid(t, np.arange(2 * m) * np.pi / m, indexing="ij")
    s2 = 1.0 - T**2
    f = np.sqrt((b * c) ** 2 * s2 * np.cos(P) ** 2 + (a * c) ** 2 * s2 * np.sin(P) ** 2)
    f = np.sqrt(f**2 + (a * b * T) ** 2)
    return float(wt @ f.sum(axis=1) * np.pi / m)


def test_exact_quadric_sphere():
    """|x - c|^2 - R^2 is P2: the geometry is exact and only the rules err."""
    errors = sphere(4, lambda x: ((x - 0.5) ** 2).sum(axis=-1) - 0.09)
    print(f"quadric sphere, h = 1/4, order 4: volume {errors[0]:.2e}, area {errors[1]:.2e}")
    assert abs(errors[0]) <= 1e-6 and abs(errors[1]) <= 3e-5


def quadric(x):
    return ((x - 0.5) ** 2).sum(axis=-1) - 0.09


def test_rule_error_on_the_exact_quadric_sphere_stays_small():
    """The P2 sphere at h = 1/8 and 1/16: only the rules err. In the tetrahedron's frame
    their relative area error is 1.5e-8 and 1.0e-8 (1.3e-8 and 1.7e-7 with
    ``raise_tolerance=None``); on the hexahedra (the same order)
    5.6e-7 and 2.2e-7, and it rises to 3.2e-6 at h = 1/32. Both frames' errors depend on
    which of two tied axis choices a symmetric box takes (:mod:`saye_axes` breaks ties
    alike under round-off): at h = 1/16 the tetrahedron's frame gives 1.3e-8 with the
    other choice."""
    errors = np.abs(np.array([sphere(n, quadric) for n in (8, 16)]))
    print(f"quadric sphere, order 4: volume {errors[:, 0]}, area {errors[:, 1]}")
    assert errors[0].max() <= 1e-7 and errors[1].max() <= 2e-7


@pytest.mark.parametrize("centre", [(0.5, 0.5, 0.5), (0.513, 0.472, 0.538)])
def test_curved_boxes_get_raised_orders(centre):
    """The ellipsoid with semi-axes 0.35, 0.25, 0.15 as the quadric
    ``|(x - c) / a|^2 - 1`` (P2: only the rules err) at h = 1/6, where its curvature
    (up to 15.6) makes ``h kappa`` 2.6. Boxes whose rules move between 3 and 4 points per
    interval get 8 (``raise_tolerance``): area errors 1.2e-6 and 3.0e-8, against 1.8e-5
    and 3.3e-6 with 4 points everywhere (``raise_tolerance=None``)."""
    axes, c = np.array([0.35, 0.25, 0.15]), np.asarray(centre)
    exact = (4 / 3 * np.pi * axes.prod(), ellipsoid_area(axes))
    errors = surface_errors(6, lambda x: (((x - c) / axes) ** 2).sum(axis=-1) - 1.0, exact)
    print(
        f"quadric ellipsoid about {centre}, h = 1/6: volume {errors[0]:.2e}, area {errors[1]:.2e}"
    )
    assert abs(errors[0]) <= 1e-8 and abs(errors[1]) <= 2e-6


@pytest.mark.parametrize(
    "corner, kuhn",
    [
        ((21, 21, 9), [(0, 0, 0), (1, 0, 0), (1, 0, 1), (1, 1, 1)]),
        ((22, 21, 10), [(0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1)]),
    ],
)
def test_raised_orders_follow_the_cell_size(corner, kuhn):
    """Two cut tetrahedra of h = 1/32 (Kuhn cubes of bench/cut3d.py's mesh) on the exact
    zero set of the sphere R = 0.3 about its first shifted centre, against Gauss-Bonnet.
    A fixed tolerance of 1e-6 reference units let area errors of 2.5e-7 and 2.4e-7 of
    the cells' through (summed over the cut cells, a floor of the surface's relative
    error); the tolerance of ``raise_tolerances``, which falls as ``(h kappa)^3`` on
    cells finer than ``h kappa = 1/2``, leaves 1.2e-9 and 2.7e-9."""
    vertices = (np.array(corner) + np.array(kuhn)) / 32.0
    centre, radius = np.array([0.51990505, 0.50843083, 0.50128042]), 0.3
    J = (vertices[1:] - vertices[0]).T

    def exact(rows, X):
        return np.linalg.norm(vertices[0] + X @ J.T - centre, axis=1) - radius

    phi = exact(np.zeros(10, dtype=int), nodes())[None]
    rules = p2_tet_cut_rules(
        phi, 4, jacobian=lambda rows, X: np.broadcast_to(J, (rows.size, 3, 3)), exact=exact
    )
    area = rules.interface.weights.sum() * abs(np.linalg.det(J))
    expected = sphere_area_in_polytope(centre, radius, tet_planes(vertices))
    print(f"area error {area / expected - 1:.2e} of the cell's")
    assert abs(area / expected - 1.0) <= 2e-8


@pytest.mark.parametrize("raise_tolerance", [1e-6, 1e-8])
def test_boxes_at_the_last_depth_keep_the_margin(raise_tolerance):
    """A cut tetrahedron of h = 1/32 (bench/cut3d.py's mesh) on the exact zero set of the
    torus R = 0.3, r = 0.12 about its eighth shifted centre, against the parametric
    reference. Tighter tolerances subdivide raised boxes down to the last depth, where
    boxes certified on one side by the interpolant alone (without the margin of
    ``exact_margin``) dropped a lens of the exact zero set: -4.9e-3 of the cell's area
    with 1e-8 (3.8e-6 now, the reference's own error is a few 1e-6)."""
    vertices = np.array([(28, 16, 13), (28, 16, 14), (29, 16, 14), (29, 17, 14)]) / 32.0
    centre = np.array([0.50388385, 0.52095701, 0.52022467])
    big, small = 0.3, 0.12
    J = (vertices[1:] - vertices[0]).T

    def exact(rows, X):
        y = vertices[0] + X @ J.T - centre
        rho2, z2 = y[:, 0] ** 2 + y[:, 1] ** 2, y[:, 2] ** 2
        return ((rho2 + z2 + big**2 - small**2) ** 2 - 4 * big**2 * rho2) / (4 * big**2)

    phi = exact(np.zeros(10, dtype=int), nodes())[None]
    rules = p2_tet_cut_rules(
        phi,
        4,
        raise_tolerance=raise_tolerance,
        jacobian=lambda rows, X: np.broadcast_to(J, (rows.size, 3, 3)),
        exact=exact,
    )
    area = rules.interface.weights.sum() * abs(np.linalg.det(J))
    expected = torus_area_in_polytope(centre, (big, small), tet_planes(vertices))
    print(f"area error {area / expected - 1:.2e} of the cell's")
    assert abs(area / expected - 1.0) <= 1e-5


@pytest.mark.parametrize("frame", ["tetrahedron", "hexahedra"])
@pytest.mark.parametrize(
    "centre, radius", [((0.581, 0.678, 0.351), 0.2298), ((0.389, 0.603, 0.347), 0.1375)]
)
def test_shallow_slopes_are_subdivided(centre, radius, frame):
    """Spheres of about one cell (h = 1/4; two of bench/robustness3d.py's): the boxes
    whose certified slopes are shallow are subdivided (``MIN_SLOPE``), where Gauss rules
    along steep roots converged slowly (area errors 5.7e-4 and 3.5e-4 without)."""
    c = np.asarray(centre)
    errors = sphere(4, lambda x: ((x - c) ** 2).sum(axis=-1) - radius**2, centre, radius, frame)
    print(f"quadric sphere {centre}, R = {radius}: volume {errors[0]:.2e}, area {errors[1]:.2e}")
    assert abs(errors[0]) <= 1e-5 and abs(errors[1]) <= 2e-5


def test_sphere_p2():
    errors = np.abs(np.array([sphere(n) for n in (8, 16)]))
    rates = np.log(errors[0] / errors[1]) / np.log(2)
    print(f"h = 1/8: {errors[0]}, h = 1/16: {errors[1]}, rates {rates}")
    # the isoparametric peer on (unstructured) tetrahedra at h = 1/16: 1.7e-4 / 1.2e-4
    assert errors[1, 0] <= 1.7e-4 and errors[1, 1] <= 1.2e-4
    assert rates[0] >= 3.8  # volume; the area's rate on this mesh is 3.0 (docs/cut3d.md)


@pytest.mark.parametrize("frame", ["hexahedra", "tetrahedron"])
def test_round_off_does_not_change_the_rules(frame):
    """Spheres centred on the line x = y = z are symmetric in the tetrahedron's hexahedra:
    a few ulps of change in the nodal values (as a different cell numbering gives) keep
    the rules to round-off (the same points per cell, at the same places)."""
    rng = np.random.default_rng(2)
    a, radii = rng.uniform(-0.8, 1.5, size=200), rng.uniform(0.2, 1.5, size=200)
    phi = np.linalg.norm(nodes()[None] - a[:, None, None], axis=2) - radii[:, None]
    phi = phi[classify_p2_tets(phi) == 0]
    ulps = rng.integers(-4, 5, size=phi.shape) * np.finfo(float).eps
    rules = p2_tet_cut_rules(phi, 3, frame=frame)
    moved = p2_tet_cut_rules(phi * (1.0 + ulps), 3, frame=frame)
    for side in ("minus", "plus", "interface"):
        ours, theirs = getattr(rules, side), getattr(moved, side)
        assert np.array_equal(ours.offsets, theirs.offsets), side
        np.testing.assert_allclose(ours.points, theirs.points, rtol=0, atol=1e-12)
        np.testing.assert_allclose(ours.weights, theirs.weights, rtol=0, atol=1e-12)


def test_singular_point_refused():
    x = nodes() - 0.2
    phi = (x[:, 0] ** 2 + x[:, 1] ** 2 - x[:, 2] ** 2)[None]
    with pytest.raises(ValueError, match="tetrahedron 0: the level set has a singular point"):
        p2_tet_cut_rules(phi, 2, max_depth=3)
    # the cells go in batches: the message names the row of phi, past the first batch too
    plane = nodes() @ np.array([1.0, 1.0, 1.0]) - 0.5
    many = np.concatenate([np.tile(plane, (2100, 1)), phi])
    with pytest.raises(ValueError, match="tetrahedron 2100: the level set has a singular"):
        p2_tet_cut_rules(many, 2, max_depth=3)


def test_classification_by_the_tetrahedron_agrees_with_the_hexahedra():
    """Bernstein coefficients of the four hexahedra are convex combinations of the
    tetrahedron's: a sign certified on the tetrahedron is certified on them."""
    rng = np.random.default_rng(3)
    phi = rng.normal(size=(20000, 10)) + rng.normal(size=(20000, 1)) * 3.0
    phi[:100, 4:] = 0.0  # zero on edges: P2 Bernstein coefficients 0 and vertex values
    by_hexahedra = certified_sides(_cube_coefficients(phi)).reshape(-1, 4)
    expected = np.where(
        (by_hexahedra == -1).all(axis=1), -1, np.where((by_hexahedra == 1).all(axis=1), 1, 0)
    )
    side = classify_p2_tets(phi)
    assert 0.2 < (side != 0).mean() < 0.9
    np.testing.assert_array_equal(side, expected)


@pytest.mark.parametrize(
    "phi, match",
    [
        (np.zeros((2, 4)), r"shape \(ncells, 10\) for a P2 tetrahedron"),
        (np.full((1, 10), np.inf), "tetrahedron 0 are not finite"),
    ],
)
def test_bad_input(phi, match):
    with pytest.raises(ValueError, match=match):
        p2_tet_cut_rules(phi)


def test_bad_min_depth():
    with pytest.raises(ValueError, match=r"min_depth must be an int in 0 \.\. max_depth = 2"):
        p2_tet_cut_rules(nodes()[:, :1].T - 0.5, min_depth=3, max_depth=2)


def test_no_cell_left_open_and_no_cells():
    """Every cell certified by its own coefficients, and empty input."""
    phi = np.concatenate([np.ones((2, 10)), -np.ones((1, 10))])
    np.testing.assert_array_equal(classify_p2_tets(phi), [1, 1, -1])
    rules = p2_tet_cut_rules(np.zeros((0, 10)))
    assert rules.minus.offsets.tolist() == [0] and rules.interface.points.shape == (0, 3)
    assert rules.reduced.dtype == np.int64 and rules.reduced.size == 0


def test_a_cells_rules_do_not_depend_on_the_batch():
    """Each cell's points and weights are the same, bit for bit, alone or among others
    (partition independence), in both frames."""
    h = 0.25
    origins = np.stack(np.meshgrid(*[np.arange(4) * h] * 3, indexing="ij"), -1).reshape(-1, 3)
    vertices = (origins[:, None, None] + h * KUHN[None]).reshape(-1, 4, 3)
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))
    phi = np.linalg.norm(vertices[:, :1] + np.einsum("qk,ndk->nqd", nodes(), J) - 0.45, axis=-1)
    phi = phi - 0.3
    phi = phi[classify_p2_tets(phi) == 0]
    for frame in ("tetrahedron", "hexahedra"):
        together = p2_tet_cut_rules(phi, frame=frame)
        for row in range(0, phi.shape[0], 7):
            alone = p2_tet_cut_rules(phi[row : row + 1], frame=frame)
            for a, b in zip(
                (together.minus, together.plus, together.interface),
                (alone.minus, alone.plus, alone.interface),
                strict=True,
            ):
                part = slice(a.offsets[row], a.offsets[row + 1])
                np.testing.assert_array_equal(a.points[part], b.points)
                np.testing.assert_array_equal(a.weights[part], b.weights)
