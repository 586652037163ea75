"""Cut cells by the zero line of a level set: classification and curved
sub-triangulation in reference coordinates (pure numpy and Basix, no DOLFINx).

Each cell's level set is the Lagrange interpolant (degree 1 or 2, Basix
``gll_warped`` node order) of its nodal values ``phi``, shape ``(ncells, ndofs)``.
All coordinates are the parent cell's (dimensionless) reference coordinates.

Tolerance policy: ``phi < 0`` is side -1 and ``phi >= 0`` is side +1, by exact
floating-point comparison (an exact zero counts as +1); the interface normal
points from side -1 to side +1. Exact zeros at vertices and near-tangent edges
follow the rules of :mod:`xfem_contact.cut_topology` (a zero vertex is on side
-1 for its cell's topology when the interface leaves it along an edge; dips of
an edge polynomial within ``64 eps max|phi|`` of zero are tangency). Roots are
placed to ``xtol`` (reference coordinates); interface mid-nodes within 8 ulp
(relative to the chord) of the chord midpoint are snapped onto it.

All work is vectorised over cells; Python loops run over sign patterns, the
few candidate triangulations and solver iterations only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.cut_subcells import side_triangles
from xfem_contact.cut_topology import (
    CellData,
    cell_data,
    check_values,
    describe_cells,
    edge_coefficients,
    topology,
)

__all__ = ["CutGeometry", "ExactLevelSet", "classify", "subtriangulate"]

ExactLevelSet = Callable[[npt.NDArray[np.int64], npt.NDArray[np.float64]], npt.NDArray[np.float64]]
"""``exact(rows (m,), X (m, 2)) -> (m,)``: the exact level set at reference points
``X`` of the cut cells ``rows`` (row numbers of ``phi``)."""

_EPS = np.finfo(np.float64).eps
_WIDEN = (1e-12, 1e-9, 1e-6, 1e-3, 1e-1, np.inf)  # bracket search steps (parameter units)


@dataclass(frozen=True)
class CutGeometry:
    """Curved sub-triangulation of cut cells (reference coordinates of each parent).

    Attributes:
        tri_minus: P2 sub-triangles of side -1, shape ``(nt_m, 6, 2)``: vertices
            then mid-nodes of edges (1, 2), (0, 2), (0, 1) (Basix order),
            counter-clockwise. Only the interface edge is curved, except in the
            rare blended fallback for thin sides (:mod:`xfem_contact.cut_subcells`).
        tri_minus_cell: Row of ``phi`` (cut cell) of each, shape ``(nt_m,)``, sorted.
        tri_plus: P2 sub-triangles of side +1, shape ``(nt_p, 6, 2)``.
        tri_plus_cell: Their cut-cell rows, shape ``(nt_p,)``, sorted.
        seg: SEG3 interface piece per cut cell, shape ``(ncut, 3, 2)``: end ``a``,
            end ``b``, mid-node (Basix interval order). Side -1 lies on the left
            of ``a -> b``, so ``(t_y, -t_x)`` of the tangent points to side +1.
    """

    tri_minus: npt.NDArray[np.float64]
    tri_minus_cell: npt.NDArray[np.int64]
    tri_plus: npt.NDArray[np.float64]
    tri_plus_cell: npt.NDArray[np.int64]
    seg: npt.NDArray[np.float64]


def classify(cell_type: str, degree: int, phi: npt.ArrayLike) -> npt.NDArray[np.int8]:
    """Side of each cell: -1 (interpolant < 0), +1 (>= 0) or 0 (cut).

    Args:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Level-set degree, 1 or 2.
        phi: Nodal values, shape ``(ncells, ndofs)``.

    Returns:
        ``int8`` array of shape ``(ncells,)``.

    Raises:
        ValueError: Non-finite values, or unsupported cuts (an edge crossed
            twice, more than two boundary crossings, a closed interface piece
            inside a cell); the message names the cells.
    """
    data = cell_data(cell_type, degree)
    neg = topology(data, check_values(data, phi))
    return np.where(neg.all(axis=1), -1, np.where(neg.any(axis=1), 0, 1)).astype(np.int8)


def subtriangulate(
    cell_type: str,
    degree: int,
    phi: npt.ArrayLike,
    exact: ExactLevelSet | None = None,
    xtol: float = 1e-14,
) -> CutGeometry:
    """Split cut cells into curved P2 sub-triangles on each side and a SEG3 interface.

    Edge crossings are closed-form roots of the edge polynomials. The SEG3
    mid-node is the zero of the interpolant on the perpendicular bisector of
    the chord (bracketed Newton); for degree 1 it is the chord midpoint. With
    ``exact``, crossings and mid-node are moved onto the zero set of ``exact``
    (bracketed Illinois iteration started from the interpolant's points; where
    ``exact`` shows no sign change along the search line the interpolant's
    point is kept). Each side polygon is fan-triangulated so that the interface
    is an edge of exactly one sub-triangle (the apex chosen for the best
    minimum angle and Jacobian); zero-area sub-triangles (a repeated vertex and
    no curved edge) are dropped, tiny ones are kept. Where every such fan
    folds (a side thinner than the interface's bulge), a blended, refined fan
    is used instead, see :mod:`xfem_contact.cut_subcells`.

    Args:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Level-set degree, 1 or 2.
        phi: Nodal values of cut cells only, shape ``(ncut, ndofs)``.
        exact: Optional exact level set, see :data:`ExactLevelSet`.
        xtol: Root tolerance in reference coordinates.

    Returns:
        The :class:`CutGeometry`.

    Raises:
        ValueError: As :func:`classify`, and for cells that are not cut.
    """
    data = cell_data(cell_type, degree)
    phi = check_values(data, phi)
    if not xtol > 0:
        raise ValueError(f"xtol must be positive, got {xtol!r}")
    n, nv = phi.shape[0], data.nv
    neg = topology(data, phi)
    uncut = np.flatnonzero(neg.all(axis=1) | ~neg.any(axis=1))
    if uncut.size:
        raise ValueError(
            f"subtriangulate takes cut cells only, but {describe_cells(uncut)} are not cut; "
            "select the cells that classify() marks 0"
        )
    neg_end = np.roll(neg, -1, axis=1)
    c_pm = _edge_crossings(data, phi, neg, np.argmax(~neg & neg_end, axis=1), exact, xtol)
    c_mp = _edge_crossings(data, phi, neg, np.argmax(neg & ~neg_end, axis=1), exact, xtol)
    mid = _midnodes(data, phi, c_mp, c_pm, exact, xtol)
    table = np.concatenate(
        [np.broadcast_to(data.loop_coords, (n, nv, 2)), c_pm[:, None], c_mp[:, None]], axis=1
    )
    codes = (neg * (1 << np.arange(nv))).sum(axis=1)
    seg = np.stack([c_mp, c_pm, mid], axis=1)
    faces = (data.face_normals, data.face_offsets)
    tri_m, cell_m = side_triangles(table, seg, codes, -1, faces)
    tri_p, cell_p = side_triangles(table, seg, codes, +1, faces)
    return CutGeometry(tri_m, cell_m, tri_p, cell_p, seg)


# -- crossings -------------------------------------------------------------------------


def _crossing_parameter(a: np.ndarray, b: np.ndarray, m: np.ndarray | None) -> np.ndarray:
    """Sign change in ``[0, 1]`` of ``g`` with ``g(0) = a < 0 <= g(1) = b`` (``a`` may be
    an exact zero on side -1), ``g(1/2) = m``: the root where ``g' >= 0``,
    ``(-B + sqrt(D)) / (2A)``, evaluated without cancellation."""
    A, B = edge_coefficients(a, b, m)
    r = np.sqrt(np.maximum(B * B - 4.0 * A * a, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(B >= 0, -2.0 * a / (B + r), (r - B) / (2.0 * A))
    return np.clip(np.where(np.isfinite(s), s, 0.0), 0.0, 1.0)


def _edge_crossings(
    data: CellData,
    phi: np.ndarray,
    neg: np.ndarray,
    edge: np.ndarray,
    exact: ExactLevelSet | None,
    xtol: float,
) -> np.ndarray:
    """Crossing point on loop edge ``edge[c]`` of each cell, shape ``(n, 2)``."""
    rows = np.arange(phi.shape[0])
    nxt = (edge + 1) % data.nv
    first_neg = neg[rows, edge]
    jn, jp = np.where(first_neg, edge, nxt), np.where(first_neg, nxt, edge)
    a, b = phi[rows, data.loop[jn]], phi[rows, data.loop[jp]]
    m = phi[rows, data.loop_mid[edge]] if data.degree == 2 else None
    s = _crossing_parameter(a, b, m)
    P = data.loop_coords[jn]
    d = data.loop_coords[jp] - P
    if exact is not None:
        tol = xtol / np.hypot(d[:, 0], d[:, 1])

        def f(idx: np.ndarray, t: np.ndarray) -> np.ndarray:
            return _call_exact(exact, idx, P[idx] + t[:, None] * d[idx])

        s = _exact_root(f, s, np.zeros_like(s), np.ones_like(s), tol)
    return P + s[:, None] * d


def _call_exact(exact: ExactLevelSet, rows: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``exact(rows, X)`` checked for shape ``(m,)`` and finite values."""
    values = np.asarray(exact(rows, X), dtype=np.float64)
    if values.shape != (rows.size,):
        raise ValueError(f"exact(rows, X) must return shape ({rows.size},), got {values.shape}")
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise ValueError(
            f"exact level set is not finite ({values[bad[0]]}) at X = {X[bad[0]].tolist()} "
            f"in cut cell {rows[bad[0]]}; check the level-set function"
        )
    return values


def _interpolant(
    data: CellData, phi_rows: np.ndarray, X: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Value ``(m,)`` and reference gradient ``(m, 2)`` of the interpolant of
    ``phi_rows`` ``(m, ndofs)`` at one point ``X`` ``(m, 2)`` per row."""
    tab = data.element.tabulate(1, X)[:, :, :, 0]
    return np.einsum("pi,pi->p", tab[0], phi_rows), np.einsum("kpi,pi->pk", tab[1:], phi_rows)


def _line_limits(data: CellData, M: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Range ``[lo, hi]`` (``lo <= 0 <= hi``) of ``u`` with ``M + u nu`` in the cell."""
    lo = np.full(M.shape[0], -np.inf)
    hi = np.full(M.shape[0], np.inf)
    for normal, offset in zip(data.face_normals, data.face_offsets, strict=True):
        num, den = offset - M @ normal, nu @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            t = num / den
        hi = np.where(den > 0, np.minimum(hi, t), hi)
        lo = np.where(den < 0, np.maximum(lo, t), lo)
    return np.minimum(lo, 0.0), np.maximum(hi, 0.0)


def _midnodes(
    data: CellData,
    phi: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    exact: ExactLevelSet | None,
    xtol: float,
) -> np.ndarray:
    """SEG3 mid-nodes ``(n, 2)`` on the perpendicular bisector of the chords ``a -> b``."""
    M = 0.5 * (a + b)
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    act = np.flatnonzero(length > 0)  # zero chords keep the midpoint
    if act.size == 0 or (data.degree == 1 and exact is None):
        return M
    Ma = M[act]
    nu = np.stack([d[act, 1], -d[act, 0]], axis=1)  # towards side +1
    tol = xtol / length[act]
    lo, hi = _line_limits(data, Ma, nu)
    u = np.zeros(act.size)
    if data.degree == 2:
        pa = phi[act]

        def g(idx: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            value, grad = _interpolant(data, pa[idx], Ma[idx] + t[:, None] * nu[idx])
            return value, np.einsum("pk,pk->p", grad, nu[idx])

        everything = np.arange(act.size)
        ok = np.flatnonzero((g(everything, lo)[0] < 0) & (g(everything, hi)[0] >= 0))
        u[ok] = _newton_bracketed(
            lambda idx, t: g(ok[idx], t), np.zeros(ok.size), lo[ok], hi[ok], tol[ok]
        )
    if exact is not None:

        def f(idx: np.ndarray, t: np.ndarray) -> np.ndarray:
            return _call_exact(exact, act[idx], Ma[idx] + t[:, None] * nu[idx])

        u = _exact_root(f, u, lo, hi, tol)
    u = np.where(np.abs(u) <= 8.0 * _EPS, 0.0, u)
    mid = M.copy()
    mid[act] = Ma + u[:, None] * nu
    return mid


# -- vectorised bracketed root finders ---------------------------------------------------
# Each solves one scalar equation per entry; ``func(idx, x)`` evaluates the entries
# ``idx`` at ``x``. Brackets satisfy f(lo) < 0 <= f(hi).


def _newton_bracketed(
    func: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
    x: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    tol: np.ndarray,
    maxiter: int = 100,
) -> np.ndarray:
    """Newton from ``x``, falling back to bisection when a step leaves the bracket."""
    x, lo, hi = x.copy(), lo.copy(), hi.copy()
    idx = np.arange(x.size)
    for _ in range(maxiter):
        if idx.size == 0:
            break
        xi = x[idx]
        f, df = func(idx, xi)
        below = f < 0
        lo[idx] = np.where(below, xi, lo[idx])
        hi[idx] = np.where(below, hi[idx], xi)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = f / df
        xn = xi - step
        done = (f == 0) | (np.abs(step) <= tol[idx]) | (hi[idx] - lo[idx] <= tol[idx])
        inside = np.isfinite(xn) & (xn > lo[idx]) & (xn < hi[idx])
        xn = np.where(inside, xn, 0.5 * (lo[idx] + hi[idx]))
        final = np.clip(xi - np.where(np.isfinite(step), step, 0.0), lo[idx], hi[idx])
        x[idx] = np.where(done, final, xn)
        idx = idx[~done]
    return x


def _illinois(
    func: Callable[[np.ndarray, np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    flo: np.ndarray,
    fhi: np.ndarray,
    tol: np.ndarray,
    maxiter: int = 120,
) -> np.ndarray:
    """Illinois (modified regula falsi) until the bracket is narrower than ``tol``;
    plain bisection after 40 iterations guarantees termination."""
    lo, hi, flo, fhi = lo.copy(), hi.copy(), flo.copy(), fhi.copy()
    x = 0.5 * (lo + hi)
    last = np.zeros(x.size, dtype=np.int8)
    idx = np.arange(x.size)
    for it in range(maxiter):
        if idx.size == 0:
            break
        lo_i, hi_i, flo_i, fhi_i = lo[idx], hi[idx], flo[idx], fhi[idx]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (lo_i * fhi_i - hi_i * flo_i) / (fhi_i - flo_i)
        good = np.isfinite(t) & (t > lo_i) & (t < hi_i) & (it < 40)
        t = np.where(good, t, 0.5 * (lo_i + hi_i))
        ft = func(idx, t)
        below = ft < 0
        same = np.where(below, -1, 1) == last[idx]
        lo[idx], hi[idx] = np.where(below, t, lo_i), np.where(below, hi_i, t)
        flo[idx] = np.where(below, ft, np.where(same, 0.5 * flo_i, flo_i))
        fhi[idx] = np.where(below, np.where(same, 0.5 * fhi_i, fhi_i), ft)
        last[idx] = np.where(below, -1, 1)
        x[idx] = t
        idx = idx[~((ft == 0) | (hi[idx] - lo[idx] <= tol[idx]))]
    return x


def _exact_root(
    func: Callable[[np.ndarray, np.ndarray], np.ndarray],
    x0: np.ndarray,
    lo_lim: np.ndarray,
    hi_lim: np.ndarray,
    tol: np.ndarray,
) -> np.ndarray:
    """Root of ``func`` near ``x0`` within ``[lo_lim, hi_lim]``: bracket by steps of
    growing size away from ``x0`` (up to the limits), then Illinois. Entries with
    no sign change keep ``x0``."""
    everything = np.arange(x0.size)
    f0 = func(everything, x0)
    lo, hi, flo, fhi = x0.copy(), x0.copy(), f0.copy(), f0.copy()
    up = f0 < 0  # x0 is the lower end: search upwards
    pending = f0 != 0
    for delta in _WIDEN:
        idx = np.flatnonzero(pending)
        if idx.size == 0:
            break
        x, u = x0[idx], up[idx]
        t = np.where(u, np.minimum(x + delta, hi_lim[idx]), np.maximum(x - delta, lo_lim[idx]))
        ft = func(idx, t)
        below = ft < 0
        lo[idx], flo[idx] = np.where(below, t, lo[idx]), np.where(below, ft, flo[idx])
        hi[idx], fhi[idx] = np.where(below, hi[idx], t), np.where(below, fhi[idx], ft)
        pending[idx[below != u]] = False
    x = x0.copy()
    br = np.flatnonzero((f0 != 0) & ~pending)
    if br.size:
        x[br] = _illinois(lambda i, t: func(br[i], t), lo[br], hi[br], flo[br], fhi[br], tol[br])
    return x
