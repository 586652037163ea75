"""Tetrahedra cut by the zero plane of a P1 level set: sub-tetrahedra of each side and
triangle pieces of the interface, in reference coordinates (pure numpy, no DOLFINx).

Each cell's level set is the linear interpolant of its four vertex values ``phi``,
shape ``(ncells, 4)``, in Basix vertex order of the reference tetrahedron
``(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)``. All coordinates are the parent
cell's (dimensionless) reference coordinates. The cut is exact: the interface of a
P1 level set is planar in every cell, so straight sub-cells represent both sides
and the interface without geometric error.

Tolerance policy: ``phi < 0`` is side -1 and ``phi >= 0`` is side +1, by exact
floating-point comparison (an exact zero counts as +1); the interface normal points
from side -1 to side +1. The crossing of an edge whose ends ``i`` (``phi_i < 0``) and
``j`` (``phi_j >= 0``) differ in side is ``X_i + t (X_j - X_i)`` with
``t = phi_i / (phi_i - phi_j)``; when ``phi_j == 0`` exactly it *is* vertex ``j``,
and sub-cells with a repeated point (zero volume or area) are dropped, which handles
the degenerate positions without snapping: the plane through a vertex, along an
edge, on a face. The interface of a cell is the zero set bounding its side -1,
``{phi = 0}`` in the cell when some ``phi < 0``, so a face where ``phi`` vanishes is an
interface piece of the cell on its negative side only, and a plane touching the cell
at a vertex or an edge gives no piece. A cell whose four values are zero has no
plane and is refused (``ValueError`` naming the cells). Values close to zero are
not rounded: they give tiny sub-cells of positive volume.

Everything is vectorised over cells; Python loops run over the three sign patterns
and the few sub-cells of each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_topology import nodal_values

__all__ = ["REFERENCE_TET", "TetCut", "classify_tets", "cut_tets"]

REFERENCE_TET = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
"""Vertices of the reference tetrahedron (Basix), shape ``(4, 3)``."""

_EDGES = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
"""Edges ``(i, j)`` of a tetrahedron with vertices sorted by side (negatives first);
point label ``4 + e`` is the crossing of edge ``e``."""


def _edge(i: int, j: int) -> int:
    return 4 + _EDGES.index((i, j))


def _prism(bottom: tuple[int, int, int], top: tuple[int, int, int]) -> list[tuple[int, ...]]:
    """Three tetrahedra of the prism with lateral edges ``bottom[k] - top[k]`` (consistent
    diagonals, so valid for every convex prism with planar lateral faces)."""
    v0, v1, v2 = bottom
    w0, w1, w2 = top
    return [(v0, v1, v2, w0), (v1, v2, w0, w1), (v2, w0, w1, w2)]


# Sub-cells per number k of negative vertices, in labels of the vertices sorted by side
# (0 .. k-1 negative): (side -1 tetrahedra, side +1 tetrahedra, interface triangles).
_TABLES = {
    1: (
        [(0, _edge(0, 1), _edge(0, 2), _edge(0, 3))],
        _prism((1, 2, 3), (_edge(0, 1), _edge(0, 2), _edge(0, 3))),
        [(_edge(0, 1), _edge(0, 2), _edge(0, 3))],
    ),
    2: (
        _prism((0, _edge(0, 2), _edge(0, 3)), (1, _edge(1, 2), _edge(1, 3))),
        _prism((2, _edge(0, 2), _edge(1, 2)), (3, _edge(0, 3), _edge(1, 3))),
        [
            (_edge(0, 2), _edge(0, 3), _edge(1, 3)),
            (_edge(0, 2), _edge(1, 3), _edge(1, 2)),
        ],
    ),
    3: (
        _prism((0, 1, 2), (_edge(0, 3), _edge(1, 3), _edge(2, 3))),
        [(3, _edge(0, 3), _edge(1, 3), _edge(2, 3))],
        [(_edge(0, 3), _edge(1, 3), _edge(2, 3))],
    ),
}


@dataclass(frozen=True)
class TetCut:
    """Sub-cells of tetrahedra cut by planes (reference coordinates of each parent).

    Every row of ``phi`` is covered: a cell on one side is one sub-tetrahedron (the
    reference cell) of that side.

    Attributes:
        tet_minus: Sub-tetrahedra of side -1, shape ``(nt_m, 4, 3)``; orientation is
            not fixed (rules use ``|det|``); none has zero volume.
        tet_minus_cell: Row of ``phi`` of each, shape ``(nt_m,)``, sorted.
        tet_plus: Sub-tetrahedra of side +1, shape ``(nt_p, 4, 3)``.
        tet_plus_cell: Their rows, shape ``(nt_p,)``, sorted.
        tri: Interface triangles, shape ``(ntri, 3, 3)``, oriented so that
            ``(b - a) x (c - a)`` points to side +1 in reference coordinates; none
            has zero area. A cell has 0, 1 or 2 of them.
        tri_normal: Reference unit normal of each (the direction of the level set's
            reference gradient, more accurate than the normal of a sliver triangle),
            shape ``(ntri, 3)``.
        tri_cell: Row of each, shape ``(ntri,)``, sorted.
        num_cells: Number of cells (rows of ``phi``).
    """

    tet_minus: npt.NDArray[np.float64]
    tet_minus_cell: npt.NDArray[np.int64]
    tet_plus: npt.NDArray[np.float64]
    tet_plus_cell: npt.NDArray[np.int64]
    tri: npt.NDArray[np.float64]
    tri_normal: npt.NDArray[np.float64]
    tri_cell: npt.NDArray[np.int64]
    num_cells: int


_FIELDS = {
    "tm": "tet_minus",
    "cm": "tet_minus_cell",
    "tp": "tet_plus",
    "cp": "tet_plus_cell",
    "tr": "tri",
    "ntr": "tri_normal",
    "ctr": "tri_cell",
}


def _check(phi: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``phi`` as float64 ``(ncells, 4)``; raises naming the first bad cell."""
    phi = nodal_values(phi, 4, "P1 tetrahedron", "tetrahedron")
    flat = np.flatnonzero((phi == 0.0).all(axis=1))
    if flat.size:
        raise ValueError(
            f"the level set vanishes at all four vertices of tetrahedron {flat[0]} "
            f"({flat.size} cell(s), rows {flat[:10].tolist()}): no interface plane"
        )
    return phi


def classify_tets(phi: npt.ArrayLike) -> npt.NDArray[np.int8]:
    """Side of each tetrahedron: -1, +1, or 0 when :func:`cut_tets` gives it sub-cells on
    both sides or an interface piece (a face where ``phi`` vanishes, ``phi < 0`` at the
    fourth vertex).

    Args:
        phi: Vertex values, shape ``(ncells, 4)``.

    Returns:
        ``int8`` array of shape ``(ncells,)``.

    Raises:
        ValueError: Bad shape, non-finite values or four zero values; names the cell.
    """
    phi = _check(phi)
    neg = (phi < 0).any(axis=1)
    pos = (phi > 0).any(axis=1)
    face = (phi < 0).sum(axis=1) == 1
    face &= (phi == 0).sum(axis=1) == 3
    side = np.where(neg, -1, 1)
    return np.where(neg & (pos | face), 0, side).astype(np.int8)


def cut_tets(phi: npt.ArrayLike) -> TetCut:
    """Cut tetrahedra by the zero plane of their P1 level sets (see the module's policy).

    Args:
        phi: Vertex values, shape ``(ncells, 4)`` (Basix vertex order).

    Returns:
        A :class:`TetCut` covering every row.

    Raises:
        ValueError: Bad shape, non-finite values or four zero values; names the cell.
    """
    phi = _check(phi)
    ncells = phi.shape[0]
    neg = phi < 0
    nneg = neg.sum(axis=1)
    keys = ("tm", "cm", "tp", "cp", "tr", "ntr", "ctr")
    parts: dict[str, list[np.ndarray]] = {k: [] for k in keys}
    ref = np.broadcast_to(REFERENCE_TET, (ncells, 4, 3))
    for k, key_t, key_c in ((4, "tm", "cm"), (0, "tp", "cp")):
        rows = np.flatnonzero(nneg == k)
        parts[key_t].append(ref[rows])
        parts[key_c].append(rows)
    for k, (minus, plus, tris) in _TABLES.items():
        rows = np.flatnonzero(nneg == k)
        order = np.argsort(~neg[rows], axis=1, kind="stable")  # negatives first
        values = np.take_along_axis(phi[rows], order, axis=1)
        points, labels = _points(REFERENCE_TET[order], values)
        for table, key_t, key_c in ((minus, "tm", "cm"), (plus, "tp", "cp")):
            cells, cell_rows = _simplices(points, labels, table, rows)
            keep = _volume(cells) != 0.0
            parts[key_t].append(cells[keep])
            parts[key_c].append(cell_rows[keep])
        tri, tri_rows = _simplices(points, labels, tris, rows)
        gradient = _gradient(phi[tri_rows])
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        flip = (normal * gradient).sum(axis=1) < 0
        tri[flip] = tri[flip][:, [0, 2, 1]]
        keep = (normal != 0.0).any(axis=1)
        parts["tr"].append(tri[keep])
        parts["ntr"].append(gradient[keep] / np.linalg.norm(gradient[keep], axis=1)[:, None])
        parts["ctr"].append(tri_rows[keep])
    arrays = {}
    for key_c, key_data in (("cm", ("tm",)), ("cp", ("tp",)), ("ctr", ("tr", "ntr"))):
        rows = np.concatenate(parts[key_c]).astype(np.int64)
        order = np.argsort(rows, kind="stable")
        arrays[key_c] = rows[order]
        for key in key_data:
            shape = {"tm": (4, 3), "tp": (4, 3), "tr": (3, 3), "ntr": (3,)}[key]
            arrays[key] = np.concatenate(parts[key]).reshape(-1, *shape)[order]
    return TetCut(num_cells=ncells, **{_FIELDS[k]: arrays[k] for k in keys})


def _points(vertices: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and edge crossings of cells with vertices sorted by side, and a label per
    point that identifies coincident ones (a crossing at a zero vertex has its label).

    Args:
        vertices: Sorted reference vertices, shape ``(m, 4, 3)``.
        values: Their level-set values, shape ``(m, 4)``.

    Returns:
        Points ``(m, 10, 3)`` (4 vertices, 6 crossings; a crossing of an edge not cut
        is meaningless and never used) and labels ``(m, 10)``.
    """
    m = values.shape[0]
    points = np.empty((m, 10, 3))
    points[:, :4] = vertices
    labels = np.tile(np.arange(10), (m, 1))
    for e, (i, j) in enumerate(_EDGES):
        a, b = values[:, i], values[:, j]
        cut = (a < 0) & (b >= 0)
        t = np.divide(a, a - b, out=np.zeros_like(a), where=cut)
        points[:, 4 + e] = vertices[:, i] + t[:, None] * (vertices[:, j] - vertices[:, i])
        at_vertex = cut & (b == 0.0)
        points[at_vertex, 4 + e] = vertices[at_vertex, j]
        labels[at_vertex, 4 + e] = j
    return points, labels


def _simplices(
    points: np.ndarray, labels: np.ndarray, table: list[tuple[int, ...]], rows: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The simplices of ``table`` in every cell, without those with a repeated point.

    Returns:
        Simplices ``(n, len(table[0]), 3)`` and their cell rows ``(n,)``.
    """
    index = np.asarray(table)  # (ns, nv)
    cells = points[:, index]  # (m, ns, nv, 3)
    lab = np.sort(labels[:, index], axis=2)
    distinct = (np.diff(lab, axis=2) != 0).all(axis=2)  # (m, ns)
    m_idx, s_idx = np.nonzero(distinct)
    return cells[m_idx, s_idx], rows[m_idx]


def _volume(tets: np.ndarray) -> np.ndarray:
    """Signed ``det`` of the edge vectors of tetrahedra ``(n, 4, 3)`` (6 x volume)."""
    return np.linalg.det(tets[:, 1:] - tets[:, :1]) if tets.size else np.zeros(0)


def _gradient(phi: np.ndarray) -> np.ndarray:
    """Reference gradient of P1 level sets with vertex values ``phi`` ``(n, 4)``."""
    return phi[:, 1:] - phi[:, :1]
