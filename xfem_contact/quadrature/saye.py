"""Saye's quadrature on hexahedra cut by Q1/Q2 level sets: rules of both sides and of the
interface by dimension reduction and root finding (R. Saye, SISC 2015), pure numpy.

On a box ``U = [lo, hi]`` of the reference cube, with ``psi`` the cell's level set
(:mod:`xfem_contact.geometry.tensor_levelset`):

1. If the Bernstein coefficients of ``psi`` on ``U`` are all ``>= 0`` (all ``< 0``) the box
   lies on side +1 (-1): a tensor Gauss-Legendre rule.
2. Otherwise choose a *height* axis ``k3`` along which ``psi`` is monotone (the Bernstein
   coefficients of ``d psi / d x_k3`` have one strict sign) and an axis ``k2`` along which
   each face function ``psi(x_k3 = lo_k3)``, ``psi(x_k3 = hi_k3)`` is monotone or free of
   zeros (coefficients of one strict sign, or all zero); ``k1`` is the third axis. Of the
   valid pairs the one whose certified slopes are steepest wins: the lower bound of
   ``|d psi / d x_k3|`` relative to the bound of ``|grad psi|``, and of
   ``|d psi / d x_k2|`` relative to the face gradient for face functions with zeros
   (steep slopes keep the roots smooth functions of the outer coordinates); near ties are
   broken so that round-off does not change the choice
   (:func:`~xfem_contact.quadrature.saye_axes.choose_axes`).
3. Nested one-dimensional Gauss-Legendre rules (``order`` points per interval): along
   ``k1`` on the intervals between the roots of ``psi`` on the four box edges parallel to
   ``k1`` (roots within :data:`BREAK_TOLERANCE` of each other are one); at each such point,
   along ``k2`` between the roots of the two face functions; at each of those, along
   ``k3`` between the roots of ``psi`` itself. Each innermost interval goes to the side
   of ``psi`` at its midpoint, and each root ``w`` of the height line gives an interface
   point with area vector
   ``grad psi / |d psi / d x_k3|`` (reference coordinates) and the weight of its line.
   Every integrand is smooth between the breakpoints, so the rules converge at the rate
   of Gauss-Legendre rules; all weights are positive.
4. When no pair is valid, or the best pair's certified slopes (its score in step 2) are
   below :data:`MIN_SLOPE`, or above ``min_depth`` for every box the interface may cross,
   the box is subdivided into eight, down to ``max_depth`` levels; a box
   at that depth that still has none uses the best monotone height axis alone (a
   lower-order rule on a box of size ``2^-max_depth``; the cell is reported in
   :attr:`CutRules.reduced`), and one with no monotone axis at all (a singular
   point of the zero set: a saddle or a cone) is refused with a ``ValueError`` naming
   the cell and the box.

Given the level set that ``psi`` interpolates as a function (``exact``), the boxes and axes
stay ``psi``'s, but the breakpoints of every line are the function's roots, the sides of the
height intervals its signs, and the area vectors its gradient: the rules follow its zero set
(:func:`hex_cut_rules`).

Tolerance policy, as for tetrahedra (:mod:`xfem_contact.geometry.cut_tets`): ``psi < 0`` is
side -1, ``psi >= 0`` side +1, decided by exact comparisons of Bernstein coefficients and
of ``psi`` at interval midpoints; roots within ``16 eps`` (relative to the interval) of an
end are that end. The interface of a box is the zero set bounding its side -1: a root at
an end of a height line counts only when ``psi < 0`` inside next to it, so a face where
``psi`` vanishes belongs to the cell on its negative side.

Points are in the parent's reference coordinates, weights in the reference measure;
interface rules go through :func:`~xfem_contact.quadrature.surface_rules.surface_rules`.
All work is vectorised over boxes and points; Python loops run over subdivision levels,
the six axis pairs and the few breakpoints of a line.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry import exact_lines
from xfem_contact.geometry.exact_lines import ExactLevelSet, central_gradient
from xfem_contact.geometry.tensor_levelset import (
    bernstein,
    coefficients,
    evaluate,
    gradient,
    line_coefficients,
    line_roots,
)
from xfem_contact.quadrature.rules import RuleSet
from xfem_contact.quadrature.saye_axes import PAIRS, choose_axes
from xfem_contact.quadrature.surface_rules import Jacobian, surface_rules

__all__ = [
    "MAX_DEPTH",
    "MIN_SLOPE",
    "CutRules",
    "SayePoints",
    "certified_boxes",
    "certified_sides",
    "check_parameters",
    "classify_hexes",
    "hex_cut_rules",
    "rules_from_points",
    "saye_points",
]

MAX_DEPTH = 6
"""Default number of box subdivision levels of :func:`hex_cut_rules`."""

BREAK_TOLERANCE = 1e-12
"""Breakpoints of the outer lines (levels 1 and 2) closer than this, relative to the line's
length, are one: the same crossing found on two edges of a symmetric box gives one
breakpoint, not an interval of a few ulps whose presence round-off decides."""

MIN_SLOPE = 0.4
"""Boxes whose best pair of axes has certified slopes below this score (the lower bound of a
slope relative to the gradient's bound, step 2 of the module) are subdivided, down to
``max_depth``: on such boxes the roots are steep functions of the outer coordinates and
the Gauss rules converge slowly (the docs' 3D cut page gives the errors measured). The
tetrahedron frame has its own (:data:`xfem_contact.quadrature.tet_saye.MIN_SLOPE`)."""


@dataclass(frozen=True)
class CutRules:
    """Rules of cells cut by a level set, one rule per cell (row of ``phi``).

    Attributes:
        minus: Side -1, points ``(N, 3)`` in reference coordinates, weights in the
            reference measure (all positive).
        plus: Side +1, likewise.
        interface: Interface, weights ``ds / |det J|`` and unit normals ``(N, 3)`` from
            side -1 to side +1 (see
            :func:`~xfem_contact.quadrature.surface_rules.surface_rules`).
        reduced: Rows of the cells where a box at the maximum depth used the lower-order
            rule (see the module), sorted.
    """

    minus: RuleSet
    plus: RuleSet
    interface: RuleSet
    reduced: npt.NDArray[np.int64]


def classify_hexes(phi: npt.ArrayLike, degree: int) -> npt.NDArray[np.int8]:
    """Side of each hexahedron certified by the Bernstein coefficients of its level set:
    -1 (all ``< 0``), +1 (all ``>= 0``) or 0 (possibly cut: :func:`hex_cut_rules` decides).

    Args:
        phi: Nodal values, shape ``(ncells, (degree + 1)^3)`` (Basix order).
        degree: 1 or 2.

    Returns:
        ``int8`` array of shape ``(ncells,)``.
    """
    return certified_sides(coefficients(phi, degree))


def certified_sides(C: np.ndarray) -> npt.NDArray[np.int8]:
    """-1 / +1 / 0 per polynomial ``C`` ``(n, p+1, p+1, p+1)`` on the unit cube by its
    Bernstein coefficients (see :func:`classify_hexes`)."""
    n = C.shape[0]
    B = bernstein(C, np.zeros((n, 3)), np.ones((n, 3))).reshape(n, int(np.prod(C.shape[1:])))
    return np.where((B < 0).all(axis=1), -1, np.where((B >= 0).all(axis=1), 1, 0)).astype(np.int8)


def hex_cut_rules(
    phi: npt.ArrayLike,
    degree: int,
    order: int = 4,
    *,
    max_depth: int = MAX_DEPTH,
    jacobian: Jacobian | None = None,
    exact: ExactLevelSet | None = None,
) -> CutRules:
    """Saye's rules of both sides and of the interface of every cell (see the module).

    With ``exact``, the level set that ``phi`` interpolates, the boxes and their axes are
    still chosen on the polynomial, but the breakpoints of every line are the exact level
    set's roots near the polynomial's (:func:`~xfem_contact.geometry.exact_lines.line_roots`),
    the side of each height interval is its sign at the midpoint, and the interface's area
    vector is its gradient (:func:`~xfem_contact.geometry.exact_lines.central_gradient`):
    the rules integrate the exact level set's sides and zero set in the cut cells.

    Args:
        phi: Nodal values, shape ``(ncells, (degree + 1)^3)`` (Basix ``gll_warped`` order).
        degree: Level-set degree, 1 (Q1) or 2 (Q2).
        order: Gauss-Legendre points per interval (exact for one-dimensional
            polynomials of degree ``2 order - 1``).
        max_depth: Box subdivision levels.
        jacobian: ``(rows, X) -> (m, 3, 3)`` parent Jacobians for the interface rule;
            ``None``: reference cells.
        exact: ``(rows, X) -> (m,)``: the exact level set at reference points ``X``
            ``(m, 3)`` of cells ``rows`` (see :data:`ExactLevelSet`); ``None``: the
            polynomial's zero set.

    Returns:
        A :class:`CutRules`; a cell entirely on one side gets a tensor rule there.

    Raises:
        ValueError: Bad input, or a cell whose zero set has a singular point (no monotone
            axis in a box at ``max_depth``); the message names the cell and the box.
    """
    C = coefficients(phi, degree)
    ncells = C.shape[0]
    points = saye_points(C, order, max_depth=max_depth, exact=exact)
    rows, X, w, area = points.interface
    return CutRules(
        rules_from_points(*points.minus, ncells),
        rules_from_points(*points.plus, ncells),
        surface_rules(X, area, w, rows, ncells, jacobian),
        points.reduced,
    )


@dataclass(frozen=True)
class SayePoints:
    """Saye's rules on the unit cube of tensor polynomials, as point lists sorted by row.

    Attributes:
        minus: ``(rows (N,), X (N, 3), w (N,))`` of side -1, weights in the cube's measure.
        plus: Likewise for side +1.
        interface: ``(rows, X, w, area)``: weights in the surface parameter and area
            vectors ``(N, 3)`` (see :mod:`xfem_contact.quadrature.surface_rules`).
        reduced: Rows where a box at the maximum depth used the lower-order rule, sorted.
    """

    minus: tuple[np.ndarray, np.ndarray, np.ndarray]
    plus: tuple[np.ndarray, np.ndarray, np.ndarray]
    interface: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    reduced: npt.NDArray[np.int64]


def saye_points(
    C: np.ndarray,
    order: int,
    *,
    max_depth: int = MAX_DEPTH,
    min_depth: int = 0,
    kind: str = "hexahedron",
    first: int = 0,
    exact: ExactLevelSet | None = None,
    names: npt.ArrayLike | None = None,
    margin: np.ndarray | None = None,
) -> SayePoints:
    """Saye's rules (see the module) of polynomials on the unit cube.

    Args:
        C: Monomial coefficients, shape ``(ncells, p + 1, p + 1, p + 1)``
            (:func:`~xfem_contact.geometry.tensor_levelset.coefficients`).
        order: Gauss-Legendre points per interval.
        max_depth: Box subdivision levels.
        min_depth: Levels of boxes subdivided whenever the interface may cross them, before
            the axes are chosen (finer boxes for level sets that are not polynomials of
            low degree in the cell's own coordinates).
        kind: The cells' name in error messages.
        first: The number of row 0 of ``C`` in error messages.
        exact: The level set the polynomials interpolate, as a function of
            ``(rows, U)`` (see :data:`ExactLevelSet`): the roots on every line, the sides
            of the height intervals and the interface's area vectors are then its own
            (see :func:`hex_cut_rules`); ``None``: the polynomials'.
        names: Per row of ``C``, its number in error messages (added to ``first``);
            ``None``: the row itself.
        margin: Per row ``(ncells,)``, a bound of ``|exact - psi|`` on the cube: above
            ``max_depth`` a box lies on one side only when its Bernstein coefficients are
            all ``< -margin`` or all ``>= margin`` (:func:`certified_boxes`). ``None``: 0.

    Returns:
        A :class:`SayePoints`.

    Raises:
        ValueError: Bad ``order`` or ``max_depth``, or a singular point of a zero set.
    """
    check_parameters(order, max_depth, min_depth)
    ncells = C.shape[0]
    gx, gw = np.polynomial.legendre.leggauss(order)
    gauss = (0.5 * (gx + 1.0), 0.5 * gw)
    parts: dict[str, list[tuple[np.ndarray, ...]]] = {"minus": [], "plus": [], "interface": []}
    reduced = []
    cell = np.arange(ncells)
    lo, hi = np.zeros((ncells, 3)), np.ones((ncells, 3))
    for depth in range(max_depth + 1):
        if cell.size == 0:
            break
        B = bernstein(C[cell], lo, hi)
        sides = certified_boxes(B, None if depth == max_depth else margin, cell)
        for side, whole in sides.items():
            parts[side].append(_tensor_rule(cell[whole], lo[whole], hi[whole], gauss))
        rest = ~(sides["minus"] | sides["plus"])
        cell, lo, hi, B = cell[rest], lo[rest], hi[rest], B[rest]
        if cell.size == 0:
            break
        if depth < min_depth:  # subdivide every box that the interface may cross
            pair, height = np.full(cell.size, -1), np.full(cell.size, -1)
        else:
            pair, height, score = choose_axes(C[cell], lo, hi, B)
            if depth < max_depth:  # shallow slopes: steep roots, slow rules; subdivide
                pair = np.where(score < MIN_SLOPE, -1, pair)
        if depth == max_depth:
            bad = np.flatnonzero((pair < 0) & (height < 0))
            if bad.size:
                b = bad[0]
                name = cell[b] if names is None else np.asarray(names)[cell[b]]
                raise ValueError(
                    f"{kind} {first + name}: the level set has a singular point on its zero set "
                    f"in the box {lo[b].tolist()} .. {hi[b].tolist()} (unit-cube coordinates; "
                    f"no monotone axis after {max_depth} subdivisions); {bad.size} box(es)"
                )
            fallback = pair < 0
            reduced.append(cell[fallback])
            pair = np.where(fallback, [PAIRS.index((k, (k + 1) % 3)) for k in height], pair)
        for index, (k3, k2) in enumerate(PAIRS):
            group = pair == index
            if group.any():
                _box_rules(C, cell[group], lo[group], hi[group], (k3, k2), gauss, parts, exact)
        subdivided = pair < 0
        cell, lo, hi = _subdivide(cell[subdivided], lo[subdivided], hi[subdivided])
    return SayePoints(
        tuple(_gather(parts["minus"], (1, 3, 1))),
        tuple(_gather(parts["plus"], (1, 3, 1))),
        tuple(_gather(parts["interface"], (1, 3, 1, 3))),
        np.unique(np.concatenate(reduced)).astype(np.int64) if reduced else np.zeros(0, np.int64),
    )


def certified_boxes(
    B: np.ndarray, margin: np.ndarray | None, cell: np.ndarray
) -> dict[str, np.ndarray]:
    """Boxes on one side, ``{"minus": (m,) bool, "plus": (m,) bool}``, by the Bernstein
    coefficients ``B`` ``(m, ...)`` of the polynomial on them: all ``< -margin[cell]``
    (side -1) or all ``>= margin[cell]`` (side +1); ``margin`` ``None``: 0 (the polynomial's
    own sides). A box of neither may be cut."""
    flat = B.reshape(B.shape[0], int(np.prod(B.shape[1:])))  # no boxes: (0, k)
    if margin is None:
        return {"minus": (flat < 0).all(axis=1), "plus": (flat >= 0).all(axis=1)}
    m = margin[cell][:, None]
    return {"minus": (flat < -m).all(axis=1), "plus": (flat >= m).all(axis=1)}


def check_parameters(order: int, max_depth: int, min_depth: int) -> None:
    """Raise a ``ValueError`` naming a bad ``order``, ``max_depth`` or ``min_depth``."""
    if not (isinstance(order, int) and order >= 1):
        raise ValueError(f"order must be a positive int (Gauss points per interval), got {order!r}")
    if not (isinstance(max_depth, int) and max_depth >= 0):
        raise ValueError(f"max_depth must be a non-negative int, got {max_depth!r}")
    if not (isinstance(min_depth, int) and 0 <= min_depth <= max_depth):
        raise ValueError(
            f"min_depth must be an int in 0 .. max_depth = {max_depth}, got {min_depth!r}"
        )


def _subdivide(cell, lo, hi):
    """The eight children of every box."""
    mid = 0.5 * (lo + hi)
    children = [
        (np.where(bits, mid, lo), np.where(bits, hi, mid))
        for bits in (np.array(b, dtype=bool) for b in itertools.product((0, 1), repeat=3))
    ]
    return (
        np.tile(cell, 8),
        np.concatenate([c[0] for c in children]),
        np.concatenate([c[1] for c in children]),
    )


def _tensor_rule(cell, lo, hi, gauss):
    """Tensor Gauss-Legendre rules of whole boxes: (rows, X, w)."""
    x, w = gauss
    grid = np.stack(np.meshgrid(x, x, x, indexing="ij"), axis=-1).reshape(-1, 3)
    wq = np.einsum("i,j,k->ijk", w, w, w).reshape(-1)
    X = lo[:, None] + (hi - lo)[:, None] * grid
    W = np.prod(hi - lo, axis=1)[:, None] * wq
    return np.repeat(cell, wq.size), X.reshape(-1, 3), W.reshape(-1)


def _pieces(roots: np.ndarray, lo: np.ndarray, hi: np.ndarray, gauss, merge: bool = False):
    """Gauss rules on the intervals of ``[lo, hi]`` between ``roots`` ``(m, r)`` (NaN: none).
    With ``merge``, breakpoints closer than :data:`BREAK_TOLERANCE` ``(hi - lo)`` to the
    previous one (or to ``hi``) are that one: roots equal but for round-off (the same
    crossing seen from two edges of a symmetric box) make no extra interval.

    Returns:
        ``(owner, x, w, piece, mid)``: per point its line, coordinate and weight, and per
        point the index of its interval among ``(m_owner_of_piece, mid)`` arrays.
    """
    x, w = gauss
    breaks = np.concatenate([lo[:, None], roots, hi[:, None]], axis=1)
    breaks = np.sort(np.where(np.isnan(breaks), hi[:, None], breaks), axis=1)
    if merge:
        close = BREAK_TOLERANCE * (hi - lo)
        for k in range(1, breaks.shape[1] - 1):
            near = breaks[:, k] - breaks[:, k - 1] <= close
            breaks[near, k] = breaks[near, k - 1]
        for k in range(breaks.shape[1] - 2, 0, -1):
            near = hi - breaks[:, k] <= close
            breaks[near, k] = hi[near]
    a, length = breaks[:, :-1], np.diff(breaks, axis=1)
    line, k = np.nonzero(length > 0)
    start, size = a[line, k], length[line, k]
    q = x.size
    return (
        np.repeat(line, q),
        (start[:, None] + size[:, None] * x).reshape(-1),
        (size[:, None] * w).reshape(-1),
        np.repeat(np.arange(line.size), q),
        (line, start + 0.5 * size),
    )


def _box_rules(C, cell, lo, hi, axes, gauss, parts, exact):
    """Nested Gauss rules of boxes sharing the axes ``(k3, k2)`` (height first); the roots
    on every line are ``exact``'s when given."""
    k3, k2 = axes
    k1 = 3 - k3 - k2
    m = cell.size

    def roots_of(C, axis, X, lo, hi, rows):
        """Roots of the lines ``X + t e_axis`` of polynomials ``C`` in cells ``rows``."""
        c = line_coefficients(C, axis, X)
        if exact is None:
            return line_roots(c, lo, hi)
        return exact_lines.line_roots(lambda i, Y: exact(rows[i], Y), X, axis, lo, hi, c)

    # level 1: along k1, breakpoints at the roots of psi on the four edges parallel to k1
    roots = []
    C1 = C[cell]
    for v, w in itertools.product((lo[:, k2], hi[:, k2]), (lo[:, k3], hi[:, k3])):
        X = np.zeros((m, 3))
        X[:, k2], X[:, k3] = v, w
        roots.append(roots_of(C1, k1, X, lo[:, k1], hi[:, k1], cell))
    roots = np.concatenate(roots, axis=1)
    box1, u, w1, _, _ = _pieces(roots, lo[:, k1], hi[:, k1], gauss, merge=True)
    # level 2: along k2 at each u, breakpoints at the roots of the two face functions
    roots = []
    C1 = C1[box1]
    for end in (lo, hi):
        X = np.zeros((u.size, 3))
        X[:, k1], X[:, k3] = u, end[box1, k3]
        roots.append(roots_of(C1, k2, X, lo[box1, k2], hi[box1, k2], cell[box1]))
    roots = np.concatenate(roots, axis=1)
    p1, v, w2, _, _ = _pieces(roots, lo[box1, k2], hi[box1, k2], gauss, merge=True)
    box2 = box1[p1]
    W = w1[p1] * w2
    X = np.zeros((v.size, 3))
    X[:, k1], X[:, k2] = u[p1], v
    C2 = C1[p1]
    lo3, hi3 = lo[box2, k3], hi[box2, k3]
    # level 3: along k3 at each (u, v), breakpoints at the roots of psi
    r = roots_of(C2, k3, X, lo3, hi3, cell[box2])
    p2, w, w3, piece, (pline, mid) = _pieces(r, lo3, hi3, gauss)
    Xmid = X[pline].copy()
    Xmid[:, k3] = mid
    if exact is None:
        negative = evaluate(C2[pline], Xmid) < 0
    else:
        negative = exact(cell[box2[pline]], Xmid) < 0
    Xq = X[p2].copy()
    Xq[:, k3] = w
    weights = W[p2] * w3
    rows = cell[box2[p2]]
    for side, keep in (("minus", negative[piece]), ("plus", ~negative[piece])):
        parts[side].append((rows[keep], Xq[keep], weights[keep]))
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
        at_lo, at_hi = r[line, j] == lo3[line], r[line, j] == hi3[line]
        bounding = ~(at_lo | at_hi) | (at_hi & (slope > 0)) | (at_lo & (slope < 0))
        bounding &= slope != 0
        if j == 1:  # a double root (both columns equal) is one point
            bounding &= ~(r[line, 1] == r[line, 0])
        line, Xs, grad, slope = line[bounding], Xs[bounding], grad[bounding], slope[bounding]
        area = grad / np.abs(slope)[:, None]
        parts["interface"].append((cell[box2[line]], Xs, W[line], area))


def _gather(parts, widths: tuple[int, ...]) -> list[np.ndarray]:
    """Concatenated columns of pieces ``(rows, X, w[, area])`` (``widths``: 1 for a
    scalar per point, 3 for a vector), sorted by row (stable)."""
    columns = []
    for c, width in enumerate(widths):
        col = np.concatenate([p[c] for p in parts]) if parts else np.zeros(0)
        columns.append(col.reshape(-1, 3) if width == 3 else col)
    order = np.argsort(columns[0], kind="stable")
    columns = [col[order] for col in columns]
    columns[0] = columns[0].astype(np.int64)
    return columns


def rules_from_points(rows: np.ndarray, X: np.ndarray, w: np.ndarray, ncells: int) -> RuleSet:
    """A :class:`~xfem_contact.quadrature.rules.RuleSet` of ``ncells`` rules from points
    ``X`` ``(N, 3)`` with weights ``w`` ``(N,)`` of cells ``rows`` ``(N,)`` (sorted)."""
    return RuleSet(X, w, np.searchsorted(rows, np.arange(ncells + 1)).astype(np.int64))
