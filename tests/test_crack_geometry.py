"""Crack geometry and tip quadrature: classification, tips, fan cuts, Duffy rules.

Pure numpy and Basix, no mesh: single cells mapped affinely to physical space.
"""

import basix
import numpy as np
import pytest

from xfem_contact.geometry.crack import CROSSED, NONE, TIP, classify_crack, polar
from xfem_contact.geometry.crack_tip_cell import cut_tip_cells
from xfem_contact.geometry.cut import CutGeometry
from xfem_contact.geometry.cut_topology import cell_data
from xfem_contact.quadrature.rules import triangle_rules
from xfem_contact.quadrature.tip_rules import (
    duffy_rule,
    near_tip_side_rules,
    tip_lip_rule,
    tip_side_rules,
)

CELLS = ("triangle", "quadrilateral")
A = np.array([[1.3, 0.4], [-0.2, 0.9]])  # an affine parent map x = A X + b
B = np.array([0.7, -0.3])


def _nodes(cell_type, degree):
    return cell_data(cell_type, degree).element.points


def _straight(cell_type, degree, tip_ref, angle):
    """Nodal phi, psi (signed distances in physical space) of a straight crack
    ending at physical point A tip_ref + b and running along -(cos, sin)(angle)."""
    t = np.array([np.cos(angle), np.sin(angle)])
    n = np.array([-t[1], t[0]])
    x = _nodes(cell_type, degree) @ A.T + B
    tip = A @ tip_ref + B
    return ((x - tip) @ n)[None], ((x - tip) @ t)[None], tip, n, t


def _jacobian(rows, X):
    return np.broadcast_to(A, (len(rows), 2, 2))


def _polygon_area(p):
    return 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])


def _clip(polygon, normal, offset):
    """Sutherland-Hodgman: the part of a convex polygon with normal . x <= offset."""
    out = []
    for k in range(len(polygon)):
        p, q = polygon[k], polygon[(k + 1) % len(polygon)]
        fp, fq = p @ normal - offset, q @ normal - offset
        if fp <= 0:
            out.append(p)
        if fp * fq < 0:
            out.append(p + fp / (fp - fq) * (q - p))
    return np.array(out)


@pytest.mark.parametrize("cell_type", CELLS)
@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize(("tip_ref", "angle"), [((0.3, 0.25), 0.4), ((0.35, 0.6), 2.5)])
def test_straight_crack_sides_length_and_tip_exact(cell_type, degree, tip_ref, angle):
    tip_ref = np.array(tip_ref)
    phi, psi, tip, n, t = _straight(cell_type, degree, tip_ref, angle)
    cells = classify_crack(cell_type, degree, phi, psi)
    assert cells.kind.tolist() == [TIP]
    assert np.allclose(cells.tip, tip_ref, atol=1e-15, rtol=0)
    pushed = cells.physical_tips(lambda rows, X: X @ A.T + B)
    assert np.abs(pushed - tip).max() < 1e-14
    cut = cut_tip_cells(cell_type, degree, phi, psi, cells.tip)
    assert np.all(cut.tri_minus[:, 0] == cut.tip) and np.all(cut.tri_plus[:, 0] == cut.tip)
    data = cell_data(cell_type, degree)
    cell = data.loop_coords @ A.T + B
    det = abs(np.linalg.det(A))
    for side, sign in ((-1, 1.0), (1, -1.0)):
        exact = abs(_polygon_area(_clip(cell, sign * n, sign * (n @ tip))))
        area = tip_side_rules(cut, side, 4).weights.sum() * det
        assert abs(area - exact) < 1e-13
    # crack length: from the tip back along -t to the cell boundary
    faces = data.face_normals @ np.linalg.inv(A)  # physical half-planes m . x <= c
    offsets = data.face_offsets + faces @ B
    run = (offsets - faces @ tip) / (faces @ -t)
    length = run[faces @ -t > 0].min()
    lip = tip_lip_rule(cut, 3, _jacobian, lambda rows, X: np.broadcast_to(A.T @ n, (len(rows), 2)))
    assert abs(lip.weights.sum() * det - length) < 1e-13
    assert np.allclose(lip.normals, n, atol=1e-14)  # from side -1 (phi < 0) to side +1
    end = cut.crack[0, 1 - cut.crack_tip_end[0]] @ A.T + B
    assert np.abs(end - (tip - length * t)).max() < 1e-14


def _unit_cell(cell_type, degree, phi, psi):
    X = _nodes(cell_type, degree)
    return phi(X[:, 0], X[:, 1])[None], psi(X[:, 0], X[:, 1])[None]


@pytest.mark.parametrize("cell_type", CELLS)
def test_classification(cell_type):
    def kind(phi, psi, degree=1):
        return classify_crack(cell_type, degree, *_unit_cell(cell_type, degree, phi, psi)).kind[0]

    line = lambda x, y: y - 0.3 - 0.1 * x  # noqa: E731
    assert kind(lambda x, y: y + 0.1, lambda x, y: x - 0.5) == NONE  # phi keeps its sign
    assert kind(line, lambda x, y: x + 0.2) == NONE  # the crack's extension only
    assert kind(line, lambda x, y: x - 1.5) == CROSSED
    assert kind(line, lambda x, y: x - 0.4) == TIP
    assert kind(line, lambda x, y: x - 0.4, degree=2) == TIP
    assert kind(lambda x, y: y - x, lambda x, y: x - 2.0) == CROSSED  # through two vertices


@pytest.mark.parametrize("cell_type", CELLS)
def test_crack_ending_twice_refused_by_name(cell_type):
    phi, psi = lambda x, y: y - 0.2, lambda x, y: -(x - 0.1) * (0.3 - x)
    with pytest.raises(ValueError, match="ends twice"):
        classify_crack(cell_type, 2, *_unit_cell(cell_type, 2, phi, psi))


@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("cell_type", CELLS)
@pytest.mark.parametrize(
    ("phi", "psi", "tip", "entry", "case"),
    [
        (lambda x, y: y - 0.5 * (1 - x), lambda x, y: x - 1.0, (1.0, 0.0), (0, 0.5), "node"),
        (lambda x, y: x - 0.5 + 0.2 * y, lambda x, y: -y, (0.5, 0.0), "top", "edge"),
        (lambda x, y: -y, lambda x, y: x - 0.5, (0.5, 0.0), (0.0, 0.0), "along an edge"),
        (lambda x, y: -y, lambda x, y: x - 1.0, (1.0, 0.0), (0.0, 0.0), "along, at a node"),
    ],
)
def test_tip_on_the_cell_boundary(cell_type, degree, phi, psi, tip, entry, case):
    """A tip on a node or an edge of its cell, also with the crack along an edge: one
    tip cell, the tip exact, the fans tile both sides exactly and the lip rule
    measures the crack from where it enters to the tip (these were refused)."""
    values = _unit_cell(cell_type, degree, phi, psi)
    cells = classify_crack(cell_type, degree, *values)
    assert cells.kind.tolist() == [TIP], case
    np.testing.assert_allclose(cells.tip, [tip], atol=1e-15)
    cut = cut_tip_cells(cell_type, degree, *values, cells.tip)
    vertices = _nodes(cell_type, 1)[[0, 1, 3, 2] if cell_type == "quadrilateral" else [0, 1, 2]]
    gradient = np.array(
        [phi(1.0, 0.0) - phi(0.0, 0.0), phi(0.0, 1.0) - phi(0.0, 0.0)]
    )  # phi is affine
    below = _clip(vertices, gradient, -phi(0.0, 0.0))
    areas = [tip_side_rules(cut, side, 4).weights.sum() for side in (-1, 1)]
    total = _polygon_area(vertices)
    np.testing.assert_allclose(
        areas, [_polygon_area(below), total - _polygon_area(below)], atol=1e-14
    )
    if entry == "top":  # x = 0.5 - 0.2 y meets x + y = 1 (triangle) or y = 1
        entry = (0.375, 0.625) if cell_type == "triangle" else (0.3, 1.0)
    identity = lambda rows, X: np.broadcast_to(np.eye(2), (len(rows), 2, 2))  # noqa: E731
    lip = tip_lip_rule(cut, 4, identity, lambda rows, X: np.tile(gradient, (len(rows), 1)))
    assert lip.weights.sum() == pytest.approx(np.hypot(*(np.array(tip) - entry)), abs=1e-14)


@pytest.mark.parametrize("cell_type", CELLS)
@pytest.mark.parametrize("degree", [1, 2])
def test_crack_through_a_vertex_is_handled(cell_type, degree):
    phi, psi = _unit_cell(cell_type, degree, lambda x, y: y - x, lambda x, y: x - 0.3)
    cells = classify_crack(cell_type, degree, phi, psi)
    assert cells.kind.tolist() == [TIP] and np.allclose(cells.tip, [[0.3, 0.3]], atol=1e-15)
    cut = cut_tip_cells(cell_type, degree, phi, psi, cells.tip)
    half = 0.25 if cell_type == "triangle" else 0.5  # y = x halves both cells
    areas = [tip_side_rules(cut, side, 3).weights.sum() for side in (-1, 1)]
    assert np.allclose(areas, half, atol=1e-14, rtol=0)
    assert abs(np.hypot(*(cut.crack[0, 0] - cut.crack[0, 1])) - 0.3 * np.sqrt(2)) < 1e-15


def test_polar_coordinates_and_gradients():
    phi = np.array([0.0, -0.0, 0.3, -0.3, 0.0])
    psi = np.array([-1.0, -1.0, 0.4, 0.4, 2.0])
    g_phi, g_psi = np.tile([0.0, 1.0], (5, 1)), np.tile([1.0, 0.0], (5, 1))
    r, theta, grad_r, grad_theta = polar(phi, psi, g_phi, g_psi)
    assert theta[0] == np.pi and theta[1] == -np.pi and theta[4] == 0.0  # the lips, ahead
    x, y = psi, phi  # straight crack along -x: compare with polar coordinates of (x, y)
    assert np.allclose(r, np.hypot(x, y)) and np.allclose(grad_r[2], [0.8, 0.6])
    assert np.allclose(grad_theta[2], [-y[2], x[2]] / r[2] ** 2)
    with pytest.raises(ValueError, match="both or none"):
        polar(phi, psi, g_phi)


# --- the tip rule: Williams-type singular integrands over a fan triangle -------------------
FAN = np.array([[0.0, 0.0], [1.0, 0.2], [0.3, 0.9]])  # tip at vertex 0, straight P2 triangle
CRACK_ANGLE = 3.6  # direction of the crack (theta = +-pi) from the tip, outside the fan


def _fan_p2(v):
    return np.concatenate([v, 0.5 * (v[[1, 0, 0]] + v[[2, 2, 1]])])[None]


def _g(theta):
    """Angular factors h(theta) of r^a h(theta): the values and squared gradients of
    sqrt(r) sin(theta/2) and of sqrt(r) sin(theta/2) sin(theta) (|grad (r^(1/2) g)|^2 =
    r^-1 (g^2 / 4 + g'^2))."""
    s, c = np.sin(theta / 2), np.cos(theta / 2)
    g2, dg2 = s * np.sin(theta), 0.5 * c * np.sin(theta) + s * np.cos(theta)
    return {
        "r^-1/2": (-0.5, np.ones_like(theta)),
        "sqrt(r) sin(theta/2)": (0.5, s),
        "|grad sqrt(r) sin(theta/2)|^2": (-1.0, np.full_like(theta, 0.25)),
        "|grad sqrt(r) sin(theta/2) sin(theta)|^2": (-1.0, g2**2 / 4 + dg2**2),
    }


def _crack_theta(x):
    """Angle about the tip with theta = +-pi along the crack direction CRACK_ANGLE."""
    return np.angle(np.exp(1j * (np.arctan2(x[:, 1], x[:, 0]) - CRACK_ANGLE + np.pi)))


def _reference_integrals(n=400, p1=FAN[1], p2=FAN[2]):
    """int r^a h(theta) over the fan (0, p1, p2) in polar coordinates (negative if
    clockwise): the radial part exactly (R(theta)^(a+2) / (a+2), R the distance to the
    far edge), the angle by n-point Gauss."""
    a1 = np.arctan2(p1[1], p1[0])
    a2 = a1 + np.angle(np.exp(1j * (np.arctan2(p2[1], p2[0]) - a1)))
    x, w = np.polynomial.legendre.leggauss(n)
    phi = a1 + (a2 - a1) * (x + 1) / 2
    w = w * (a2 - a1) / 2
    e = p2 - p1
    d = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    R = (p1[0] * e[1] - p1[1] * e[0]) / (d[:, 0] * e[1] - d[:, 1] * e[0])  # ray meets edge
    theta = _crack_theta(d)
    return {k: np.sum(w * h * R ** (a + 2) / (a + 2)) for k, (a, h) in _g(theta).items()}


def _integrate(points, weights):
    r = np.hypot(points[:, 0], points[:, 1])
    theta = _crack_theta(points)
    return {k: np.sum(weights * r**a * h) for k, (a, h) in _g(theta).items()}


def test_reference_integrals_converged():
    coarse, fine = _reference_integrals(200), _reference_integrals(400)
    for key in fine:
        assert abs(coarse[key] - fine[key]) <= 5e-14 * abs(fine[key])


def test_duffy_rule_integrates_tip_singularities_plain_gauss_does_not():
    exact = _reference_integrals()
    tri = _fan_p2(FAN)
    errors = {}
    for name, (xi, w) in {
        "almost polar": duffy_rule(12, grading=2),
        "plain Duffy": duffy_rule(12, grading=1),
        "Gauss degree 30": basix.make_quadrature(basix.CellType.triangle, 30),
    }.items():
        rule = triangle_rules(tri, np.array([0]), 1, xi, w)
        got = _integrate(rule.points, rule.weights)
        errors[name] = {k: abs(got[k] - exact[k]) / abs(exact[k]) for k in exact}
    assert max(errors["almost polar"].values()) < 1e-10
    gauss = errors["Gauss degree 30"]
    assert gauss["r^-1/2"] > 1e-6 and gauss["|grad sqrt(r) sin(theta/2)|^2"] > 1e-4
    assert errors["plain Duffy"]["r^-1/2"] > 1e-7  # the grading is what makes r^-1/2 smooth
    assert errors["plain Duffy"]["|grad sqrt(r) sin(theta/2)|^2"] < 1e-12  # 1/r is smooth


def test_near_tip_rule_integrates_a_tip_just_outside_the_cell():
    """A sub-triangle of a cell next to the tip cell, its vertex A 0.022 from the tip:
    exact integrals as the signed sum of the three fans from the tip. The Duffy rule
    collapsed onto A (found by distance, A is the sub-triangle's vertex 2) is exact to
    1e-9; the degree-16 Gauss rule of uncut cells and one collapsed onto B are not."""
    A, B, C = np.array([0.02, 0.01]), np.array([1.0, 0.3]), np.array([0.2, 0.9])
    fans = [_reference_integrals(400, p, q) for p, q in ((A, B), (B, C), (C, A))]
    exact = {k: sum(f[k] for f in fans) for k in fans[0]}
    tri = _fan_p2(np.array([B, C, A]))
    empty = np.zeros(0, dtype=np.int64)
    geom = CutGeometry(
        np.zeros((0, 6, 2)), empty, tri, np.array([0]), np.zeros((0, 3, 2)), empty, 1, empty
    )

    def errors(points, weights):
        got = _integrate(points, weights)
        return max(abs(got[k] - exact[k]) / abs(exact[k]) for k in exact)

    near = near_tip_side_rules(geom, 1, np.array([0]), lambda r, X: np.hypot(*X.T), 24)
    assert abs(near.weights.sum() - 0.41) < 1e-14  # the triangle's area
    assert errors(near.points, near.weights) < 1e-9
    assert near_tip_side_rules(geom, -1, np.array([0]), lambda r, X: 1 / 0, 24).points.shape == (
        0,
        2,
    )
    gauss = triangle_rules(
        tri, np.array([0]), 1, *basix.make_quadrature(basix.CellType.triangle, 16)
    )
    assert errors(gauss.points, gauss.weights) > 1e-3
    at_B = triangle_rules(tri, np.array([0]), 1, *duffy_rule(24))
    assert errors(at_B.points, at_B.weights) > 1e-6


def test_duffy_rule_weights_and_polynomials():
    for grading, n in ((1, 5), (2, 6)):
        xi, w = duffy_rule(n, grading=grading)
        assert np.all(w > 0) and abs(w.sum() - 0.5) < 1e-15
        degree = 2 * n - 2 if grading == 1 else n - 2
        ref, ref_w = basix.make_quadrature(basix.CellType.triangle, degree)
        f = lambda X, p=degree: X[:, 0] ** (p - 1) * X[:, 1] + 1.0  # noqa: E731
        assert abs(w @ f(xi) - ref_w @ f(ref)) < 1e-15


def test_lip_rule_integrates_inverse_sqrt_of_the_distance_to_the_tip():
    phi, psi, tip, n, t = _straight("quadrilateral", 2, np.array([0.55, 0.45]), 0.3)
    cells = classify_crack("quadrilateral", 2, phi, psi)
    cut = cut_tip_cells("quadrilateral", 2, phi, psi, cells.tip)
    det = abs(np.linalg.det(A))
    length = np.hypot(*((cut.crack[0, 0] - cut.crack[0, 1]) @ A.T))
    grad = lambda rows, X: np.broadcast_to(A.T @ n, (len(rows), 2))  # noqa: E731
    errors = []
    for grading in (2, 1):
        lip = tip_lip_rule(cut, 8, _jacobian, grad, grading=grading)
        r = np.hypot(*((lip.points - cut.tip[0]) @ A.T).T)
        errors.append(abs(np.sum(lip.weights * det / np.sqrt(r)) - 2 * np.sqrt(length)))
    assert errors[0] < 1e-13 * np.sqrt(length) and errors[1] > 1e-4 * np.sqrt(length)


# --- a curved crack: a circular arc -----------------------------------------------------------
CENTRE, RADIUS, ALPHA = np.array([0.15, -0.9]), 1.0, 1.2  # the crack: angles > ALPHA


def _arc_cell(h, degree, cell_type):
    """Nodal phi, psi of a cell of size h (x = origin + h X) holding the arc's tip."""
    tip = CENTRE + RADIUS * np.array([np.cos(ALPHA), np.sin(ALPHA)])
    origin = tip - h * np.array([0.43, 0.27])
    d = origin + h * _nodes(cell_type, degree) - CENTRE
    phi = np.hypot(*d.T) - RADIUS
    psi = -RADIUS * (np.arctan2(d[:, 1], d[:, 0]) - ALPHA)
    return phi[None], psi[None], origin


def _arc_exact(h, origin, cell_type):
    """Area of the cell inside the circle (Green's formula) and the crack's length in it."""
    corners = origin + h * cell_data(cell_type, 1).loop_coords
    chain, enter = [], None  # boundary points inside the disc, counter-clockwise
    for k in range(len(corners)):
        p, e = corners[k], corners[(k + 1) % len(corners)] - corners[k]
        if np.hypot(*(p - CENTRE)) < RADIUS:
            chain.append(p)
        a, b, c = e @ e, 2 * e @ (p - CENTRE), (p - CENTRE) @ (p - CENTRE) - RADIUS**2
        root = np.sqrt(b * b - 4 * a * c) if b * b > 4 * a * c else np.nan
        for s in sorted(((-b - root) / (2 * a), (-b + root) / (2 * a))):
            if 0 < s < 1:
                chain.append(p + s * e)
                if 2 * a * s + b < 0:
                    enter = len(chain) - 1
    chain = np.roll(np.array(chain), -enter, axis=0)  # entry ... exit
    area = 0.5 * np.sum(chain[:-1, 0] * chain[1:, 1] - chain[1:, 0] * chain[:-1, 1])
    t1, t2 = np.arctan2(*(chain[[-1, 0]] - CENTRE)[:, ::-1].T) % (2 * np.pi)
    t2 = t2 if t2 > t1 else t2 + 2 * np.pi  # the arc from the exit back to the entry
    cx, cy = CENTRE
    area += 0.5 * (
        RADIUS**2 * (t2 - t1)
        + RADIUS * (cx * (np.sin(t2) - np.sin(t1)) - cy * (np.cos(t2) - np.cos(t1)))
    )
    ends = np.arctan2(*(chain[[0, -1]] - CENTRE)[:, ::-1].T)
    return area, RADIUS * (ends.max() - ALPHA)


def _arc_errors(degree, cell_type, sizes):
    errors = []
    for h in sizes:
        phi, psi, origin = _arc_cell(h, degree, cell_type)
        cells = classify_crack(cell_type, degree, phi, psi)
        cut = cut_tip_cells(cell_type, degree, phi, psi, cells.tip)
        area = tip_side_rules(cut, -1, 8).weights.sum() * h * h
        grad = lambda rows, X: np.broadcast_to([1.0, 0.0], (len(rows), 2))  # noqa: E731
        jac = lambda rows, X, h=h: np.broadcast_to(h * np.eye(2), (len(rows), 2, 2))  # noqa: E731
        length = tip_lip_rule(cut, 12, jac, grad).weights.sum() * h * h
        exact_area, exact_length = _arc_exact(h, origin, cell_type)
        errors.append((abs(area - exact_area), abs(length - exact_length)))
    return np.array(errors)


@pytest.mark.parametrize("cell_type", CELLS)
def test_curved_crack_area_and_length_converge(cell_type):
    """One cell of size h at the tip: with degree 2 (the interpolant's zero line O(h^3)
    from the arc, curved pieces and fans) the area error is O(h^4), the length error
    O(h^3); degree 1 (straight pieces) is an order lower in both."""
    sizes = 0.4 / 2.0 ** np.arange(5)
    e2, e1 = _arc_errors(2, cell_type, sizes), _arc_errors(1, cell_type, sizes)
    rates = np.log2(e2[:-1] / e2[1:])
    assert np.all(rates[-2:, 0] > 3.8) and np.all(rates[-2:, 1] > 2.9), rates
    assert np.all(e2[-1] < 0.05 * e1[-1])
