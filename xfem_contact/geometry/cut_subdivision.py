"""Cells that one SEG3 cannot represent: recursive subdivision, and corner cells.

Helper of :mod:`xfem_contact.geometry.cut` (pure numpy and Basix, no DOLFINx):
:func:`corner_pieces` and :func:`subdivide` return :data:`Pieces` with rows of
the parent ``phi``, which the driver concatenates.

Degeneracy policy: a *simple* cut crosses the cell boundary exactly twice and
is represented by one SEG3 (:mod:`xfem_contact.geometry.cut_simple`). A cell whose
interpolant

* crosses an edge twice (a cap; dips within the tangency bound of
  :mod:`xfem_contact.geometry.cut_topology` do not count),
* crosses the boundary more than twice (several pieces, e.g. near a saddle), or
* changes sign inside but not on the boundary (a closed piece; degree 2 only,
  seen on a 9 x 9 sample lattice, so smaller pieces between its points are missed)

is *subdivided*: in reference coordinates into 4 sub-cells (quadrilateral:
4 rectangles; triangle: 3 corner triangles and a middle one), at the edge
mid-points except that an edge crossed twice is divided between its crossings
(at the extremum of its polynomial) and a closed piece through its inside
(:func:`xfem_contact.geometry.cut_children.subdivision_parameters`). On an affine sub-cell
the interpolant is again a Lagrange interpolant of the same degree, with the
parent's values at the sub-cell's nodes; ``exact`` is composed with the
sub-cell map. Sub-cells are cut as reference cells (the same rules, ``xtol``
in sub-cell units), uncut ones become straight sub-triangles of their side,
and everything is mapped back affinely (P2 nodes map exactly). Sub-cells that
still need it are subdivided again, up to ``max_depth`` levels (default
:data:`xfem_contact.geometry.cut.MAX_DEPTH` = 5). Inside subdivided cells only, a simply
cut sub-cell whose SEG3 strays from the zero set by more than ``2e-4`` times its chord at
its quarter points (as a circular arc of about 29 degrees would) is subdivided
once more through the farthest point while depth allows, unless one of its
children would then need subdivision (accuracy refinement never fails). A
subdivided cell has one SEG3 per cut sub-cell (those shorter than ``64 eps``
dropped), possibly none.

A (sub-)cell whose interpolant vanishes identically on two or more of its
edges and is negative at its other vertices (a corner of a mesh-aligned
interface, or crossing branches meeting at a subdivision point) lies wholly on side
-1 and carries those edges as straight interface pieces (:func:`corner_pieces`):
the convention of an interface along one edge, where the cell on side -1
carries it. If such a degree-2 interpolant turns positive inside, the cell is
subdivided instead.

After ``max_depth`` levels :func:`subdivide` raises ``ValueError`` naming
the cells and the reason. This happens for interface branches that cross
(an exact saddle with zero value) away from subdivision points, and for details
finer than the last level. Cells that are not subdivided are never refined for
accuracy, however strongly their SEG3 bends.
"""

from __future__ import annotations

import numpy as np

from xfem_contact.geometry.cut_children import (
    child_cells,
    straight_triangles,
    subdivision_parameters,
)
from xfem_contact.geometry.cut_simple import ExactLevelSet, call_exact, cut_simple, interpolant
from xfem_contact.geometry.cut_topology import (
    CORNER,
    CellData,
    describe_cells,
    describe_kinds,
    lagrange_basis,
    seg3_basis,
    topology,
    zero_edges,
)

_EPS = np.finfo(np.float64).eps
_TINY = 64.0 * _EPS  # pieces of subdivided cells shorter than this (reference units) are dropped
_GAP = 2e-4  # SEG3 distance to the zero set / chord refined in subdivided cells (~29 deg arcs)

Pieces = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""``(tri_minus, cell, tri_plus, cell, seg, seg_cell)`` with rows of the parent ``phi``."""


def needs_subdivision(kind: np.ndarray) -> np.ndarray:
    """Cells that must be subdivided, boolean ``(n,)``, from the ``kind`` flags
    ``(n,)`` of :func:`~xfem_contact.geometry.cut_topology.topology`: flagged, and not
    just :data:`CORNER`."""
    return (kind != 0) & (kind != CORNER)


def corner_pieces(
    data: CellData, phi: np.ndarray, vertices: np.ndarray, cells: np.ndarray
) -> Pieces:
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


def compose(
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
        return call_exact(exact, rows[k], mapped)

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
    for the affine (quadrilaterals: axis-parallel) sub-cells of :func:`child_cells`."""
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
    value, grad = interpolant(data, phi[rows], X)
    if exact is not None:
        value = call_exact(exact, rows, X)
    size = np.hypot(grad[:, 0], grad[:, 1])
    dist = np.divide(np.abs(value), size, out=np.zeros_like(size), where=size > 0)
    dist = dist.reshape(2, m)
    chord = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    ratio = np.divide(dist.max(axis=0), chord, out=np.zeros(m), where=chord > 0)
    pick = np.argmax(dist, axis=0) * m + np.arange(m)
    tangent = np.einsum("qk,qkd->qd", dN[pick], seg[rows[pick]])
    return ratio, X[pick], tangent


def _take(pieces: Pieces, keep: np.ndarray, cells: np.ndarray) -> Pieces:
    """The entries of ``pieces`` whose cell ``c`` has ``keep[c]``, relabelled ``cells[c]``."""
    tri_m, cell_m, tri_p, cell_p, seg, seg_cell = pieces
    m, p, s = keep[cell_m], keep[cell_p], keep[seg_cell]
    return tri_m[m], cells[cell_m[m]], tri_p[p], cells[cell_p[p]], seg[s], cells[seg_cell[s]]


def subdivide(
    data: CellData,
    phi: np.ndarray,
    rows: np.ndarray,
    neg: np.ndarray,
    kind: np.ndarray,
    exact: ExactLevelSet | None,
    xtol: float,
    max_depth: int,
) -> list[Pieces]:
    """Cut the cells ``rows`` of ``phi`` by recursive subdivision (module docstring),
    as a list of :data:`Pieces` with rows of ``phi``.

    All sub-cells of one level are processed together; each carries its root
    row and its vertices in the root's reference coordinates. Besides the
    sub-cells that need subdivision, simply cut sub-cells whose SEG3 strays from
    the zero set by more than ``_GAP`` times its chord (see :func:`_gap`) are
    subdivided once more, through the SEG3 point farthest from the zero set and
    across its tangent, while depth allows; if one of their children then needs
    subdivision, the coarse piece is kept instead (refining for accuracy never
    fails).

    Args:
        data: Reference-cell data.
        phi: Nodal values of all cut cells, shape ``(n, ndofs)``.
        rows: The cells to subdivide, shape ``(m,)``.
        neg: Vertex sides of ``phi[rows]`` from
            :func:`~xfem_contact.geometry.cut_topology.topology`, ``(m, nv)``.
        kind: Their flags from the same, ``(m,)``.
        exact: Optional exact level set on the rows of ``phi``.
        xtol: Root tolerance in sub-cell units.
        max_depth: Maximum number of subdivision levels.

    Raises:
        ValueError: Sub-cells still need subdivision after ``max_depth`` levels.
    """
    pieces: list[Pieces] = []
    if rows.size == 0:
        return pieces
    root = rows
    vertices = np.broadcast_to(data.vertices, (rows.size, data.nv, 2))
    sub_phi = phi[rows]
    through, across = np.full((rows.size, 2), np.nan), np.full((rows.size, 2), np.nan)
    bent = np.zeros(rows.size, dtype=bool)
    fallback: Pieces | None = None  # pieces of the bent sub-cells, by index in ``root``
    for depth in range(1, max_depth + 1):
        t = subdivision_parameters(data, sub_phi, neg, kind, through, across)
        vertices = child_cells(data, vertices, t).reshape(-1, data.nv, 2)
        parent = np.repeat(np.arange(root.size), 4)
        sub_phi = _restricted_values(data, phi[root[parent]], vertices)
        neg, kind = topology(data, sub_phi)
        if fallback is not None:
            failed = bent & needs_subdivision(kind).reshape(-1, 4).any(axis=1)
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
        result: Pieces | None = None
        if cut.size:
            sub_exact = compose(exact, root[cut], origin[cut], matrix[cut])
            tri_m, cell_m, tri_p, cell_p, seg = cut_simple(
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
            pieces.append(corner_pieces(data, sub_phi[corner], vertices[corner], root[corner]))
        again = np.flatnonzero(needs_subdivision(kind) | bent)
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
