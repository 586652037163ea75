"""Simply cut cells: edge crossings, SEG3 mid-nodes and the sub-triangles of both sides.

Helper of :mod:`xfem_contact.geometry.cut` (pure numpy and Basix, no DOLFINx). A
*simple* cut crosses the cell boundary exactly twice (``kind == 0`` and mixed
vertex sides in :func:`xfem_contact.geometry.cut_topology.topology`) and is represented
by one SEG3 ``(a, b, mid)``. Its ends are closed-form roots of the edge
polynomials of the two crossed loop edges; an end within ``xtol`` of a vertex is
that vertex, bitwise (a node on the zero line leaves no sliver beside it, whatever
rounding its nodal value carries). The mid-node is the zero of the
interpolant on the perpendicular bisector of the chord (bracketed Newton of
:mod:`xfem_contact.geometry.roots`); for degree 1 it is the chord midpoint. Mid-nodes
within 8 ulp (relative to the chord) of the chord midpoint are snapped onto it. With
an exact level set (:data:`ExactLevelSet`), crossings and mid-node are moved
onto its zero set (bracketed Illinois iteration started from the interpolant's
points); where ``exact`` shows no sign change along the search line the
interpolant's point is kept. Roots are placed to ``xtol`` in the reference
coordinates of the cell handed in. The side polygons are then triangulated by
:mod:`xfem_contact.geometry.cut_subcells`.

:func:`cut_simple` treats its cells as reference cells;
:mod:`xfem_contact.geometry.cut_subdivision` applies it to sub-cells as well (with
``exact`` composed with the sub-cell maps).
"""

from __future__ import annotations

import numpy as np

from xfem_contact.geometry.cut_subcells import side_triangles
from xfem_contact.geometry.cut_topology import CellData, edge_coefficients
from xfem_contact.geometry.exact_lines import ExactLevelSet
from xfem_contact.geometry.roots import bracketed_root, newton_bracketed

_EPS = np.finfo(np.float64).eps


def cut_simple(
    data: CellData,
    phi: np.ndarray,
    neg: np.ndarray,
    exact: ExactLevelSet | None,
    xtol: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sub-triangles ``(tri_minus, cell, tri_plus, cell)`` and the SEG3 ``(n, 3, 2)``
    of simply cut cells with topological vertex sides ``neg``.

    Args:
        data: Reference-cell data.
        phi: Nodal values, shape ``(n, ndofs)``.
        neg: Vertex sides from :func:`xfem_contact.geometry.cut_topology.topology`, ``(n, nv)``.
        exact: Optional exact level set on these cells (rows ``0 .. n-1``).
        xtol: Root tolerance in the reference coordinates of these cells.

    Returns:
        ``tri_minus`` ``(nt_m, 6, 2)``, its cell rows ``(nt_m,)``, ``tri_plus``
        ``(nt_p, 6, 2)``, its cell rows ``(nt_p,)`` (sorted, as
        :func:`xfem_contact.geometry.cut_subcells.side_triangles` gives them) and the SEG3
        ``(n, 3, 2)`` (``c_mp``, ``c_pm``, mid-node) of each cell.
    """
    n, nv = phi.shape[0], data.nv
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
    return tri_m, cell_m, tri_p, cell_p, seg


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
    tol = xtol / np.hypot(d[:, 0], d[:, 1])
    # A crossing within xtol of a vertex is the vertex, bitwise: no sliver beside it
    at_start, at_end = s <= tol, s >= 1.0 - tol
    free = np.flatnonzero(~(at_start | at_end))
    if exact is not None and free.size:

        def f(idx: np.ndarray, t: np.ndarray) -> np.ndarray:
            return call_exact(exact, free[idx], P[free[idx]] + t[:, None] * d[free[idx]])

        s[free] = bracketed_root(f, s[free], np.zeros(free.size), np.ones(free.size), tol[free])
    X = P + s[:, None] * d
    X[at_start] = P[at_start]
    X[at_end] = data.loop_coords[jp][at_end]
    return X


def call_exact(exact: ExactLevelSet, rows: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``exact(rows, X)`` at ``rows`` ``(m,)`` and points ``X`` ``(m, 2)``, checked for
    shape ``(m,)`` and finite values."""
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


def interpolant(
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
            value, grad = interpolant(data, pa[idx], Ma[idx] + t[:, None] * nu[idx])
            return value, np.einsum("pk,pk->p", grad, nu[idx])

        everything = np.arange(act.size)
        ok = np.flatnonzero((g(everything, lo)[0] < 0) & (g(everything, hi)[0] >= 0))
        u[ok] = newton_bracketed(
            lambda idx, t: g(ok[idx], t), np.zeros(ok.size), lo[ok], hi[ok], tol[ok]
        )
    if exact is not None:

        def f(idx: np.ndarray, t: np.ndarray) -> np.ndarray:
            return call_exact(exact, act[idx], Ma[idx] + t[:, None] * nu[idx])

        u = bracketed_root(f, u, lo, hi, tol)
    u = np.where(np.abs(u) <= 8.0 * _EPS, 0.0, u)
    mid = M.copy()
    mid[act] = Ma + u[:, None] * nu
    return mid
