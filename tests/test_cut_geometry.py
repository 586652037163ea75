"""Cut-cell geometry and quadrature (pure numpy): ``xfem_contact.cut`` and
``xfem_contact.quadrature`` against exact references.

References are computed independently here: straight cuts by clipping the
reference cell with the half-plane (shoelace areas, high-order rules on a
straight triangulation for moments); curved P2 geometry by clipping with the
chord plus the parabolic segment between chord and SEG3; circles by the
closed-form area of a disc clipped by a polygon.
"""

from __future__ import annotations

import basix
import numpy as np
import pytest

from xfem_contact import cut, quadrature

CELLS = ["triangle", "quadrilateral"]
DEGREES = [1, 2]
VERTICES = {  # counter-clockwise
    "triangle": np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
    "quadrilateral": np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
}
AREA = {"triangle": 0.5, "quadrilateral": 1.0}


# -- independent references ---------------------------------------------------------------


def nodes(cell: str, degree: int) -> np.ndarray:
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType[cell], degree, basix.LagrangeVariant.gll_warped
    )
    return element.points


def clip(poly: np.ndarray, f) -> np.ndarray:
    """Sutherland-Hodgman: the part of the convex polygon where ``f <= 0``."""
    out = []
    values = f(poly)
    for i in range(len(poly)):
        P, Q, fP, fQ = poly[i], poly[(i + 1) % len(poly)], values[i], values[(i + 1) % len(poly)]
        if fP <= 0:
            out.append(P)
        if (fP < 0 < fQ) or (fQ < 0 < fP):
            out.append(P + fP / (fP - fQ) * (Q - P))
    return np.array(out).reshape(-1, 2)


def shoelace(poly: np.ndarray) -> float:
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def perimeter(poly: np.ndarray) -> float:
    if len(poly) < 2:
        return 0.0
    return float(np.linalg.norm(np.roll(poly, -1, axis=0) - poly, axis=1).sum())


def exponents(degree: int) -> list[tuple[int, int]]:
    return [(i, k - i) for k in range(degree + 1) for i in range(k + 1)]


def polygon_moments(poly: np.ndarray, degree: int) -> np.ndarray:
    """``int x^i y^j`` over a convex polygon, by a high-order rule on a fan."""
    xi, w = basix.make_quadrature(basix.CellType.triangle, 2 * degree + 2)
    total = np.zeros(len(exponents(degree)))
    for k in range(1, len(poly) - 1):
        A, B, C = poly[0], poly[k], poly[k + 1]
        J = np.column_stack([B - A, C - A])
        X = A + xi @ J.T
        dA = abs(np.linalg.det(J)) * w
        total += [np.sum(X[:, 0] ** i * X[:, 1] ** j * dA) for i, j in exponents(degree)]
    return total


def parabolic_segment_moments(seg: np.ndarray, degree: int) -> np.ndarray:
    """Signed moments ``int f 4s(1-s) cross(b - a, m - M) ds dt`` of the region
    between the chord ``a -> b`` and the SEG3 ``(a, b, m)``."""
    a, b, m = seg
    d, delta = b - a, m - 0.5 * (a + b)
    s, ws = np.polynomial.legendre.leggauss(degree + 4)
    s, ws = 0.5 * (s + 1), 0.5 * ws
    S, T = np.meshgrid(s, s, indexing="ij")
    W = np.outer(ws, ws)
    X = a + S[..., None] * d + (T * 4 * S * (1 - S))[..., None] * delta
    jac = 4 * S * (1 - S) * (d[0] * delta[1] - d[1] * delta[0])
    x, y, weight = X[..., 0], X[..., 1], jac * W
    return np.array([np.sum(x**i * y**j * weight) for i, j in exponents(degree)])


def curved_side_moments(cell: str, seg: np.ndarray, side: int, degree: int) -> np.ndarray:
    """Moments of one side of the cell cut by the SEG3 ``(a, b, m)``, side -1 on the
    left of ``a -> b``: chord clip plus (or minus) the parabolic segment."""
    a, b, _ = seg
    d = b - a

    def right_of_chord(X: np.ndarray) -> np.ndarray:  # > 0 on the right of a -> b
        return (X[:, 0] - a[0]) * d[1] - (X[:, 1] - a[1]) * d[0]

    poly = clip(VERTICES[cell], lambda X: side * -right_of_chord(X))
    return polygon_moments(poly, degree) + side * parabolic_segment_moments(seg, degree)


def rule_moments(rules: quadrature.RuleSet, k: int, degree: int) -> np.ndarray:
    lo, hi = rules.offsets[k], rules.offsets[k + 1]
    X, w = rules.points[lo:hi], rules.weights[lo:hi]
    return np.array([np.sum(X[:, 0] ** i * X[:, 1] ** j * w) for i, j in exponents(degree)])


def per_rule(rules: quadrature.RuleSet, values: np.ndarray) -> np.ndarray:
    owner = np.repeat(np.arange(rules.offsets.size - 1), np.diff(rules.offsets))
    return np.bincount(owner, weights=values, minlength=rules.offsets.size - 1)


def identity(rows: np.ndarray, X: np.ndarray) -> np.ndarray:
    return np.broadcast_to(np.eye(2), (len(rows), 2, 2))


def grad_ref(cell: str, degree: int, phi: np.ndarray):
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType[cell], degree, basix.LagrangeVariant.gll_warped
    )

    def grad(rows: np.ndarray, X: np.ndarray) -> np.ndarray:
        tab = element.tabulate(1, X)[1:, :, :, 0]
        return np.einsum("kpi,pi->pk", tab, phi[rows])

    return grad


def disc_in_polygon(poly: np.ndarray, c: np.ndarray, R: float) -> tuple[float, float]:
    """Area and arc length of ``{|x - c| < R}`` inside a convex polygon crossed by
    the circle exactly twice (Green's theorem: polygon part plus circular segment)."""
    inside = np.linalg.norm(poly - c, axis=1) < R
    pts, cross = [], []
    for i in range(len(poly)):
        P, Q = poly[i], poly[(i + 1) % len(poly)]
        if inside[i]:
            pts.append(P)
        d, f = Q - P, P - c
        A, B, C = d @ d, 2 * f @ d, f @ f - R * R
        disc = B * B - 4 * A * C
        if disc > 0:
            for t in sorted([(-B - np.sqrt(disc)) / (2 * A), (-B + np.sqrt(disc)) / (2 * A)]):
                if 0 < t < 1:
                    pts.append(P + t * d)
                    cross.append(len(pts) - 1)
    assert len(cross) == 2
    pts = np.array(pts)
    dtheta = 2 * np.arcsin(np.linalg.norm(pts[cross[0]] - pts[cross[1]]) / (2 * R))
    return shoelace(pts) + 0.5 * R * R * (dtheta - np.sin(dtheta)), R * dtheta


# -- straight level sets -------------------------------------------------------------------

STRAIGHT = {  # phi = a . X + b
    "vertical": ((1.0, 0.0), -0.3),
    "oblique": ((1.0, 1.0), -0.7),
    "shallow": ((-0.5, 1.0), -0.25),
    "steep_reversed": ((-3.0, 1.0), 0.4),
    "diagonal_v0": ((1.0, -1.0), 0.0),
    "anti_diagonal_v1_v2": ((1.0, 1.0), -1.0),
    "vertex_v1_and_edge": ((1.0, 2.0), -1.0),
    "vertex_v2_and_edge": ((2.0, 1.0), -1.0),
    "along_edge_y0": ((0.0, -1.0), 0.0),
    "along_edge_x1": ((1.0, 0.0), -1.0),
    "touch_vertex_v0": ((-1.0, -1.0), 0.0),
    **{f"strip_{e:.0e}": ((1.0, 0.0), -e) for e in 10.0 ** -np.arange(1, 13)},
    **{f"strip_plus_{e:.0e}": ((-1.0, 0.0), e) for e in 10.0 ** -np.arange(1, 13)},
    **{f"corner_{e:.0e}": ((1.0, 1.0), -np.sqrt(2 * e)) for e in 10.0 ** -np.arange(1, 13, 2)},
    **{f"far_{e:.0e}": ((-1.0, -1.0), 1.0 - np.sqrt(2 * e)) for e in 10.0 ** -np.arange(1, 13, 2)},
}


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
@pytest.mark.parametrize("case", list(STRAIGHT))
def test_straight_cut(cell: str, degree: int, case: str):
    a, b = np.array(STRAIGHT[case][0]), STRAIGHT[case][1]
    phi = (nodes(cell, degree) @ a + b)[None]
    level = lambda X: X @ a + b  # noqa: E731
    minus = clip(VERTICES[cell], level)
    plus = clip(VERTICES[cell], lambda X: -level(X))
    side = cut.classify(cell, degree, phi)[0]
    if side != 0:  # uncut: the other side has no area
        assert shoelace(plus if side == -1 else minus) == pytest.approx(0.0, abs=1e-15)
        return
    geom = cut.subtriangulate(cell, degree, phi)
    assert all(np.isfinite(x).all() for x in (geom.tri_minus, geom.tri_plus, geom.seg))
    length = 0.5 * (perimeter(minus) + perimeter(plus) - perimeter(VERTICES[cell]))
    for q in (1, 2, 4, 7):
        for s, poly in ((-1, minus), (1, plus)):
            rules = quadrature.side_rules(geom, s, q, 1)
            exact = shoelace(poly)
            assert rules.weights.sum() == pytest.approx(exact, rel=1e-12, abs=1e-15)
            if exact == 0.0:
                assert rules.weights.size == 0  # the side with no area has no triangles
                continue
            assert (rules.weights >= 0).all()
            assert np.all(s * level(rules.points) >= -1e-15)
            np.testing.assert_allclose(
                rule_moments(rules, 0, q), polygon_moments(poly, q), rtol=1e-12, atol=1e-14
            )
        total = sum(quadrature.side_rules(geom, s, q, 1).weights.sum() for s in (-1, 1))
        assert total == pytest.approx(AREA[cell], abs=1e-14)
        gamma = quadrature.interface_rule(geom, q, 1, identity, grad_ref(cell, degree, phi))
        assert gamma.weights.sum() == pytest.approx(length, abs=1e-14)
        if gamma.weights.size:
            normal = np.tile(a / np.linalg.norm(a), (len(gamma.weights), 1))
            np.testing.assert_allclose(gamma.normals, normal, atol=1e-13)
            np.testing.assert_allclose(level(gamma.points), 0.0, atol=1e-15)


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_tiny_fractions_keep_tiny_triangles(cell: str, degree: int):
    """Cut fractions down to 1e-12: tiny positive triangles stay, relative accuracy."""
    for e in 10.0 ** -np.arange(1, 13):
        phi = (nodes(cell, degree)[:, 0] - e)[None]
        geom = cut.subtriangulate(cell, degree, phi)
        minus = quadrature.side_rules(geom, -1, 3, 1).weights.sum()
        exact = shoelace(clip(VERTICES[cell], lambda X, e=e: X[:, 0] - e))
        assert minus / AREA[cell] == pytest.approx(exact / AREA[cell], rel=1e-12)
        assert exact / AREA[cell] < 2.5 * e


# -- batches: vectorisation over mixed sign patterns ------------------------------------------


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_random_batch(cell: str, degree: int):
    """Random lines and circles in one batch: each side's rule integrates the
    curved P2 geometry exactly, both sides tile the cell, normals point to +1."""
    rng = np.random.default_rng(7)
    n = 150
    X = nodes(cell, degree)
    inner = np.array([0.3, 0.3]) if cell == "triangle" else np.array([0.5, 0.5])
    phi_lines = (X @ rng.normal(size=(2, n)) + rng.uniform(-1, 1, n) - inner @ rng.normal(size=2)).T
    radius = rng.uniform(1.5, 8.0, n)
    angle = rng.uniform(0, 2 * np.pi, n)
    through = rng.uniform(0.1, 0.6, (n, 2)) * (0.6 if cell == "triangle" else 1.0)
    centre = through - radius[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    phi_circles = ((X[None] - centre[:, None]) ** 2).sum(-1) - radius[:, None] ** 2
    phi = np.concatenate([phi_lines, phi_circles])
    ok = np.ones(len(phi), dtype=bool)
    for k in range(len(phi)):  # drop cells with unsupported cuts (tested elsewhere)
        try:
            cut.classify(cell, degree, phi[k : k + 1])
        except ValueError:
            ok[k] = False
    phi = phi[ok]
    rows = np.flatnonzero(cut.classify(cell, degree, phi) == 0)
    assert rows.size > 100
    geom = cut.subtriangulate(cell, degree, phi[rows])
    ncut, q, p = rows.size, 6, 2  # curved P2 sub-triangles: exact for degree p if 2p + 2 <= q
    sides = {s: quadrature.side_rules(geom, s, q, ncut) for s in (-1, 1)}
    total = per_rule(sides[-1], sides[-1].weights) + per_rule(sides[1], sides[1].weights)
    np.testing.assert_allclose(total, AREA[cell], atol=1e-13)
    for s, rules in sides.items():
        assert np.isfinite(rules.points).all() and np.isfinite(rules.weights).all()
        assert np.all(np.diff(rules.offsets) >= 0) and rules.offsets[-1] == len(rules.weights)
        for k in range(ncut):
            exact = curved_side_moments(cell, geom.seg[k], s, p)
            np.testing.assert_allclose(rule_moments(rules, k, p), exact, atol=2e-14)
    gamma = quadrature.interface_rule(geom, 8, ncut, identity, grad_ref(cell, degree, phi[rows]))
    owner = np.repeat(np.arange(ncut), np.diff(gamma.offsets))
    grad = grad_ref(cell, degree, phi[rows])(owner, gamma.points)
    assert np.all((gamma.normals * grad).sum(axis=1) > 0)
    np.testing.assert_allclose(np.linalg.norm(gamma.normals, axis=1), 1.0, atol=1e-14)


# -- circles: a degree-2 level set represented exactly --------------------------------------


@pytest.mark.parametrize("cell", CELLS)
def test_circle_area_and_length_converge(cell: str):
    """A cell of size h on the unit circle: errors of the disc part and the arc
    fall like h^5 per cell (SEG3 approximating the circle) and are < 1e-6 at
    h = 0.2 (reference radius 5)."""
    errors = []
    X = nodes(cell, 2)
    hs = [0.4, 0.2, 0.1, 0.05]
    for h in hs:
        x0 = np.array([np.cos(0.3), np.sin(0.3)]) - h * np.array([0.3, 0.4])
        phi = (((x0 + h * X) ** 2).sum(axis=1) - 1.0)[None]
        assert cut.classify(cell, 2, phi)[0] == 0
        geom = cut.subtriangulate(cell, 2, phi)
        area = quadrature.side_rules(geom, -1, 6, 1).weights.sum() * h * h
        jac = lambda rows, X, h=h: np.broadcast_to(h * np.eye(2), (len(rows), 2, 2))  # noqa: E731
        grad = lambda r, X, x0=x0, h=h: 2 * (x0 + h * X)  # noqa: E731
        gamma = quadrature.interface_rule(geom, 6, 1, jac, grad)
        length = gamma.weights.sum() * h * h  # FFCx's |det J| = h^2
        exact_area, exact_length = disc_in_polygon(x0 + h * VERTICES[cell], np.zeros(2), 1.0)
        errors.append((abs(area - exact_area), abs(length - exact_length)))
        radius = np.linalg.norm(x0 + h * gamma.points, axis=1)
        np.testing.assert_allclose(radius, 1.0, atol=3e-4 * h)
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(orders > 4.5), orders
    assert np.all(errors[1] < 1e-6), errors


@pytest.mark.parametrize("cell", CELLS)
def test_circle_rule_degree(cell: str):
    """The curved P2 side is integrated exactly: area for any degree >= 2 and
    degree-p moments once the rule degree reaches 2p + 2."""
    X = nodes(cell, 2)
    phi = (((X - np.array([-0.2, -0.3])) ** 2).sum(axis=1) - 0.55**2)[None]
    geom = cut.subtriangulate(cell, 2, phi)
    assert not np.allclose(geom.seg[0, 2], 0.5 * (geom.seg[0, 0] + geom.seg[0, 1]))  # curved
    areas = [quadrature.side_rules(geom, -1, q, 1).weights.sum() for q in range(2, 13)]
    np.testing.assert_allclose(areas, areas[0], rtol=1e-14)
    for p in (1, 2, 3):
        for s in (-1, 1):
            rules = quadrature.side_rules(geom, s, 2 * p + 2, 1)
            exact = curved_side_moments(cell, geom.seg[0], s, p)
            np.testing.assert_allclose(rule_moments(rules, 0, p), exact, rtol=1e-13, atol=1e-15)
    # arc length of the SEG3: Gauss-Legendre converges fast in the degree
    grad = grad_ref(cell, 2, phi)
    length = {
        q: quadrature.interface_rule(geom, q, 1, identity, grad).weights.sum()
        for q in (1, 3, 5, 7, 9, 41)
    }
    errors = np.array([abs(length[q] - length[41]) for q in (1, 3, 5, 7, 9)])
    assert np.all(errors[1:] < 0.2 * errors[:-1]) and errors[-1] < 1e-7, errors


@pytest.mark.parametrize("cell", CELLS)
def test_circle_through_two_vertices_lens(cell: str):
    """The circle through v0 = (0, 0) and v1 = (1, 0) bulging into the cell: side -1
    is the lens between edge and SEG3 (a collapsed sub-triangle), of area
    2/3 s and first moment int y = 4 s^2 / 15 for sagitta s."""
    X = nodes(cell, 2)
    phi = (((X - np.array([0.5, -1.0])) ** 2).sum(axis=1) - 1.25)[None]
    assert phi[0, 0] == 0.0 and phi[0, 1] == 0.0
    assert cut.classify(cell, 2, phi)[0] == 0
    geom = cut.subtriangulate(cell, 2, phi)
    sag = np.sqrt(1.25) - 1.0
    # side -1 lies on the left of a -> b along the curve: a = v1, b = v0
    np.testing.assert_allclose(geom.seg[0], [[1.0, 0.0], [0.0, 0.0], [0.5, sag]], atol=1e-15)
    minus = quadrature.side_rules(geom, -1, 6, 1)
    plus = quadrature.side_rules(geom, 1, 6, 1)
    assert minus.weights.sum() == pytest.approx(2 / 3 * sag, rel=1e-14)
    assert np.sum(minus.weights * minus.points[:, 1]) == pytest.approx(4 * sag**2 / 15, rel=1e-13)
    assert plus.weights.sum() == pytest.approx(AREA[cell] - 2 / 3 * sag, rel=1e-14)
    assert (minus.weights >= 0).all() and (plus.weights >= 0).all()


SLIVERS = {  # circles nearly touching an edge: thin sides need the blended fallback
    "quad_folded": ("quadrilateral", (0.75130849, 2.06201005), 2.047530151054075),
    "quad_level2": ("quadrilateral", (-1.55557748, 0.27897986), 2.5285161227021624),
    "quad_folded2": ("quadrilateral", (0.69028036, -1.33478568), 2.333313277245834),
    "tri_folded": ("triangle", (0.89042243, 2.2421034), 2.232463645553705),
    "tri_level1": ("triangle", (2.51936088, 0.48094407), 2.4840945552155267),
}


@pytest.mark.parametrize("case", list(SLIVERS))
def test_thin_side_fallback_is_exact(case: str):
    """A side thinner than the interface's bulge: the blended (possibly least
    folded) construction still integrates the curved P2 side exactly."""
    cell, centre, radius = SLIVERS[case]
    phi = (((nodes(cell, 2) - np.array(centre)) ** 2).sum(axis=1) - radius**2)[None]
    geom = cut.subtriangulate(cell, 2, phi)
    assert geom.tri_plus.shape[0] > 3  # refined fallback, not a plain fan
    total = 0.0
    for s in (-1, 1):
        rules = quadrature.side_rules(geom, s, 6, 1)
        assert np.isfinite(rules.weights).all()
        exact = curved_side_moments(cell, geom.seg[0], s, 2)
        np.testing.assert_allclose(rule_moments(rules, 0, 2), exact, atol=3e-15)
        total += rules.weights.sum()
    assert total == pytest.approx(AREA[cell], abs=1e-14)


def test_circle_through_one_vertex():
    """Interface through vertex v0 of a quadrilateral (zero nodal value) and an edge."""
    X = nodes("quadrilateral", 2)
    centre = np.array([-0.5, 0.75])
    phi = (((X - centre) ** 2).sum(axis=1) - 0.8125)[None]
    assert phi[0, 0] == 0.0
    geom = cut.subtriangulate("quadrilateral", 2, phi)
    assert any(np.array_equal(geom.seg[0, k], [0.0, 0.0]) for k in (0, 1))  # ends at v0
    for s in (-1, 1):
        rules = quadrature.side_rules(geom, s, 6, 1)
        exact = curved_side_moments("quadrilateral", geom.seg[0], s, 2)
        np.testing.assert_allclose(rule_moments(rules, 0, 2), exact, atol=1e-15)
    radius = np.linalg.norm(geom.seg[0] - centre, axis=1)
    np.testing.assert_allclose(radius, np.sqrt(0.8125), atol=1e-15)


# -- exact level-set callable ----------------------------------------------------------------


def grid_cells(cell: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Affine cells of an n x n grid of [0, 1]^2 as origin ``(m, 2)`` and
    Jacobian ``(m, 2, 2)`` (triangles: each square split in two)."""
    h = 1.0 / n
    corners = np.array([[i * h, j * h] for i in range(n) for j in range(n)])
    if cell == "quadrilateral":
        return corners, np.broadcast_to(h * np.eye(2), (len(corners), 2, 2))
    lower = np.broadcast_to(h * np.eye(2), (len(corners), 2, 2))
    upper = np.broadcast_to(h * np.array([[-1.0, 0.0], [0.0, -1.0]]), (len(corners), 2, 2))
    return np.concatenate([corners, corners + h]), np.concatenate([lower, upper])


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_exact_callable_puts_nodes_on_zero_set(cell: str, degree: int):
    """Nodal values of the distance function |x - c| - r (not polynomial): with the
    exact callable, crossings and mid-nodes lie on the circle to 1e-14 (reference
    units); the disc area is then close to pi r^2."""
    n, c, r = 8, np.array([0.52, 0.47]), 0.3
    origin, J = grid_cells(cell, n)
    x = origin[:, None] + np.einsum("mij,pj->mpi", J, nodes(cell, degree))
    phi = np.linalg.norm(x - c, axis=2) - r
    side = cut.classify(cell, degree, phi)
    rows = np.flatnonzero(side == 0)

    def exact(k: np.ndarray, X: np.ndarray) -> np.ndarray:
        xk = origin[rows[k]] + np.einsum("mij,mj->mi", J[rows[k]], X)
        return np.linalg.norm(xk - c, axis=1) - r

    for ex in (None, exact):
        geom = cut.subtriangulate(cell, degree, phi[rows], exact=ex)
        xs = origin[rows, None] + np.einsum("mij,mpj->mpi", J[rows], geom.seg)
        dist = np.abs(np.linalg.norm(xs - c, axis=2) - r) * n  # reference units
        if ex is None:
            assert dist.max() > 1e-8  # the interpolant's zero set is not the circle
            continue
        assert dist.max() < 1e-14
        minus = quadrature.side_rules(geom, -1, 6, rows.size)
        area = per_rule(minus, minus.weights) @ np.abs(np.linalg.det(J[rows]))
        area += np.abs(np.linalg.det(J[side == -1])).sum() * AREA[cell]
        assert area == pytest.approx(np.pi * r * r, rel=1e-4)


@pytest.mark.parametrize("cell", CELLS)
def test_exact_callable_converges_fourth_order(cell: str):
    """Q1/P1 nodal values plus the exact callable: disc area and circumference
    converge at about fourth order (nodes on the circle, parabolic SEG3s)."""
    c, r = np.array([0.52, 0.47]), 0.3
    errors = []
    for n in (8, 16, 32):
        origin, J = grid_cells(cell, n)
        x = origin[:, None] + np.einsum("mij,pj->mpi", J, nodes(cell, 1))
        phi = np.linalg.norm(x - c, axis=2) - r
        side = cut.classify(cell, 1, phi)
        rows = np.flatnonzero(side == 0)

        def exact(k, X, origin=origin, J=J, rows=rows):
            xk = origin[rows[k]] + np.einsum("mij,mj->mi", J[rows[k]], X)
            return np.linalg.norm(xk - c, axis=1) - r

        geom = cut.subtriangulate(cell, 1, phi[rows], exact=exact)
        det = np.abs(np.linalg.det(J[rows]))
        minus = quadrature.side_rules(geom, -1, 6, rows.size)
        area = per_rule(minus, minus.weights) @ det
        area += np.abs(np.linalg.det(J[side == -1])).sum() * AREA[cell]
        gamma = quadrature.interface_rule(
            geom, 6, rows.size, lambda k, X, J=J, rows=rows: J[rows[k]], lambda k, X: X
        )
        length = per_rule(gamma, gamma.weights) @ det
        errors.append((abs(area - np.pi * r * r), abs(length - 2 * np.pi * r)))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 3.5), orders


def test_exact_callable_must_be_finite():
    X = nodes("triangle", 1)
    phi = (X[:, 0] - 0.5)[None]
    with pytest.raises(ValueError, match="not finite"):
        cut.subtriangulate("triangle", 1, phi, exact=lambda rows, X: np.full(len(rows), np.nan))


# -- classification and errors ------------------------------------------------------------------


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_classify_uncut_and_cut(cell: str, degree: int):
    X = nodes(cell, degree)
    cases = [
        (X[:, 0] + 2.0, 1),  # positive
        (X[:, 0] - 2.0, -1),  # negative
        (X[:, 0] + X[:, 1], 1),  # zero at v0 only: touching, side +1
        (X[:, 1], 1),  # zero along edge (v0, v1): +1
        (X[:, 0] - 0.5, 0),
        (-X[:, 1], 0),  # along an edge, side +1 has no area: still cut
        (np.zeros(len(X)), 1),  # identically zero: +1
    ]
    if degree == 2:
        cases += [
            ((X[:, 0] - 0.3) ** 2 + (X[:, 1] + 0.4) ** 2 - 0.16, 1),  # tangent from outside
            (-((X[:, 0] - 0.3) ** 2 + (X[:, 1] + 0.4) ** 2 - 0.16), -1),  # tangent from inside
            (X[:, 0] ** 2 + X[:, 1] ** 2 - 0.25, 0),  # quarter circle around v0
        ]
    phi = np.array([c[0] for c in cases])
    np.testing.assert_array_equal(cut.classify(cell, degree, phi), [c[1] for c in cases])
    assert cut.classify(cell, degree, phi).dtype == np.int8


def test_classify_rejects_non_finite():
    phi = np.zeros((4, 3))
    phi[2, 1] = np.nan
    with pytest.raises(ValueError, match="cell 2"):
        cut.classify("triangle", 1, phi)
    phi[2, 1] = 0.0
    phi[3, 0] = np.inf
    with pytest.raises(ValueError, match="cell 3"):
        cut.subtriangulate("triangle", 1, phi)


def test_saddle_quadrilateral_raises():
    X = nodes("quadrilateral", 1)
    phi = np.array([X[:, 0] + 1.0, (X[:, 0] - 0.5) * (X[:, 1] - 0.5) * 4])  # + - - + (tensor)
    assert np.array_equal(np.sign(phi[1]), [1, -1, -1, 1])
    with pytest.raises(ValueError, match=r"saddle.*\[1\].*refine the mesh"):
        cut.classify("quadrilateral", 1, phi)


@pytest.mark.parametrize("cell", CELLS)
def test_edge_crossed_twice_raises(cell: str):
    X = nodes(cell, 2)
    ok = X[:, 0] - 0.25
    twice = (X[:, 0] - 0.5) ** 2 + (X[:, 1] + 0.1) ** 2 - 0.09  # clips edge y = 0 twice
    phi = np.array([ok, ok, twice])
    with pytest.raises(ValueError, match=r"edge twice in cell\(s\) \[2\].*refine the mesh"):
        cut.classify(cell, 2, phi)


@pytest.mark.parametrize("cell", CELLS)
def test_closed_interior_piece_raises(cell: str):
    X = nodes(cell, 2)
    centre = np.array([0.3, 0.3]) if cell == "triangle" else np.array([0.5, 0.5])
    phi = (((X - centre) ** 2).sum(axis=1) - 0.1**2)[None]
    with pytest.raises(ValueError, match=r"inside cell\(s\) \[0\].*refine the mesh"):
        cut.classify(cell, 2, phi)


def test_bad_arguments():
    X = nodes("triangle", 1)
    with pytest.raises(ValueError, match="not cut"):
        cut.subtriangulate("triangle", 1, (X[:, 0] + 1)[None])
    with pytest.raises(ValueError, match="shape"):
        cut.classify("triangle", 2, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="cell_type"):
        cut.classify("tetrahedron", 1, np.zeros((1, 4)))
    with pytest.raises(ValueError, match="degree"):
        cut.classify("triangle", 3, np.zeros((1, 10)))


@pytest.mark.parametrize("cell", CELLS)
def test_no_cut_cells(cell: str):
    geom = cut.subtriangulate(cell, 2, np.zeros((0, 6 if cell == "triangle" else 9)))
    assert geom.seg.shape == (0, 3, 2) and geom.tri_minus.shape == (0, 6, 2)
    rules = quadrature.side_rules(geom, -1, 4, 0)
    assert rules.offsets.tolist() == [0] and rules.points.shape == (0, 2)
    gamma = quadrature.interface_rule(geom, 4, 0, identity, lambda r, X: np.zeros((len(r), 2)))
    assert gamma.offsets.tolist() == [0] and gamma.weights.shape == (0,)


def test_interface_rule_affine_map_and_touching_vertex():
    """Physical length and normal through an affine map; a zero-length piece (the
    interface touches a vertex) gets an empty rule."""
    X = nodes("quadrilateral", 1)
    phi = np.array([X[:, 0] + 0.5 * X[:, 1] - 0.6, -(X[:, 0] + X[:, 1])])
    geom = cut.subtriangulate("quadrilateral", 1, phi)
    J = np.array([[2.0, 0.5], [0.0, 1.5]])
    jac = lambda r, X: np.broadcast_to(J, (len(r), 2, 2))  # noqa: E731
    gamma = quadrature.interface_rule(geom, 3, 2, jac, grad_ref("quadrilateral", 1, phi))
    assert gamma.offsets[2] == gamma.offsets[1]  # touching piece: empty rule
    a, b = geom.seg[0, 0], geom.seg[0, 1]
    length = gamma.weights.sum() * abs(np.linalg.det(J))
    assert length == pytest.approx(np.linalg.norm(J @ (b - a)), rel=1e-14)
    normal = np.linalg.solve(J.T, [1.0, 0.5])
    normal = np.tile(normal / np.linalg.norm(normal), (len(gamma.weights), 1))
    np.testing.assert_allclose(gamma.normals, normal, atol=1e-14)
