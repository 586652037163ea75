"""Curved P2 sub-triangles of the two sides of cut cells (helper of
:mod:`xfem_contact.geometry.cut`).

Each side of a cut cell is a convex polygon ``q_0 .. q_{n-1}`` (``n`` = 3, 4 or
5) of cell-boundary points, closed by the interface chord ``q_{n-1} -> q_0``;
the interface itself is the SEG3 ``(a, b, m)`` whose mid-node ``m`` sits on the
chord's perpendicular bisector. Per cell the first valid construction wins:

1. *Apex fans* with straight interior edges: the interface triangle
   ``(q_0, apex, q_{n-1})`` holds the whole interface as its edge (0, 2) with
   mid-node ``m``; triangles and pentagons have one fan (apex opposite the
   interface), quadrilaterals two diagonals, ranked by ``min angle *
   min/max`` of the Bernstein coefficients of ``det J``.
2. For interfaces curved strongly relative to the side's thickness (where
   every straight fan folds): the same fans, uniformly refined 0, 1 or 2
   times, with every P2 node placed by the blend map
   ``B(X) = X + 4 tau (1 - tau) (1 - eta / eta_max(tau)) (m - M)``, where ``tau``
   is the chord coordinate of ``X``, ``eta`` its distance from the chord into
   the polygon and ``eta_max(tau)`` the polygon's extent along that normal.
   ``B`` maps the chord onto the SEG3 and fixes the cell boundary, so the
   sub-triangles still tile the curved side exactly.

A sub-triangle is valid when ``det J > 0`` on it (all Bernstein coefficients
positive; ``>= 0`` for a *collapsed* triangle, a lens between a straight edge
and the interface when the interface runs through two vertices of one edge).
Triangles with a repeated vertex and no curved edge have zero area and are
dropped.

If no construction is valid (a side thinner than the interface's bulge
resolves at level 2, e.g. an interface nearly touching a cell edge, or a SEG3
through exact points that leaves the cell), the least folded level-2
construction is used. Its triangles still tile the side with the exact
boundary, so integrating with the *signed* ``det J`` (as
:func:`xfem_contact.quadrature.rules.side_rules` does) remains exact: by the degree
formula the folds cancel. Only there can weights be negative, in the fold.
"""

from __future__ import annotations

import functools

import basix
import numpy as np

from xfem_contact.geometry.cut_topology import side_polygon

_APEX = {
    3: [[(0, 1, 2)]],
    4: [[(0, 2, 3), (0, 1, 2)], [(0, 1, 3), (1, 2, 3)]],
    5: [[(0, 2, 4), (0, 1, 2), (2, 3, 4)]],
}  # the first triangle of each fan is the interface triangle (q_0, apex, q_{n-1})
_LEVELS = (0, 1, 2)  # refinement levels of the blended fallback
_EPS = np.finfo(np.float64).eps


@functools.cache
def _children(level: int) -> np.ndarray:
    """Barycentric coordinates of the P2 nodes of the ``4**level`` children of a
    uniformly refined triangle, shape ``(nchild, 6, 3)`` (Basix node order)."""
    tris = [np.eye(3)]
    for _ in range(level):
        new = []
        for A, B, C in tris:
            ab, bc, ac = (A + B) / 2, (B + C) / 2, (A + C) / 2
            new += [np.array(t) for t in ((A, ab, ac), (ab, B, bc), (ac, bc, C), (ab, bc, ac))]
        tris = new
    v = np.array(tris)
    return np.concatenate([v, 0.5 * (v[:, [1, 0, 0]] + v[:, [2, 2, 1]])], axis=1)


@functools.cache
def _p2_node_derivatives() -> np.ndarray:
    """Derivatives of the P2 triangle basis at its own nodes, shape ``(2, 6, 6)``."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.triangle, 2, basix.LagrangeVariant.gll_warped
    )
    return element.tabulate(1, element.points)[1:, :, :, 0]


def _jacobian_bernstein(nodes: np.ndarray) -> np.ndarray:
    """Bernstein coefficients ``(..., 6)`` of ``det dX/dxi`` (degree 2) of P2
    triangles ``(..., 6, 2)``; all positive implies an injective map."""
    J = np.einsum("kpi,...id->...pdk", _p2_node_derivatives(), nodes)
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    ends = det[..., [1, 0, 0]] + det[..., [2, 2, 1]]  # edges (1, 2), (0, 2), (0, 1)
    return np.concatenate([det[..., :3], 2.0 * det[..., 3:] - 0.5 * ends], axis=-1)


def _repeated(v: np.ndarray) -> np.ndarray:
    """Triangles ``(..., 3, 2)`` with two bitwise-equal vertices."""
    same = [(v[..., i, :] == v[..., j, :]).all(axis=-1) for i, j in ((0, 1), (1, 2), (0, 2))]
    return same[0] | same[1] | same[2]


def _min_angle(v: np.ndarray) -> np.ndarray:
    """Smallest interior angle of straight triangles ``(..., 3, 2)``."""
    angles = []
    for i in range(3):
        e1 = v[..., (i + 1) % 3, :] - v[..., i, :]
        e2 = v[..., (i + 2) % 3, :] - v[..., i, :]
        cross = e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0]
        angles.append(np.arctan2(np.abs(cross), (e1 * e2).sum(axis=-1)))
    return np.minimum(np.minimum(angles[0], angles[1]), angles[2])


def _blend(
    X: np.ndarray, seg: np.ndarray, side: int, faces: tuple[np.ndarray, np.ndarray]
) -> np.ndarray:
    """The blend map ``B`` at points ``X`` ``(r, k, 2)`` of the side polygons of the
    cells with SEG3s ``seg`` ``(r, 3, 2)``."""
    a, b, m = seg[:, None, 0], seg[:, None, 1], seg[:, None, 2]
    d = b - a
    length = np.linalg.norm(d, axis=-1)
    nhat = side * np.stack([d[..., 1], -d[..., 0]], axis=-1) / length[..., None]  # inwards
    tau = ((X - a) * d).sum(axis=-1) / length**2
    eta = ((X - a) * nhat).sum(axis=-1)
    foot = a + tau[..., None] * d
    eta_max = np.full(tau.shape, np.inf)
    for normal, offset in zip(*faces, strict=True):
        den = nhat @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            reach = (offset - foot @ normal) / den
        eta_max = np.where(den > 0, np.minimum(eta_max, reach), eta_max)
    with np.errstate(divide="ignore", invalid="ignore"):
        fade = np.clip(1.0 - eta / eta_max, 0.0, 1.0)
    weight = np.where((tau > 0) & (tau < 1) & (eta_max > 0), 4 * tau * (1 - tau) * fade, 0.0)
    return X + weight[..., None] * (m - 0.5 * (a + b))


#: Fans whose scores differ by less than this fraction are equally good
_TIE = 1e-9


def _best_fan(
    pts: np.ndarray,
    seg: np.ndarray,
    straight: np.ndarray,
    side: int,
    faces: tuple[np.ndarray, np.ndarray],
    level: int | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Best valid apex fan of polygons ``pts`` ``(r, n, 2)``: straight interior edges
    (``level is None``) or blended and refined ``level`` times.

    Returns:
        P2 nodes ``(r, ntri, 6, 2)``, drop mask ``(r, ntri)`` and validity ``(r,)``
        of the best valid fan, else of the least folded one.
    """
    children = _children(0 if level is None else level)
    options = []
    for fan in _APEX[pts.shape[1]]:
        v = np.stack([pts[:, list(t)] for t in fan], axis=1)  # (r, nfan, 3, 2)
        repeated = _repeated(v)
        drop = repeated & ((np.arange(len(fan)) > 0) | straight[:, None])  # [0]: interface
        nodes = np.einsum("cjl,rtld->rtcjd", children, v)  # (r, nfan, nchild, 6, 2)
        if level is None:
            nodes[:, 0, 0, 4] = seg[:, 2]
        else:
            nodes = _blend(nodes.reshape(len(v), -1, 2), seg, side, faces).reshape(nodes.shape)
        b = _jacobian_bernstein(nodes)
        bmin, babs = b.min(axis=-1), np.abs(b).max(axis=-1)
        ratio = np.divide(bmin, babs, out=np.zeros_like(bmin), where=babs > 0)
        collapsed = (repeated & ~drop)[..., None]  # a lens: det J may vanish on an edge
        ok = drop[..., None] | np.where(collapsed, bmin >= -64 * _EPS * babs, bmin > 0)
        q = np.where(collapsed, 0.0, _min_angle(nodes[..., :3, :]) * ratio)
        q = np.where(drop[..., None], np.inf, q).min(axis=(1, 2))
        fold = np.where(drop[..., None], np.inf, ratio).min(axis=(1, 2))
        score = np.where(ok.all(axis=(1, 2)), q, np.minimum(fold, 0.0) - 1.0)
        drop = np.repeat(drop, len(children), axis=1)
        options.append((nodes.reshape(len(v), -1, 6, 2), drop, score))
    scores = np.stack([o[2] for o in options], axis=1)
    # Near ties (the two diagonals of a symmetric side) go to the first fan: a bare
    # argmax followed 1-ulp noise in the nodal level set, which depends on the cell
    # numbering, so 1 and 2 processes subdivide some annulus cells differently.
    top = scores.max(axis=1, keepdims=True)
    margin = np.where(np.isfinite(top), _TIE * np.abs(top), 0.0)  # inf: every child dropped
    best = np.argmax(scores >= top - margin, axis=1)
    pick = np.arange(len(pts))
    nodes = np.stack([o[0] for o in options], axis=1)[pick, best]
    drop = np.stack([o[1] for o in options], axis=1)[pick, best]
    return nodes, drop, scores[pick, best] >= 0


def side_triangles(
    table: np.ndarray,
    seg: np.ndarray,
    codes: np.ndarray,
    side: int,
    faces: tuple[np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """Curved P2 sub-triangles of one side of cut cells.

    Args:
        table: Points ``[loop vertices, c_pm, c_mp]`` per cell, ``(n, nv + 2, 2)``.
        seg: SEG3 ``(a, b, m)`` per cell, ``(n, 3, 2)``, with ``a = c_mp``, ``b = c_pm``.
        codes: Sign patterns (bit ``j``: loop vertex ``j`` on side -1), ``(n,)``.
        side: -1 or +1.
        faces: The cell's half-planes ``n . X <= c`` as (normals ``(nf, 2)``,
            offsets ``(nf,)``).

    Returns:
        Sub-triangles ``(m, 6, 2)`` and their cells ``(m,)``, sorted by cell.
    """
    nv = table.shape[1] - 2
    straight = (seg[:, 2] == 0.5 * (seg[:, 0] + seg[:, 1])).all(axis=1)
    tris, cells = [np.zeros((0, 6, 2))], [np.zeros(0, dtype=np.int64)]
    for code in np.unique(codes):
        rows = np.flatnonzero(codes == code)
        pts = table[:, side_polygon(int(code), nv, side)]
        for level in (None, *_LEVELS):
            nodes, drop, ok = _best_fan(pts[rows], seg[rows], straight[rows], side, faces, level)
            if level == _LEVELS[-1]:
                ok[:] = True  # least folded: exact with signed det J, see module docstring
            keep = ~drop & ok[:, None]
            tris.append(nodes[keep])
            cells.append(np.broadcast_to(rows[:, None], keep.shape)[keep])
            rows = rows[~ok]
            if rows.size == 0:
                break
    tri, cell = np.concatenate(tris), np.concatenate(cells)
    order = np.argsort(cell, kind="stable")
    return tri[order], cell[order]
