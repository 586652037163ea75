"""Cut-cell geometry and quadrature (pure numpy): ``xfem_contact.geometry.cut`` and
``xfem_contact.quadrature.rules`` against exact references.

References are computed independently here: straight cuts by clipping the
reference cell with the half-plane (shoelace areas, high-order rules on a
straight triangulation for moments); curved P2 geometry by clipping with the
chord plus the parabolic segment between chord and SEG3; circles by the
closed-form area of a disc clipped by a polygon; subdivided cells by Green's
theorem on the boundary made of their SEG3s and the negative parts of the
cell's edges, and hyperbolas by 1D Gauss-Legendre between kinks.
"""

from __future__ import annotations

import basix
import numpy as np
import pytest

from xfem_contact.geometry import cut
from xfem_contact.geometry.cut_topology import lagrange_basis
from xfem_contact.quadrature import boundary
from xfem_contact.quadrature import rules as quadrature

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


def cross2(u: np.ndarray, v: np.ndarray) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def disc_in_polygon(poly: np.ndarray, c: np.ndarray, R: float) -> tuple[float, float]:
    """Area and arc length of ``{|x - c| < R}`` inside a convex polygon, in closed
    form: Green's theorem ``A = 1/2 int (x dy - y dx)`` on the boundary of the
    intersection, i.e. the polygon's edges inside the disc and the circle's arcs
    inside the polygon (any number of crossings)."""
    P = np.asarray(poly, dtype=np.float64) - c
    if shoelace(P) < 0:
        P = P[::-1]
    n = len(P)
    area, angles = 0.0, []
    for i in range(n):
        a, d = P[i], P[(i + 1) % n] - P[i]
        A, B, C = d @ d, 2 * a @ d, a @ a - R * R
        disc = B * B - 4 * A * C
        roots = []
        if disc > 0:
            roots = [t for t in ((-B - np.sqrt(disc)) / (2 * A), (-B + np.sqrt(disc)) / (2 * A))]
            roots = [t for t in roots if 0 < t < 1]
        ts = [0.0, *roots, 1.0]
        for t0, t1 in zip(ts[:-1], ts[1:], strict=True):
            X0, X1 = a + t0 * d, a + t1 * d
            if np.linalg.norm(0.5 * (X0 + X1)) < R:
                area += 0.5 * cross2(X0, X1)
        angles += [np.arctan2((a + t * d)[1], (a + t * d)[0]) for t in roots]

    def inside(Q: np.ndarray) -> bool:
        return all(cross2(P[(i + 1) % n] - P[i], Q - P[i]) > 0 for i in range(n))

    if not angles:  # the circle is inside the polygon, or does not meet it
        return (np.pi * R * R, 2 * np.pi * R) if inside(np.array([R, 0.0])) else (area, 0.0)
    angles.sort()
    arc = 0.0
    for t0, t1 in zip(angles, [*angles[1:], angles[0] + 2 * np.pi], strict=True):
        mid = 0.5 * (t0 + t1)
        if inside(R * np.array([np.cos(mid), np.sin(mid)])):
            area += 0.5 * R * R * (t1 - t0)
            arc += R * (t1 - t0)
    return area, arc


def hyperbola_in_square(a: float, b: float, c: float) -> tuple[float, float]:
    """Area of ``{(X - a)(Y - b) < c}`` in the unit square and length of its zero
    line there: with ``u = X - a``, the ``v = Y - b`` measure is ``clip(c/u - v_lo)``
    (``u > 0``) or ``clip(v_hi - c/u)`` (``u < 0``); 1D Gauss-Legendre on the
    pieces between kinks, where the integrands are analytic."""
    vlo, vhi = -b, 1.0 - b
    breaks = {-a, 0.0, 1.0 - a} | {c / v for v in (vlo, vhi) if -a < c / v < 1.0 - a}
    breaks = sorted(breaks)
    s, w = np.polynomial.legendre.leggauss(200)
    area = length = 0.0
    for u0, u1 in zip(breaks[:-1], breaks[1:], strict=True):
        u = 0.5 * (u0 + u1) + 0.5 * (u1 - u0) * s
        wu = 0.5 * (u1 - u0) * w
        measure = np.where(u > 0, np.clip(c / u - vlo, 0, 1), np.clip(vhi - c / u, 0, 1))
        area += measure @ wu
        um = 0.5 * (u0 + u1)
        if vlo < c / um < vhi:  # the zero line v = c / u is inside the square
            length += np.sqrt(1 + (c / u**2) ** 2) @ wu
    return area, length


def seg3_basis(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """SEG3 shape functions (nodes a, b, mid) and derivatives at ``s``, ``(nq, 3)`` each."""
    N = np.stack([2 * (s - 0.5) * (s - 1), 2 * s * (s - 0.5), 4 * s * (1 - s)], axis=1)
    return N, np.stack([4 * s - 3, 4 * s - 1, 4 - 8 * s], axis=1)


def green_moments(cell: str, degree: int, phi: np.ndarray, segs: np.ndarray, p: int) -> np.ndarray:
    """Moments ``int x^i y^j`` (``i + j <= p``) of the region bounded by the SEG3s
    ``segs`` ``(k, 3, 2)`` (traversed ``a -> b``) and the parts of the cell's
    edges where the interpolant of ``phi`` ``(ndofs,)`` is negative (roots of the
    edge polynomials by ``numpy.roots``), by Green's theorem
    ``int x^i y^j dA = int x^(i+1) y^j / (i+1) dy`` with Gauss-Legendre: exact
    for the piecewise-polynomial boundary, independent of the sub-triangles."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType[cell], degree, basix.LagrangeVariant.gll_warped
    )
    s, w = np.polynomial.legendre.leggauss(p + 4)
    s, w = 0.5 * (s + 1), 0.5 * w

    def flux(X: np.ndarray, dY: np.ndarray) -> np.ndarray:
        x, y = X[:, 0], X[:, 1]
        return np.array([np.sum(x ** (i + 1) * y**j / (i + 1) * dY * w) for i, j in exponents(p)])

    total = np.zeros(len(exponents(p)))
    N, dN = seg3_basis(s)
    for seg in segs:
        total += flux(N @ seg, dN @ seg[:, 1])
    V = VERTICES[cell]
    for k in range(len(V)):
        P, Q = V[k], V[(k + 1) % len(V)]
        g0, gm, g1 = element.tabulate(0, np.array([P, 0.5 * (P + Q), Q]))[0, :, :, 0] @ phi
        coeffs = np.trim_zeros([2 * g0 + 2 * g1 - 4 * gm, 4 * gm - 3 * g0 - g1, g0], "f")
        roots = np.roots(coeffs) if len(coeffs) > 1 else np.zeros(0)
        roots = [r.real for r in roots if r.imag == 0 and 0 < r.real < 1]
        ts = np.sort([0.0, 1.0, *roots])
        for t0, t1 in zip(ts[:-1], ts[1:], strict=True):
            if np.polyval(coeffs, 0.5 * (t0 + t1)) < 0:
                a, b = P + t0 * (Q - P), P + t1 * (Q - P)
                total += flux(a + s[:, None] * (b - a), np.full(s.size, b[1] - a[1]))
    return total


def cell_moments(cell: str, p: int) -> np.ndarray:
    return polygon_moments(VERTICES[cell], p)


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
    rows = np.flatnonzero(cut.classify(cell, degree, phi) == 0)
    assert rows.size > 100
    geom = cut.subtriangulate(cell, degree, phi[rows])
    assert geom.subdivided.size == 0  # simple cuts: one SEG3 per cell (subdivision tested below)
    np.testing.assert_array_equal(geom.seg_cell, np.arange(rows.size))
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
    Jacobian ``(m, 2, 2)`` (triangles: each square cut in two)."""
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
    with pytest.raises(ValueError, match="max_depth"):
        cut.subtriangulate("triangle", 1, (X[:, 0] - 0.5)[None], max_depth=-1)


@pytest.mark.parametrize("cell", CELLS)
def test_no_cut_cells(cell: str):
    geom = cut.subtriangulate(cell, 2, np.zeros((0, 6 if cell == "triangle" else 9)))
    assert geom.seg.shape == (0, 3, 2) and geom.tri_minus.shape == (0, 6, 2)
    assert geom.seg_cell.shape == (0,) and geom.num_cells == 0
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


# -- cells one SEG3 cannot represent: subdivision ---------------------------------------------


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_lagrange_basis_matches_basix(cell: str, degree: int):
    """The closed-form basis used on sub-cells is Basix's, and exactly 0/1 at the nodes."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType[cell], degree, basix.LagrangeVariant.gll_warped
    )
    X = np.random.default_rng(0).uniform(0, 1, (60, 2))
    X = X[X.sum(axis=1) < 1] if cell == "triangle" else X
    expected = element.tabulate(0, X)[0, :, :, 0]
    np.testing.assert_allclose(lagrange_basis(cell, degree, X), expected, atol=1e-14)
    np.testing.assert_array_equal(lagrange_basis(cell, degree, element.points), np.eye(element.dim))


def check_subdivided(cell: str, degree: int, phi: np.ndarray, geom: cut.CutGeometry, p: int = 2):
    """For every subdivided cell: each side's rule integrates degree-``p`` moments of
    the region bounded by its SEG3s exactly (Green), the SEG3s have side -1 on
    their left (along the level-set gradient); arrays are sorted by cell."""
    ncut = len(phi)
    for cells in (geom.tri_minus_cell, geom.tri_plus_cell, geom.seg_cell):
        assert np.all(np.diff(cells) >= 0)
    minus = quadrature.side_rules(geom, -1, 2 * p + 2, ncut)
    plus = quadrature.side_rules(geom, 1, 2 * p + 2, ncut)
    total = per_rule(minus, minus.weights) + per_rule(plus, plus.weights)
    np.testing.assert_allclose(total, AREA[cell], atol=1e-13)
    for k in geom.subdivided:
        reference = green_moments(cell, degree, phi[k], geom.seg[geom.seg_cell == k], p)
        np.testing.assert_allclose(rule_moments(minus, k, p), reference, atol=2e-14)
        np.testing.assert_allclose(
            rule_moments(plus, k, p), polygon_moments(VERTICES[cell], p) - reference, atol=2e-14
        )
    s = np.array([0.2, 0.5, 0.8])
    N, dN = seg3_basis(s)
    X = np.einsum("qk,ckd->cqd", N, geom.seg).reshape(-1, 2)
    dX = np.einsum("qk,ckd->cqd", dN, geom.seg).reshape(-1, 2)
    grad = grad_ref(cell, degree, phi)(np.repeat(geom.seg_cell, s.size), X)
    assert np.all(dX[:, 1] * grad[:, 0] - dX[:, 0] * grad[:, 1] > 0)  # (t_y, -t_x) . grad
    gamma = quadrature.interface_rule(geom, 8, ncut, identity, grad_ref(cell, degree, phi))
    return minus, plus, gamma


def first_cells(degree: int, cell: str, *levels) -> np.ndarray:
    """Nodal values of the level sets ``f(X)`` in ``levels``, one cell each."""
    X = nodes(cell, degree)
    return np.array([f(X) for f in levels])


def circle(centre, radius):
    return lambda X: ((X - np.asarray(centre)) ** 2).sum(axis=1) - radius**2


def line(X: np.ndarray) -> np.ndarray:
    return X[:, 0] - 0.25


@pytest.mark.parametrize("cell", CELLS)
def test_cap_on_one_edge(cell: str):
    """A circle clipping one edge (both of its ends outside): the cell is cut (no
    error), subdivided between the two crossings; the simple cells in the same
    batch are unchanged; area and arc match the circular segment."""
    centre, r = np.array([0.5, -0.1]), 0.3
    phi = first_cells(2, cell, line, circle(centre, r), line)
    np.testing.assert_array_equal(cut.classify(cell, 2, phi), [0, 0, 0])
    geom = cut.subtriangulate(cell, 2, phi)
    np.testing.assert_array_equal(geom.subdivided, [1])
    assert np.sum(geom.seg_cell == 0) == 1 and np.sum(geom.seg_cell == 2) == 1
    alone = cut.subtriangulate(cell, 2, phi[:1])
    np.testing.assert_array_equal(geom.tri_minus[geom.tri_minus_cell == 2], alone.tri_minus)
    np.testing.assert_array_equal(geom.seg[geom.seg_cell == 0], alone.seg)
    minus, _, gamma = check_subdivided(cell, 2, phi, geom)
    area, arc = disc_in_polygon(VERTICES[cell], centre, r)
    assert per_rule(minus, minus.weights)[1] == pytest.approx(area, rel=1e-4)
    assert per_rule(gamma, gamma.weights)[1] == pytest.approx(arc, rel=1e-4)
    with pytest.raises(ValueError, match=r"cell\(s\) \[1\].*after 0 levels.*crosses an edge twice"):
        cut.subtriangulate(cell, 2, phi, max_depth=0)


@pytest.mark.parametrize("cell", CELLS)
def test_cap_converges_fifth_order(cell: str):
    """The unit circle clipping the bottom edge of a cell of size h (cap height
    0.05 h^2, chord about 0.6 h, so the same topology at every h): area and arc
    errors fall like h^5, as for simple cuts."""
    X = nodes(cell, 2)
    errors = []
    hs = [0.4, 0.2, 0.1, 0.05]
    for h in hs:
        x0 = np.array([-0.4 * h, 1 - 0.05 * h * h])
        phi = (((x0 + h * X) ** 2).sum(axis=1) - 1.0)[None]
        geom = cut.subtriangulate(cell, 2, phi)
        assert geom.subdivided.tolist() == [0]
        area = quadrature.side_rules(geom, -1, 6, 1).weights.sum() * h * h
        jac = lambda rows, X, h=h: np.broadcast_to(h * np.eye(2), (len(rows), 2, 2))  # noqa: E731
        gamma = quadrature.interface_rule(geom, 6, 1, jac, lambda r, X, x0=x0, h=h: x0 + h * X)
        exact_area, exact_arc = disc_in_polygon(x0 + h * VERTICES[cell], np.zeros(2), 1.0)
        errors.append((abs(area - exact_area), abs(gamma.weights.sum() * h * h - exact_arc)))
    errors = np.array(errors)
    orders = np.log2(errors[:-1] / errors[1:])
    assert np.all(orders > 4.5), orders
    assert np.all(errors[0] < 1e-7), errors


@pytest.mark.parametrize("offset", [0.0, 0.07])
@pytest.mark.parametrize("cell", CELLS)
def test_closed_piece_inside_cell(cell: str, offset: float):
    """A small circle inside one cell, crossing no edge: cut (not uncut), subdivided
    through its inside; area and circumference within 5e-4 of the circle's (the
    pieces are refined to stray less than 2e-4 of their chord, depth permitting)."""
    centre = (np.array([0.3, 0.3]) if cell == "triangle" else np.array([0.5, 0.5])) + offset
    r = 0.1
    phi = first_cells(2, cell, circle(centre, r))
    assert cut.classify(cell, 2, phi)[0] == 0
    geom = cut.subtriangulate(cell, 2, phi)
    assert geom.subdivided.tolist() == [0] and geom.seg.shape[0] >= 4
    minus, _, gamma = check_subdivided(cell, 2, phi, geom)
    assert minus.weights.sum() == pytest.approx(np.pi * r * r, rel=5e-4)
    assert gamma.weights.sum() == pytest.approx(2 * np.pi * r, rel=5e-4)
    with pytest.raises(ValueError, match="changes sign inside without crossing the boundary"):
        cut.subtriangulate(cell, 2, phi, max_depth=0)


@pytest.mark.parametrize("cell", CELLS)
def test_several_pieces(cell: str):
    """A circle crossing every edge twice (4 corner pieces of side +1 in the
    quadrilateral, 3 in the triangle), and one crossing the edges at vertex 0
    twice each, missing the vertex (2 arcs): closed-form area and arc length."""
    big = ((0.5, 0.5), 0.6, 4) if cell == "quadrilateral" else ((0.29, 0.29), 0.35, 3)
    cases = [big, ((0.25, 0.25), 0.3, 2)]
    phi = first_cells(2, cell, *(circle(c, r) for c, r, _ in cases))
    np.testing.assert_array_equal(cut.classify(cell, 2, phi), 0)
    geom = cut.subtriangulate(cell, 2, phi)
    np.testing.assert_array_equal(geom.subdivided, [0, 1])
    minus, _, gamma = check_subdivided(cell, 2, phi, geom)
    for k, (c, r, pieces) in enumerate(cases):
        assert np.sum(geom.seg_cell == k) >= pieces
        area, arc = disc_in_polygon(VERTICES[cell], np.array(c), r)
        assert per_rule(minus, minus.weights)[k] == pytest.approx(area, rel=1e-4)
        assert per_rule(gamma, gamma.weights)[k] == pytest.approx(arc, rel=1e-4)


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("c", [0.01, -0.01, 0.002])
def test_saddle_hyperbola(degree: int, c: float):
    """``(X - 0.45)(Y - 0.55) = c`` on a quadrilateral (interpolated exactly by Q1
    and Q2): four boundary crossings, two branches. Both degrees integrate the
    region bounded by their pieces exactly; degree 2 matches the hyperbola."""
    X = nodes("quadrilateral", degree)
    phi = ((X[:, 0] - 0.45) * (X[:, 1] - 0.55) - c)[None]
    assert cut.classify("quadrilateral", degree, phi)[0] == 0
    geom = cut.subtriangulate("quadrilateral", degree, phi)
    assert geom.subdivided.tolist() == [0] and geom.seg.shape[0] >= 2
    minus, _, gamma = check_subdivided("quadrilateral", degree, phi, geom)
    if degree == 2:
        area, length = hyperbola_in_square(0.45, 0.55, c)
        assert minus.weights.sum() == pytest.approx(area, rel=1e-4)
        assert gamma.weights.sum() == pytest.approx(length, rel=1e-4)


@pytest.mark.parametrize("degree", DEGREES)
def test_crossing_lines(degree: int):
    """Zero lines that cross: at a subdivision point (the centre) the sub-cells see the
    interface along two of their edges and are exact; elsewhere the crossing
    stays inside a sub-cell at every level and the cell is reported."""
    X = nodes("quadrilateral", degree)
    phi = ((X[:, 0] - 0.5) * (X[:, 1] - 0.5))[None]
    geom = cut.subtriangulate("quadrilateral", degree, phi)
    minus, _, gamma = check_subdivided("quadrilateral", degree, phi, geom)
    assert minus.weights.sum() == pytest.approx(0.5, abs=1e-14)
    assert gamma.weights.sum() == pytest.approx(2.0, abs=1e-14)
    phi = np.array([line(X), (X[:, 0] - 0.4) * (X[:, 1] - 0.55)])
    with pytest.raises(
        ValueError,
        match=r"cannot cut cell\(s\) \[1\].*after 5 levels.*more than twice.*perturb",
    ):
        cut.subtriangulate("quadrilateral", degree, phi)


@pytest.mark.parametrize("cell", CELLS)
def test_interface_along_two_edges(cell: str):
    """``-X Y`` vanishes on the edges X = 0 and Y = 0 and is negative inside: the
    cell is wholly on side -1 and carries both edges as interface pieces, with
    normals pointing out of the cell."""
    X = nodes(cell, 2)
    phi = (-X[:, 0] * X[:, 1])[None]
    assert cut.classify(cell, 2, phi)[0] == 0
    geom = cut.subtriangulate(cell, 2, phi)
    assert geom.tri_plus.shape[0] == 0 and geom.seg.shape[0] == 2
    minus, _, _ = check_subdivided(cell, 2, phi, geom)
    assert minus.weights.sum() == pytest.approx(AREA[cell], abs=1e-14)
    no_flip = lambda r, X: np.zeros((len(r), 2))  # noqa: E731  (orientation of the SEG3s only)
    gamma = quadrature.interface_rule(geom, 3, 1, identity, no_flip)
    assert gamma.weights.sum() == pytest.approx(2.0, abs=1e-14)
    outward = np.where((gamma.points[:, 1] == 0)[:, None], [0.0, -1.0], [-1.0, 0.0])
    np.testing.assert_allclose(gamma.normals, outward, atol=1e-15)


def test_interface_along_two_edges_with_inner_pocket():
    """``X Y (5 (1 - X)(1 - Y) - 1)`` also vanishes on X = 0 and Y = 0 but is
    positive in a pocket at that corner: not wholly side -1, so it is subdivided.
    Side -1 is ``(1 - X)(1 - Y) < 1/5``, of area ``1/5 - 1/5 ln(1/5)``."""
    X = nodes("quadrilateral", 2)
    x, y = X[:, 0], X[:, 1]
    phi = (x * y * (5 * (1 - x) * (1 - y) - 1))[None]
    geom = cut.subtriangulate("quadrilateral", 2, phi)
    minus, _, _ = check_subdivided("quadrilateral", 2, phi, geom)
    assert minus.weights.sum() == pytest.approx(0.2 - 0.2 * np.log(0.2), rel=1e-4)


@pytest.mark.parametrize("cell", CELLS)
def test_mesh_aligned_square_inclusion(cell: str):
    """The square [0.25, 0.75]^2 on a 4 x 4 grid: its sides run along cell edges
    and its corners are cells with the interface along two edges; area, perimeter
    and outward normals are exact."""
    origin, J = grid_cells(cell, 4)
    x = origin[:, None] + np.einsum("mij,pj->mpi", J, nodes(cell, 2))
    phi = np.abs(x - 0.5).max(axis=2) - 0.25
    side = cut.classify(cell, 2, phi)
    rows = np.flatnonzero(side == 0)
    geom = cut.subtriangulate(cell, 2, phi[rows])
    det = np.abs(np.linalg.det(J))
    minus = quadrature.side_rules(geom, -1, 4, rows.size)
    area = per_rule(minus, minus.weights) @ det[rows] + det[side == -1].sum() * AREA[cell]
    assert area == pytest.approx(0.25, abs=1e-14)

    def jacobian(k: np.ndarray, X: np.ndarray) -> np.ndarray:
        return J[rows[k]]

    no_flip = lambda r, X: np.zeros((len(r), 2))  # noqa: E731
    gamma = quadrature.interface_rule(geom, 3, rows.size, jacobian, no_flip)
    assert per_rule(gamma, gamma.weights) @ det[rows] == pytest.approx(2.0, abs=1e-14)
    owner = np.repeat(np.arange(rows.size), np.diff(gamma.offsets))
    xq = origin[rows[owner]] + np.einsum("mij,mj->mi", J[rows[owner]], gamma.points)
    axis = np.argmax(np.abs(xq - 0.5), axis=1)
    outward = np.zeros_like(xq)
    outward[np.arange(len(xq)), axis] = np.sign(xq[np.arange(len(xq)), axis] - 0.5)
    np.testing.assert_allclose(gamma.normals, outward, atol=1e-14)


@pytest.mark.parametrize("cell", CELLS)
def test_exact_callable_on_subdivided_cells(cell: str):
    """Nodal values of the distance to the unit circle, which clips one edge of a
    cell of size 0.2, and the distance itself as ``exact``: it is called with rows
    of ``phi`` and points of the parent cell, and every SEG3 node of the
    subdivided cell lies on the circle."""
    h = 0.2
    x0 = np.array([-0.4 * h, 1 - 0.05 * h * h])
    X = nodes(cell, 2)
    phi = np.array([line(X), np.linalg.norm(x0 + h * X, axis=1) - 1.0])
    seen = []

    def exact(rows: np.ndarray, X: np.ndarray) -> np.ndarray:
        seen.append((rows.copy(), X.copy()))
        return np.where(rows == 1, np.linalg.norm(x0 + h * X, axis=1) - 1.0, X[:, 0] - 0.25)

    geom = cut.subtriangulate(cell, 2, phi, exact=exact)
    assert geom.subdivided.tolist() == [1]
    rows = np.concatenate([s[0] for s in seen])
    points = np.concatenate([s[1] for s in seen])
    assert set(rows.tolist()) == {0, 1}
    assert points.min() >= -1e-15 and points.max() <= 1 + 1e-15
    on = x0 + h * geom.seg[geom.seg_cell == 1]
    np.testing.assert_allclose(np.linalg.norm(on, axis=2), 1.0, atol=1e-15)
    minus = quadrature.side_rules(geom, -1, 6, 2)
    area, _ = disc_in_polygon(x0 + h * VERTICES[cell], np.zeros(2), 1.0)
    assert per_rule(minus, minus.weights)[1] * h * h == pytest.approx(area, rel=1e-4)


@pytest.mark.parametrize("cell", CELLS)
def test_facet_pieces_of_subdivided_cells(cell: str):
    """Boundary pieces read off the sub-triangles (:func:`boundary.facet_pieces`)
    cover each facet once, and side -1's pieces are where the interpolant is
    negative, also for subdivided cells."""
    centre, r = np.array([0.5, -0.1]), 0.3
    phi = first_cells(2, cell, circle(centre, r), circle((0.29, 0.29), 0.35), line)
    geom = cut.subtriangulate(cell, 2, phi)
    assert geom.subdivided.size == 2
    fverts, _ = boundary.reference_facets(cell)
    covered = np.zeros((len(phi), len(fverts)))
    negative = np.zeros((len(phi), len(fverts)))
    for side in (-1, 1):
        rows, facets, ends, signs = boundary.facet_pieces(geom, side, cell)
        lengths = signs * np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
        np.add.at(covered, (rows, facets), lengths)
        if side == -1:
            np.add.at(negative, (rows, facets), lengths)
    facet_length = np.linalg.norm(fverts[:, 1] - fverts[:, 0], axis=1)
    np.testing.assert_allclose(covered, np.broadcast_to(facet_length, covered.shape), atol=1e-14)
    for k in range(len(phi)):
        for f, (P, Q) in enumerate(fverts):
            t = np.linspace(0, 1, 200001)
            values = lagrange_basis(cell, 2, P + t[:, None] * (Q - P)) @ phi[k]
            expected = np.mean(values < 0) * facet_length[f]  # sampled: to 1e-5
            assert negative[k, f] == pytest.approx(expected, abs=1e-5)


@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_random_circles_batch(cell: str, degree: int):
    """Random circles of radius 0.05 .. 0.8 around the cell (caps, closed pieces,
    several pieces, simple cuts) in one batch: every cell is handled, and each
    subdivided cell integrates the region bounded by its pieces exactly."""
    rng = np.random.default_rng(3)
    n = 500
    X = nodes(cell, degree)
    radius = rng.uniform(0.05, 0.8, n)
    centre = rng.uniform(-0.5, 1.5, (n, 2))
    phi = ((X[None] - centre[:, None]) ** 2).sum(-1) - radius[:, None] ** 2
    rows = np.flatnonzero(cut.classify(cell, degree, phi) == 0)
    geom = cut.subtriangulate(cell, degree, phi[rows])
    if degree == 2:
        assert geom.subdivided.size > 50
    else:  # a linear interpolant of a circle is a line (triangle) or a hyperbola (quad)
        assert geom.subdivided.size == 0
    check_subdivided(cell, degree, phi[rows], geom)


@pytest.mark.parametrize("eps", [0.0, 1e-17, -1e-17, 1e-16, -1e-16, 1e-15, -1e-15])
@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("cell", CELLS)
def test_line_through_a_vertex(cell: str, degree: int, eps: float):
    """The line X + 2 Y = 1 through vertex (1, 0), its nodal value there 0 or a rounding
    error away: the crossing is the vertex (no sliver beside it, no folded fallback
    fan), each facet's pieces cover it once on each side (a value of -1e-17 there
    counted facet (0, 1) three times on side -1, 1e-16 nine times on side +1)."""
    X = nodes(cell, degree)
    phi = X[:, 0] + 2.0 * X[:, 1] - 1.0
    phi[np.flatnonzero((X == [1.0, 0.0]).all(axis=1))] = eps
    geom = cut.subtriangulate(cell, degree, phi[None])
    assert len(geom.tri_minus) <= 2 and len(geom.tri_plus) <= 2  # apex fans
    fverts, _ = boundary.reference_facets(cell)
    for side in (-1, 1):
        rows, facets, ends, signs = boundary.facet_pieces(geom, side, cell)
        assert (signs == 1).all()
        lengths = np.bincount(facets, np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1), len(fverts))
        for f, (P, Q) in enumerate(fverts):
            t = np.linspace(0.0, 1.0, 100001)
            values = (P[0] + t * (Q - P)[0]) + 2.0 * (P[1] + t * (Q - P)[1]) - 1.0
            exact = np.mean(side * values > 0) * np.linalg.norm(Q - P)  # sampled: to 1e-5
            assert lengths[f] == pytest.approx(exact, abs=2e-5), (side, f)


def test_facet_pieces_of_a_fold_cancel():
    """Pieces carry their sub-triangle's orientation: a triangle and a reversed copy (the
    overlap of a folded fallback fan) cancel, so the facet counts once."""
    whole = np.array([[0, 0], [1, 0], [0, 1], [0.5, 0.5], [0, 0.5], [0.5, 0]], dtype=float)
    inner = np.array([[0, 0], [1, 0], [0.2, 0.2], [0.6, 0.1], [0.1, 0.1], [0.5, 0]])
    reversed_ = inner[[1, 0, 2, 4, 3, 5]]
    tri = np.stack([whole, inner, reversed_])
    geom = cut.CutGeometry(
        tri,
        np.zeros(3, dtype=np.int64),
        np.zeros((0, 6, 2)),
        np.zeros(0, dtype=np.int64),
        np.zeros((0, 3, 2)),
        np.zeros(0, dtype=np.int64),
        1,
        np.zeros(0, dtype=np.int64),
    )
    rows, facets, ends, signs = boundary.facet_pieces(geom, -1, "triangle")
    lengths = signs * np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1)
    assert sorted(signs.tolist()) == [-1.0, 1.0, 1.0, 1.0, 1.0]
    np.testing.assert_allclose(np.bincount(facets, lengths, 3), [np.sqrt(2), 1.0, 1.0])
