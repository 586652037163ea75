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

Degeneracy policy: a *simple* cut crosses the cell boundary exactly twice and
is represented by one SEG3. A cell whose interpolant

* crosses an edge twice (a cap; dips within the tangency bound above do not count),
* crosses the boundary more than twice (several pieces, e.g. near a saddle), or
* changes sign inside but not on the boundary (a closed piece; degree 2 only,
  seen on a 9 x 9 sample lattice, so smaller pieces between its points are missed)

is *subdivided*: split in reference coordinates into 4 sub-cells (quadrilateral:
4 rectangles; triangle: 3 corner triangles and a middle one), at the edge
mid-points except that an edge crossed twice is split between its crossings
(at the extremum of its polynomial) and a closed piece through its inside
(:func:`xfem_contact.cut_topology.split_parameters`). On an affine sub-cell
the interpolant is again a Lagrange interpolant of the same degree, with the
parent's values at the sub-cell's nodes; ``exact`` is composed with the
sub-cell map. Sub-cells are cut as reference cells (the same rules, ``xtol``
in sub-cell units), uncut ones become straight sub-triangles of their side,
and everything is mapped back affinely (P2 nodes map exactly). Sub-cells that
still need it are split again, up to ``max_depth`` levels (default
:data:`MAX_DEPTH` = 5). Inside subdivided cells only, a simply cut sub-cell
whose SEG3 strays from the zero set by more than ``2e-4`` times its chord at
its quarter points (as a circular arc of about 29 degrees would) is split
once more through the farthest point while depth allows, unless one of its
children would then need splitting (accuracy refinement never fails). A
subdivided cell has one SEG3 per cut sub-cell (those shorter than ``64 eps``
dropped), possibly none.

A (sub-)cell whose interpolant vanishes identically on two or more of its
edges and is negative at its other vertices (a corner of a mesh-aligned
interface, or crossing branches meeting at a split point) lies wholly on side
-1 and carries those edges as straight interface pieces: the convention of an
interface along one edge, where the cell on side -1 carries it. If such a
degree-2 interpolant turns positive inside, the cell is subdivided instead.

After ``max_depth`` levels :func:`subtriangulate` raises ``ValueError`` naming
the cells and the reason. This happens for interface branches that cross
(an exact saddle with zero value) away from split points, and for details
finer than the last level. Cells that are not subdivided are never refined for
accuracy, however strongly their SEG3 bends.

All work is vectorised over cells; Python loops run over subdivision levels,
sign patterns, the few candidate triangulations and solver iterations only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.cut_subcells import side_triangles
from xfem_contact.cut_topology import (
    CORNER,
    CellData,
    cell_data,
    check_values,
    describe_cells,
    describe_kinds,
    edge_coefficients,
    lagrange_basis,
    seg3_basis,
    split_cells,
    split_parameters,
    straight_triangles,
    topology,
    zero_edges,
)
from xfem_contact.roots import bracketed_root, newton_bracketed

__all__ = ["CutGeometry", "ExactLevelSet", "classify", "subtriangulate"]

ExactLevelSet = Callable[[npt.NDArray[np.int64], npt.NDArray[np.float64]], npt.NDArray[np.float64]]
"""``exact(rows (m,), X (m, 2)) -> (m,)``: the exact level set at reference points
``X`` of the cut cells ``rows`` (row numbers of ``phi``)."""

_EPS = np.finfo(np.float64).eps
MAX_DEPTH = 5
"""Default number of subdivision levels of :func:`subtriangulate`."""
_TINY = 64.0 * _EPS  # pieces of subdivided cells shorter than this (reference units) are dropped
_GAP = 2e-4  # SEG3 distance to the zero set / chord refined in subdivided cells (~29 deg arcs)


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
        seg: SEG3 interface pieces, shape ``(nseg, 3, 2)``: end ``a``, end ``b``,
            mid-node (Basix interval order). Side -1 lies on the left of
            ``a -> b``, so ``(t_y, -t_x)`` of the tangent points to side +1. A
            simply cut cell has exactly one piece (of zero length when the
            interface only touches the cell); a subdivided cell has one per cut
            sub-cell, those shorter than ``64 eps`` omitted.
        seg_cell: Cut-cell row of each piece, shape ``(nseg,)``, sorted.
        num_cells: Number of cut cells (rows of ``phi``).
        subdivided: Rows of the cells that are not simply cut (subdivided, or
            cut along two of their edges), shape ``(nsub,)``, sorted.
    """

    tri_minus: npt.NDArray[np.float64]
    tri_minus_cell: npt.NDArray[np.int64]
    tri_plus: npt.NDArray[np.float64]
    tri_plus_cell: npt.NDArray[np.int64]
    seg: npt.NDArray[np.float64]
    seg_cell: npt.NDArray[np.int64]
    num_cells: int
    subdivided: npt.NDArray[np.int64]


def classify(cell_type: str, degree: int, phi: npt.ArrayLike) -> npt.NDArray[np.int8]:
    """Side of each cell: -1 (interpolant < 0), +1 (>= 0) or 0 (cut).

    Cells that :func:`subtriangulate` subdivides (see the module docstring)
    count as cut, including a closed interface piece inside an otherwise uncut
    cell.

    Args:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Level-set degree, 1 or 2.
        phi: Nodal values, shape ``(ncells, ndofs)``.

    Returns:
        ``int8`` array of shape ``(ncells,)``.

    Raises:
        ValueError: Non-finite values or bad shapes; the message names the cells.
    """
    data = cell_data(cell_type, degree)
    neg, kind = topology(data, check_values(data, phi))
    side = np.where(neg.all(axis=1), -1, np.where(neg.any(axis=1), 0, 1))
    return np.where(kind != 0, 0, side).astype(np.int8)


def subtriangulate(
    cell_type: str,
    degree: int,
    phi: npt.ArrayLike,
    exact: ExactLevelSet | None = None,
    xtol: float = 1e-14,
    max_depth: int = MAX_DEPTH,
) -> CutGeometry:
    """Split cut cells into curved P2 sub-triangles on each side and SEG3 interface pieces.

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
    is used instead, see :mod:`xfem_contact.cut_subcells`. Cells that are not
    simply cut are subdivided first (module docstring).

    Args:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Level-set degree, 1 or 2.
        phi: Nodal values of cut cells only, shape ``(ncut, ndofs)``.
        exact: Optional exact level set, see :data:`ExactLevelSet`.
        xtol: Root tolerance in reference coordinates (of the sub-cell, if any).
        max_depth: Maximum number of subdivision levels (0: none).

    Returns:
        The :class:`CutGeometry`.

    Raises:
        ValueError: As :func:`classify`, for cells that are not cut, and for
            cells that still need subdividing after ``max_depth`` levels.
    """
    data = cell_data(cell_type, degree)
    phi = check_values(data, phi)
    if not xtol > 0:
        raise ValueError(f"xtol must be positive, got {xtol!r}")
    if max_depth < 0:
        raise ValueError(f"max_depth must be >= 0, got {max_depth!r}")
    n = phi.shape[0]
    neg, kind = topology(data, phi)
    uncut = np.flatnonzero((kind == 0) & (neg.all(axis=1) | ~neg.any(axis=1)))
    if uncut.size:
        raise ValueError(
            f"subtriangulate takes cut cells only, but {describe_cells(uncut)} are not cut; "
            "select the cells that classify() marks 0"
        )
    subdivided = np.flatnonzero(kind != 0)
    if subdivided.size == 0:  # the common case: one SEG3 per cell
        *tris, seg = _cut_simple(data, phi, neg, exact, xtol)
        return CutGeometry(*tris, seg, np.arange(n), n, subdivided)
    simple = np.flatnonzero(kind == 0)
    tri_m, cell_m, tri_p, cell_p, seg = _cut_simple(
        data, phi[simple], neg[simple], _compose(exact, simple), xtol
    )
    corner = np.flatnonzero(kind == CORNER)
    split = np.flatnonzero(_needs_split(kind))
    reference = np.broadcast_to(data.vertices, (corner.size, data.nv, 2))
    pieces = [
        (tri_m, simple[cell_m], tri_p, simple[cell_p], seg, simple),
        _corner(data, phi[corner], reference, corner),
        *_subdivide(data, phi, split, neg[split], kind[split], exact, xtol, max_depth),
    ]
    return _collect(pieces, n, subdivided)


def _cut_simple(
    data: CellData,
    phi: np.ndarray,
    neg: np.ndarray,
    exact: ExactLevelSet | None,
    xtol: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Sub-triangles ``(tri_minus, cell, tri_plus, cell)`` and the SEG3 ``(n, 3, 2)``
    of simply cut cells with topological vertex sides ``neg``."""
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


# -- subdivision -----------------------------------------------------------------------

_Pieces = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""``(tri_minus, cell, tri_plus, cell, seg, seg_cell)`` with rows of the parent ``phi``."""


def _needs_split(kind: np.ndarray) -> np.ndarray:
    """Cells that must be subdivided: flagged, and not just :data:`CORNER`."""
    return (kind != 0) & (kind != CORNER)


def _corner(data: CellData, phi: np.ndarray, vertices: np.ndarray, cells: np.ndarray) -> _Pieces:
    """Pieces of (sub-)cells flagged :data:`CORNER` only: wholly on side -1 (straight
    sub-triangles), with straight interface pieces along their zero edges,
    counter-clockwise so that side -1 is on their left.

    Args:
        data: Reference-cell data.
        phi: Nodal values of the (sub-)cells, shape ``(m, ndofs)``.
        vertices: Their vertices in the root cell, Basix order, shape ``(m, nv, 2)``.
        cells: Their root rows, shape ``(m,)``.
    """
    tris = straight_triangles(data, vertices)
    owner = np.repeat(cells, tris.shape[1])
    zero = zero_edges(data, phi)
    a = vertices[:, data.loop]
    b = np.roll(a, -1, axis=1)
    seg = np.stack([a, b, 0.5 * (a + b)], axis=2)[zero]
    seg_cell = np.broadcast_to(cells[:, None], zero.shape)[zero]
    no_tri, no_cell = np.zeros((0, 6, 2)), np.zeros(0, dtype=np.int64)
    return tris.reshape(-1, 6, 2), owner, no_tri, no_cell, seg, seg_cell


def _compose(
    exact: ExactLevelSet | None,
    rows: np.ndarray,
    origin: np.ndarray | None = None,
    matrix: np.ndarray | None = None,
) -> ExactLevelSet | None:
    """``exact`` for (sub-)cells ``k`` of the cells ``rows[k]``, at points mapped by
    ``origin[k] + matrix[k] X`` (identity when ``origin`` is ``None``)."""
    if exact is None:
        return None

    def composed(k: np.ndarray, X: np.ndarray) -> np.ndarray:
        mapped = X if origin is None else _map(X, origin[k], matrix[k])
        return _call_exact(exact, rows[k], mapped)

    return composed


def _affine(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Origin ``(m, 2)`` and matrix ``(m, 2, 2)`` of the maps ``X = V_0 + M xi`` of
    sub-cells with vertices ``(m, nv, 2)`` (Basix order) from their reference cell."""
    V = vertices
    return V[:, 0], np.stack([V[:, 1] - V[:, 0], V[:, 2] - V[:, 0]], axis=2)


def _map(points: np.ndarray, origin: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """Points ``(m, ..., 2)`` of sub-cells to the root cell's reference coordinates."""
    flat = points.reshape(points.shape[0], -1, 2)
    mapped = origin[:, None] + flat @ matrix.transpose(0, 2, 1)
    return mapped.reshape(points.shape)


def _restricted_values(data: CellData, phi: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Nodal values ``(m, ndofs)`` on sub-cells with vertices ``(m, nv, 2)`` (root
    reference coordinates) of the root interpolants ``phi`` ``(m, ndofs)``: exact
    for the affine (quadrilaterals: axis-parallel) sub-cells of :func:`split_cells`."""
    nodes = data.node_weights @ vertices
    basis = lagrange_basis(data.cell_type, data.degree, nodes.reshape(-1, 2))
    return (basis.reshape(len(phi), data.ndofs, -1) @ phi[:, :, None])[:, :, 0]


def _gap(
    data: CellData, phi: np.ndarray, seg: np.ndarray, exact: ExactLevelSet | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """How far SEG3s ``(m, 3, 2)`` stray from the zero set, relative to their chord:
    ``|phi| / |grad phi|`` (``phi``: the interpolant ``(m, ndofs)``, or ``exact``
    when given) at the quarter points ``s = 1/4, 3/4``, the larger one over the
    chord length (a circular arc of angle ``theta`` gives about ``theta^4 / 340``).

    Returns:
        The ratio ``(m,)`` (0 for zero-length pieces), the SEG3 point of the
        larger distance ``(m, 2)`` and the tangent there ``(m, 2)``.
    """
    m = seg.shape[0]
    rows = np.tile(np.arange(m), 2)
    N, dN = seg3_basis(np.repeat([0.25, 0.75], m))
    X = np.einsum("qk,qkd->qd", N, seg[rows])
    value, grad = _interpolant(data, phi[rows], X)
    if exact is not None:
        value = _call_exact(exact, rows, X)
    size = np.hypot(grad[:, 0], grad[:, 1])
    dist = np.divide(np.abs(value), size, out=np.zeros_like(size), where=size > 0)
    dist = dist.reshape(2, m)
    chord = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    ratio = np.divide(dist.max(axis=0), chord, out=np.zeros(m), where=chord > 0)
    pick = np.argmax(dist, axis=0) * m + np.arange(m)
    tangent = np.einsum("qk,qkd->qd", dN[pick], seg[rows[pick]])
    return ratio, X[pick], tangent


def _take(pieces: _Pieces, keep: np.ndarray, cells: np.ndarray) -> _Pieces:
    """The entries of ``pieces`` whose cell ``c`` has ``keep[c]``, relabelled ``cells[c]``."""
    tri_m, cell_m, tri_p, cell_p, seg, seg_cell = pieces
    m, p, s = keep[cell_m], keep[cell_p], keep[seg_cell]
    return tri_m[m], cells[cell_m[m]], tri_p[p], cells[cell_p[p]], seg[s], cells[seg_cell[s]]


def _subdivide(
    data: CellData,
    phi: np.ndarray,
    rows: np.ndarray,
    neg: np.ndarray,
    kind: np.ndarray,
    exact: ExactLevelSet | None,
    xtol: float,
    max_depth: int,
) -> list[_Pieces]:
    """Cut the cells ``rows`` of ``phi`` by recursive subdivision (module docstring).

    ``neg`` and ``kind`` are the :func:`~xfem_contact.cut_topology.topology` of
    ``phi[rows]``. All sub-cells of one level are processed together; each
    carries its root row and its vertices in the root's reference coordinates.
    Besides the sub-cells that need splitting, simply cut sub-cells whose SEG3
    strays from the zero set by more than ``_GAP`` times its chord (see
    :func:`_gap`) are split once more, through the SEG3 point farthest from the
    zero set and across its tangent, while depth allows; if one of their
    children then needs splitting, the coarse piece is kept instead (refining
    for accuracy never fails).
    """
    pieces: list[_Pieces] = []
    if rows.size == 0:
        return pieces
    root = rows
    vertices = np.broadcast_to(data.vertices, (rows.size, data.nv, 2))
    sub_phi = phi[rows]
    through, across = np.full((rows.size, 2), np.nan), np.full((rows.size, 2), np.nan)
    bent = np.zeros(rows.size, dtype=bool)
    fallback: _Pieces | None = None  # pieces of the bent sub-cells, by index in ``root``
    for depth in range(1, max_depth + 1):
        t = split_parameters(data, sub_phi, neg, kind, through, across)
        vertices = split_cells(data, vertices, t).reshape(-1, data.nv, 2)
        parent = np.repeat(np.arange(root.size), 4)
        sub_phi = _restricted_values(data, phi[root[parent]], vertices)
        neg, kind = topology(data, sub_phi)
        if fallback is not None:
            failed = bent & _needs_split(kind).reshape(-1, 4).any(axis=1)
            pieces.append(_take(fallback, failed, root))
            keep = ~failed[parent]
            vertices, parent, sub_phi = vertices[keep], parent[keep], sub_phi[keep]
            neg, kind = neg[keep], kind[keep]
        root = root[parent]
        origin, matrix = _affine(vertices)
        mixed = neg.any(axis=1) & ~neg.all(axis=1)
        bent = np.zeros(root.size, dtype=bool)
        through, across = np.full((root.size, 2), np.nan), np.full((root.size, 2), np.nan)
        cut = np.flatnonzero((kind == 0) & mixed)
        result: _Pieces | None = None
        if cut.size:
            sub_exact = _compose(exact, root[cut], origin[cut], matrix[cut])
            tri_m, cell_m, tri_p, cell_p, seg = _cut_simple(
                data, sub_phi[cut], neg[cut], sub_exact, xtol
            )
            if depth < max_depth:
                gap, through[cut], across[cut] = _gap(data, sub_phi[cut], seg, sub_exact)
                bent[cut] = gap > _GAP
            c_m, c_p = cut[cell_m], cut[cell_p]
            seg = _map(seg, origin[cut], matrix[cut])
            real = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1) > _TINY
            result = (
                _map(tri_m, origin[c_m], matrix[c_m]),
                c_m,
                _map(tri_p, origin[c_p], matrix[c_p]),
                c_p,
                seg[real],
                cut[real],
            )
            pieces.append(_take(result, ~bent, root))
        whole = np.flatnonzero((kind == 0) & ~mixed)
        if whole.size:
            tris = straight_triangles(data, vertices[whole])
            owner = np.repeat(root[whole], tris.shape[1])
            minus = np.repeat(neg[whole].all(axis=1), tris.shape[1])
            tris = tris.reshape(-1, 6, 2)
            empty = np.zeros((0, 3, 2)), np.zeros(0, dtype=np.int64)
            pieces.append((tris[minus], owner[minus], tris[~minus], owner[~minus], *empty))
        corner = np.flatnonzero(kind == CORNER)
        if corner.size:
            pieces.append(_corner(data, sub_phi[corner], vertices[corner], root[corner]))
        again = np.flatnonzero(_needs_split(kind) | bent)
        if again.size == 0:
            return pieces
        local = np.full(root.size, -1)
        local[again] = np.arange(again.size)
        fallback = None if result is None else _take(result, bent, local)
        root, vertices, sub_phi = root[again], vertices[again], sub_phi[again]
        neg, kind, bent = neg[again], kind[again], bent[again]
        through, across = through[again], across[again]
    raise ValueError(
        f"cannot cut {describe_cells(np.unique(root))}: after {max_depth} levels of "
        f"subdivision the interpolated level set still {describe_kinds(kind)} in a "
        "sub-cell (interface branches that cross or touch, or details finer than the "
        "sub-cells); perturb or smooth the level set there, refine the mesh, or raise max_depth"
    )


def _collect(pieces: list[_Pieces], n: int, subdivided: np.ndarray) -> CutGeometry:
    """Concatenate pieces and sort every array by cell (stable)."""
    fields = [np.concatenate([p[k] for p in pieces]) for k in range(6)]
    for values, cells in ((0, 1), (2, 3), (4, 5)):
        order = np.argsort(fields[cells], kind="stable")
        fields[values], fields[cells] = fields[values][order], fields[cells][order]
    return CutGeometry(*fields, n, subdivided)


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

        s = bracketed_root(f, s, np.zeros_like(s), np.ones_like(s), tol)
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
        u[ok] = newton_bracketed(
            lambda idx, t: g(ok[idx], t), np.zeros(ok.size), lo[ok], hi[ok], tol[ok]
        )
    if exact is not None:

        def f(idx: np.ndarray, t: np.ndarray) -> np.ndarray:
            return _call_exact(exact, act[idx], Ma[idx] + t[:, None] * nu[idx])

        u = bracketed_root(f, u, lo, hi, tol)
    u = np.where(np.abs(u) <= 8.0 * _EPS, 0.0, u)
    mid = M.copy()
    mid[act] = Ma + u[:, None] * nu
    return mid


# -- vectorised bracketed root finders ---------------------------------------------------
# Each solves one scalar equation per entry; ``func(idx, x)`` evaluates the entries
# ``idx`` at ``x``. Brackets satisfy f(lo) < 0 <= f(hi).
