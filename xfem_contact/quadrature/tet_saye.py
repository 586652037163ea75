"""Saye's rules on the reference tetrahedron itself: boxes of the unit cube truncated by
the tetrahedron's slanted face, for P2 level sets (pure numpy).

The reference tetrahedron is the unit cube cut by the half-space ``x + y + z <= 1``. Its
P2 level set ``psi`` is a polynomial of total degree 2 in the reference coordinates, so
the tensor machinery of :mod:`xfem_contact.geometry.tensor_levelset` applies unchanged
(monomial coefficients, Bernstein sign certificates on boxes). A *truncated box* is a box
``[lo, hi]`` of the cube intersected with that half-space; the algorithm is Saye's
(:mod:`xfem_contact.quadrature.saye`) on truncated boxes:

1. A box whose Bernstein coefficients have one sign lies on one side: a tensor rule if
   ``hi`` lies in the half-space, else the nested rule of step 3 without roots.
2. Otherwise the height axis ``k3`` and the axis ``k2`` are Saye's for the whole box; a
   box that reaches the slanted face also needs ``psi`` monotone along the face in the
   ``k2`` direction (``e_k2 - e_k3``), else the box is subdivided. Near-ties between pairs
   are broken as Saye's (:mod:`xfem_contact.quadrature.saye_axes`), and a pair whose
   score is within :data:`~xfem_contact.quadrature.saye_axes.SCORE_TOLERANCE` of zero (a
   slope certified by round-off only) is not valid.
3. Nested one-dimensional Gauss-Legendre rules: along ``k1`` between the roots of ``psi``
   on the truncated box's edges (the box edges parallel to ``k1``, clipped, and the
   slanted face's lines on the faces of constant ``k2`` or ``k3``) and the abscissae of
   its vertices; at each point, along ``k2`` between the roots of ``psi`` on the bottom
   face, the top face and the slanted face, and the kink where the top of the height line
   leaves the box's top face for the slanted face; at each of those, along ``k3`` up to
   ``min(hi_k3, 1 - x_k1 - x_k2)`` between the roots of ``psi``. Breakpoints along ``k1``
   and ``k2`` within :data:`~xfem_contact.quadrature.saye.BREAK_TOLERANCE` of each other
   are one (the same crossing found on two edges or faces), so that a few ulps in ``psi``
   do not change a rule.

4. Raised orders: the rules of every cut box are also computed with ``order - 1`` points
   per interval, and a box whose interface area or side -1 volume moves by more than its
   cell's ``raise_tolerance`` (reference units) between the two gets ``2 order`` points.
   These are the boxes near branch points of the roots (high curvature of the zero set
   in the cell, shallow slopes), where Gauss rules converge slowly; elsewhere the rules
   keep ``order`` points. A raised box whose rules still move by more than
   ``raise_tolerance`` from ``order`` to ``2 order`` points is subdivided (above
   ``max_depth``).

Given the level set that ``psi`` interpolates as a function (``exact``), the boxes and
axes stay ``psi``'s (a box lies on one side only when ``psi``'s Bernstein coefficients
keep their sign by the cell's ``margin``, a bound of ``|exact - psi|``, at every depth:
raised boxes that still move are subdivided down to ``max_depth``, where a thin lens of
the exact zero set is as likely as above), but the
breakpoints of every line (the slanted face's included) are the function's roots near
``psi``'s, the sides of the height intervals its signs and the area vectors its
gradient, as in :mod:`xfem_contact.quadrature.saye`.

Every breakpoint is a root of ``psi`` restricted to a straight line, every interval end
an affine function of the outer coordinates: for a planar ``psi`` the rules integrate
polynomials of degree ``2 order - 1`` per direction exactly, and for a curved one their
error falls with the curvature of ``psi`` in the cell (the mesh size times the
interface's curvature), not only with ``order``. All weights are positive. A box
with axes is still subdivided while a slope its roots depend on is small against the
second derivatives of ``psi`` times the box size
(:data:`~xfem_contact.quadrature.tet_saye_axes.CURVED`). At ``max_depth`` a box
without a valid pair uses the best monotone height axis alone (the cell is reported
``reduced``); a cell with a box that has none is reported unresolved (the caller
integrates it otherwise).

Side -1 is ``psi < 0``, side +1 ``psi >= 0``; the interface bounding side -1, as in
:mod:`xfem_contact.quadrature.saye` (a root at the end of a height line counts only
when ``psi < 0`` inside next to it).
"""

from __future__ import annotations

import functools
import itertools

import numpy as np

from xfem_contact.geometry import exact_lines
from xfem_contact.geometry.exact_lines import ExactLevelSet, central_gradient
from xfem_contact.geometry.tensor_levelset import (
    bernstein,
    derivative,
    evaluate,
    gradient,
    line_coefficients,
    line_roots,
)
from xfem_contact.quadrature.saye import (
    SayePoints,
    _gather,
    _pieces,
    _subdivide,
    _tensor_rule,
    certified_boxes,
    check_parameters,
)
from xfem_contact.quadrature.saye_axes import PAIRS
from xfem_contact.quadrature.tet_saye_axes import CURVED_DEPTH, curved_boxes, truncated_axes

__all__ = ["MIN_SLOPE", "truncated_saye_points"]

MIN_SLOPE = 0.2
"""Boxes inside the tetrahedron whose best pair of axes scores below this are subdivided,
as Saye's boxes of the unit cube by :data:`xfem_contact.quadrature.saye.MIN_SLOPE`; lower
here, where the boxes are those of a sixth of a cube and
:data:`~xfem_contact.quadrature.tet_saye_axes.CURVED` subdivides the
curved ones too."""


def truncated_saye_points(
    C: np.ndarray,
    order: int,
    *,
    max_depth: int,
    min_depth: int = 0,
    raise_tolerance: float | np.ndarray | None = None,
    exact: ExactLevelSet | None = None,
    margin: np.ndarray | None = None,
) -> tuple[SayePoints, np.ndarray]:
    """Saye's rules on the reference tetrahedron of P2 polynomials (see the module).

    Args:
        C: Monomial coefficients in the tetrahedron's reference coordinates, shape
            ``(ncells, 3, 3, 3)``, of polynomials of total degree <= 2.
        order: Gauss-Legendre points per interval.
        max_depth: Box subdivision levels.
        min_depth: Levels of boxes subdivided whenever the interface may cross them.
        raise_tolerance: The rules of each cut box are also computed with
            ``max(1, order - 1)`` points per interval; a box whose interface area or side
            -1 volume (reference units) differs between the two by more than this (one
            value, or one per cell ``(ncells,)``) gets rules of ``2 order`` points instead
            (where the roots' branch points are close to the box, the rules converge
            slowly). ``None``: ``order`` everywhere.
        exact: ``(rows, X) -> (m,)``: the level set that ``C`` interpolates, at points
            ``X`` ``(m, 3)`` of the reference tetrahedron of cells ``rows``; the boxes and
            axes stay ``C``'s, but the breakpoints of every line are its roots near
            ``C``'s (:func:`~xfem_contact.geometry.exact_lines.line_roots`), the sides of
            the height intervals its signs and the interface's area vectors its gradient
            (:func:`~xfem_contact.geometry.exact_lines.central_gradient`). ``None``:
            ``C``'s zero set.
        margin: Per cell ``(ncells,)``, a bound of ``|exact - psi|`` on it
            (:func:`~xfem_contact.geometry.exact_margin.exact_margin`): at every depth,
            ``max_depth`` included, a box lies on one side only when ``psi``'s Bernstein
            coefficients are all ``< -margin`` or all ``>= margin`` (else its rules look
            for ``exact``'s roots; a box at ``max_depth`` without a monotone axis leaves
            its cell unresolved). ``None``: 0.

    Returns:
        The points of the resolved cells (a :class:`~xfem_contact.quadrature.saye.SayePoints`;
        ``reduced``: cells where a box at ``max_depth`` used the height axis alone) and
        the sorted rows of the unresolved cells (a box at ``max_depth`` with no monotone
        axis), which have no points.

    Raises:
        ValueError: Bad ``order``, ``max_depth`` or ``min_depth``.
    """
    check_parameters(order, max_depth, min_depth)
    ncells = C.shape[0]
    tolerance = None
    if raise_tolerance is not None:
        tolerance = np.broadcast_to(np.asarray(raise_tolerance, dtype=np.float64), (ncells,))
        if not (tolerance >= 0).all():
            raise ValueError(f"raise_tolerance must be >= 0 or None, got {raise_tolerance!r}")
    gauss = _gauss(order)
    parts: dict[str, list[tuple[np.ndarray, ...]]] = {"minus": [], "plus": [], "interface": []}
    unresolved, reduced = [], []
    cell = np.arange(ncells)
    lo, hi = np.zeros((ncells, 3)), np.ones((ncells, 3))
    for depth in range(max_depth + 1):
        if cell.size == 0:
            break
        B = bernstein(C[cell], lo, hi)
        truncated = hi.sum(axis=1) > 1.0
        sides = certified_boxes(B, margin, cell)
        for side, whole in sides.items():
            plain = whole & ~truncated
            parts[side].append(_tensor_rule(cell[plain], lo[plain], hi[plain], gauss))
            clipped = whole & truncated
            if clipped.any():
                _clipped_rules(C, cell[clipped], lo[clipped], hi[clipped], 2, 1, gauss, parts, side)
        rest = ~(sides["minus"] | sides["plus"])
        cell, lo, hi, B = cell[rest], lo[rest], hi[rest], B[rest]
        if cell.size == 0:
            break
        if depth < min_depth:
            pair = np.full(cell.size, -1)
        else:
            DB = [bernstein(derivative(C[cell], k), lo, hi) for k in range(3)]
            pair, height, score = truncated_axes(C[cell], lo, hi, B, DB)
            if depth < max_depth:  # shallow slopes: steep roots, slow rules; subdivide
                shallow = (score < MIN_SLOPE) & (hi.sum(axis=1) <= 1.0)  # boxes of Saye's own
                pair = np.where(shallow, -1, pair)
            if depth < min(max_depth, CURVED_DEPTH):
                pair = np.where(curved_boxes(C[cell], lo, hi, B, DB, pair), -1, pair)
            if depth == max_depth:  # the best monotone height axis alone, as Saye's
                fallback = (pair < 0) & (height >= 0)
                reduced.append(cell[fallback])
                lone = [PAIRS.index((k, (k + 1) % 3)) for k in range(3)]
                pair = np.where(fallback, np.take(lone, np.maximum(height, 0)), pair)
        unsettled = []
        for index, (k3, k2) in enumerate(PAIRS):
            group = np.flatnonzero(pair == index)
            if group.size:
                box = (cell[group], lo[group], hi[group], k3, k2)
                split = depth < max_depth
                allowed = None if tolerance is None else tolerance[box[0]]
                moving = _raised_rules(C, box, order, parts, allowed, exact, split)
                unsettled.append(group[moving])
        subdivided = pair < 0
        if unsettled:
            subdivided[np.concatenate(unsettled)] = True
        if depth == max_depth:
            unresolved.append(cell[subdivided])
            break
        cell, lo, hi = _subdivide(cell[subdivided], lo[subdivided], hi[subdivided])
        inside = lo.sum(axis=1) < 1.0  # children touching the half-space in a point at most go
        cell, lo, hi = cell[inside], lo[inside], hi[inside]
    bad = np.unique(np.concatenate(unresolved)).astype(np.int64) if unresolved else np.zeros(0, int)
    gathered = []
    for side, widths in (("minus", (1, 3, 1)), ("plus", (1, 3, 1)), ("interface", (1, 3, 1, 3))):
        columns = _gather(parts[side], widths)
        if bad.size:
            keep = ~np.isin(columns[0], bad)
            columns = [c[keep] for c in columns]
        gathered.append(tuple(columns))
    reduced = np.unique(np.concatenate([np.zeros(0, int), *reduced])).astype(np.int64)
    return SayePoints(*gathered, reduced[~np.isin(reduced, bad)]), bad


@functools.cache
def _gauss(order: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights of ``order`` points on ``[0, 1]``."""
    gx, gw = np.polynomial.legendre.leggauss(order)
    return 0.5 * (gx + 1.0), 0.5 * gw


def _raised_rules(C, box, order, parts, tolerance, exact, split):
    """Nested rules of the cut truncated boxes ``box = (cell, lo, hi, k3, k2)`` with
    ``order`` points per interval, and ``2 order`` in the boxes whose rules move by more
    than ``tolerance`` ``(m,)`` from ``max(1, order - 1)`` points (see
    :func:`truncated_saye_points`),
    appended to ``parts``. With ``split``, a raised box whose rules still move by more
    than ``tolerance`` from ``order`` to ``2 order`` points (Gauss rules converging
    slowly: a branch point of the roots in or near the box) gets no rules; the mask
    ``(m,)`` of those boxes is returned (to be subdivided)."""
    cell, lo, hi, k3, k2 = box
    low = max(1, order - 1)
    if tolerance is None or low == order:
        _clipped_rules(C, cell, lo, hi, k3, k2, _gauss(order), parts, None, exact)
        return np.zeros(cell.size, dtype=bool)
    m = cell.size
    local = np.arange(m)
    Cb = C[cell]
    on_box = None if exact is None else (lambda rows, X: exact(cell[rows], X))
    found, coarse = ({"minus": [], "plus": [], "interface": []} for _ in range(2))
    _clipped_rules(Cb, local, lo, hi, k3, k2, _gauss(order), found, None, on_box)
    _clipped_rules(Cb, local, lo, hi, k3, k2, _gauss(low), coarse, None, on_box)
    moved = np.zeros(m, dtype=bool)
    for measure in (_box_areas, _box_volumes):
        moved |= np.abs(measure(found, m) - measure(coarse, m)) > tolerance
    unsettled = np.zeros(m, dtype=bool)
    if moved.any():
        raised = np.flatnonzero(moved)
        fine = {"minus": [], "plus": [], "interface": []}
        on_raised = None if exact is None else (lambda rows, X: exact(cell[raised[rows]], X))
        _clipped_rules(
            Cb[raised], local[: raised.size], lo[raised], hi[raised], k3, k2,
            _gauss(2 * order), fine, None, on_raised,
        )  # fmt: skip
        if split:
            r = raised.size
            for measure in (_box_areas, _box_volumes):
                change = np.abs(measure(fine, r) - measure(found, m)[raised])
                unsettled[raised] |= change > tolerance[raised]
        keep_fine = ~unsettled[raised]
        for side, pieces in fine.items():
            for rows, *columns in pieces:
                keep = keep_fine[rows]
                parts[side].append((cell[raised[rows[keep]]], *(c[keep] for c in columns)))
    for side, pieces in found.items():
        for rows, *columns in pieces:
            keep = ~moved[rows]
            parts[side].append((cell[rows[keep]], *(c[keep] for c in columns)))
    return unsettled


def _box_areas(parts, m):
    """Interface area (reference units) per box of ``parts`` (rows: boxes), ``(m,)``."""
    areas = np.zeros(m)
    for rows, _, w, area in parts["interface"]:
        areas += np.bincount(rows, w * np.linalg.norm(area, axis=1), minlength=m)
    return areas


def _box_volumes(parts, m):
    """Side -1 volume per box of ``parts`` (rows: boxes), ``(m,)``."""
    volumes = np.zeros(m)
    for rows, _, w in parts["minus"]:
        volumes += np.bincount(rows, w, minlength=m)
    return volumes


def _slanted_line(C, P0, a, b):
    """Coefficients ``(m, 3)`` in ``t`` of ``psi(P0 + t (e_a - e_b))`` (total degree 2)."""
    Dd = derivative(C, a) - derivative(C, b)
    Ddd = derivative(Dd, a) - derivative(Dd, b)
    return np.stack([evaluate(C, P0), evaluate(Dd, P0), 0.5 * evaluate(Ddd, P0)], axis=1)


def _roots_between(c, a, b, exact=None, X=None, axis=None, back=None):
    """Roots ``(m, 2)`` of polynomials ``c`` in ``[a, b]`` (NaN: none or an empty range).
    With ``exact`` (``(lines, Y) -> (k,)``), its roots near those of ``c`` on the lines
    through ``X`` ``(m, 3)`` whose ``axis`` coordinate is the parameter; ``back``: the axis
    that goes down as ``axis`` goes up (a line of the slanted face), else ``None``."""
    b_ = np.maximum(a, b)
    if exact is None:
        r = line_roots(c, a, b_)
    else:
        on_line = exact
        if back is not None:

            def on_line(lines, Y):
                Z = Y.copy()
                Z[:, back] = X[lines, back] - (Y[:, axis] - X[lines, axis])
                return exact(lines, Z)

        r = exact_lines.line_roots(on_line, X, axis, a, b_, c)
    return np.where((b > a)[:, None], r, np.nan)


def _inside(values, a, b):
    """``values`` ``(m,)`` strictly inside ``(a, b)``, else NaN, as a column ``(m, 1)``."""
    return np.where((values > a) & (values < b), values, np.nan)[:, None]


def _clipped_rules(C, cell, lo, hi, k3, k2, gauss, parts, side, exact=None):
    """Nested Gauss rules of truncated boxes sharing the axes ``k3`` (height) and ``k2``;
    ``side``: ``"minus"`` / ``"plus"`` for boxes certified on one side (no roots), else
    ``None``; ``exact``: the level set ``C`` interpolates, as a function of ``(cell, X)``
    (its roots, signs and gradient), or ``None``."""

    def on(rows):
        """``exact`` on the lines of boxes ``rows``."""
        return None if exact is None else (lambda lines, Y: exact(cell[rows[lines]], Y))

    k1 = 3 - k3 - k2
    m = cell.size
    C1 = C[cell]
    lo1, hi1, lo2, hi2, lo3, hi3 = lo[:, k1], hi[:, k1], lo[:, k2], hi[:, k2], lo[:, k3], hi[:, k3]
    top1 = np.minimum(hi1, 1.0 - lo2 - lo3)
    # level 1: along k1, breakpoints at the vertices and at the roots on the edges
    breaks = [
        _inside(1.0 - c2 - c3, lo1, top1) for c2, c3 in itertools.product((lo2, hi2), (lo3, hi3))
    ]
    if side is None:
        for c2, c3 in itertools.product((lo2, hi2), (lo3, hi3)):  # box edges parallel to k1
            X = np.zeros((m, 3))
            X[:, k2], X[:, k3] = c2, c3
            end = np.minimum(hi1, 1.0 - c2 - c3)
            c = line_coefficients(C1, k1, X)
            breaks.append(_roots_between(c, lo1, end, on(np.arange(m)), X, k1))
        for fixed, free, (c_lo, c_hi) in ((k2, k3, (lo3, hi3)), (k3, k2, (lo2, hi2))):
            for c in (lo[:, fixed], hi[:, fixed]):  # the slanted face on the face x_fixed = c
                P0 = np.zeros((m, 3))
                P0[:, fixed], P0[:, free] = c, 1.0 - c
                a = np.maximum(lo1, 1.0 - c - c_hi)
                b = np.minimum(hi1, 1.0 - c - c_lo)
                c = _slanted_line(C1, P0, k1, free)
                breaks.append(_roots_between(c, a, b, on(np.arange(m)), P0, k1, free))
    box1, u, w1, _, _ = _pieces(np.concatenate(breaks, axis=1), lo1, top1, gauss, merge=True)
    # level 2: along k2 at each u, breakpoints at the kink and the roots on the three faces
    lo2, hi2, lo3, hi3 = lo2[box1], hi2[box1], lo3[box1], hi3[box1]
    top2 = np.minimum(hi2, 1.0 - u - lo3)
    kink = 1.0 - u - hi3
    breaks = [_inside(kink, lo2, top2)]
    if side is None:
        C1 = C1[box1]
        X = np.zeros((u.size, 3))
        X[:, k1] = u
        for c, end in ((lo3, top2), (hi3, np.minimum(top2, kink))):
            X[:, k3] = c
            line = line_coefficients(C1, k2, X)
            breaks.append(_roots_between(line, lo2, end, on(box1), X, k2))
        P0 = np.zeros((u.size, 3))
        P0[:, k1], P0[:, k3] = u, 1.0 - u
        line = _slanted_line(C1, P0, k2, k3)
        breaks.append(_roots_between(line, np.maximum(lo2, kink), top2, on(box1), P0, k2, k3))
    p1, v, w2, _, _ = _pieces(np.concatenate(breaks, axis=1), lo2, top2, gauss, merge=True)
    box2 = box1[p1]
    W = w1[p1] * w2
    X = np.zeros((v.size, 3))
    X[:, k1], X[:, k2] = u[p1], v
    lo3 = lo3[p1]
    top3 = np.minimum(hi3[p1], 1.0 - X[:, k1] - v)
    # level 3: along k3 at each (u, v), breakpoints at the roots of psi
    if side is None:
        C2 = C1[p1]
        r = _roots_between(line_coefficients(C2, k3, X), lo3, top3, on(box2), X, k3)
    else:
        r = np.full((v.size, 0), np.nan)
    p2, w, w3, piece, (pline, mid) = _pieces(r, lo3, top3, gauss)
    Xq = X[p2].copy()
    Xq[:, k3] = w
    weights = W[p2] * w3
    rows = cell[box2[p2]]
    if side is not None:
        parts[side].append((rows, Xq, weights))
        return
    Xmid = X[pline].copy()
    Xmid[:, k3] = mid
    if exact is None:
        negative = evaluate(C2[pline], Xmid) < 0
    else:
        negative = exact(cell[box2[pline]], Xmid) < 0
    for name, keep in (("minus", negative[piece]), ("plus", ~negative[piece])):
        parts[name].append((rows[keep], Xq[keep], weights[keep]))
    # interface: each root of a height line bounding side -1
    for j in range(r.shape[1]):
        line = np.flatnonzero(~np.isnan(r[:, j]))
        Xs = X[line].copy()
        Xs[:, k3] = r[line, j]
        if exact is None:
            grad = gradient(C2[line], Xs)
        else:
            grad = central_gradient(lambda Y, c=cell[box2[line]]: exact(c, Y), Xs)
        slope = grad[:, k3]
        at_lo, at_hi = r[line, j] == lo3[line], r[line, j] == top3[line]
        bounding = ~(at_lo | at_hi) | (at_hi & (slope > 0)) | (at_lo & (slope < 0))
        bounding &= slope != 0
        if j == 1:  # a double root (both columns equal) is one point
            bounding &= ~(r[line, 1] == r[line, 0])
        line, Xs, grad, slope = line[bounding], Xs[bounding], grad[bounding], slope[bounding]
        parts["interface"].append((cell[box2[line]], Xs, W[line], grad / np.abs(slope)[:, None]))
