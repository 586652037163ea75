"""One level of subdivision: (sub-)cells into four children, and straight sub-triangles
of uncut ones.

Helper of :mod:`xfem_contact.geometry.cut_subdivision` (pure numpy). Cells flagged by
:func:`xfem_contact.geometry.cut_topology.topology` as needing subdivision are subdivided
at one parameter per loop edge (:func:`subdivision_parameters`: the mid-points, or
adaptive points that separate a cap on an edge or a closed interface piece)
into four children (:func:`child_cells`), all in the reference coordinates of
the root cell. Children are affine images of the reference cell
(quadrilaterals: axis-parallel rectangles), so the level set on them is again a
Lagrange interpolant of the root's degree. :func:`straight_triangles` tiles
(sub-)cells that lie wholly on one side by straight P2 triangles.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_topology import (
    INTERIOR,
    TANGENCY,
    TWICE,
    CellData,
    double_crossings,
    interior_values,
    loop_edges,
)

_MARGIN = 1.0 / 16.0  # adaptive subdivision parameters stay in [margin, 1 - margin]


def subdivision_parameters(
    data: CellData,
    phi: np.ndarray,
    neg: np.ndarray,
    kind: np.ndarray,
    through: np.ndarray | None = None,
    across: np.ndarray | None = None,
) -> npt.NDArray[np.float64]:
    """Where to subdivide each loop edge of cells that need it, ``(ncells, nv)``.

    By default the mid-point (1/2). An edge crossed twice (:data:`TWICE`) is
    divided at the extremum of its polynomial, between the two crossings, so that
    a cap of any width is separated in one step. Otherwise a cell with a point
    ``through`` is subdivided by a line through it: an uncut cell with an interior
    sign change (:data:`INTERIOR`) through the lattice point of largest
    opposite value, inside the closed piece (both lines for quadrilaterals,
    the one parallel to edge (1, 2) for triangles); with a direction ``across``
    given, by the one available line most transversal to it. Adaptive parameters are clamped
    to ``[1/16, 15/16]``. Quadrilaterals are subdivided along one ``X`` and one ``Y``
    line, so opposite loop edges get matching parameters (``t_2 = 1 - t_0``,
    ``t_3 = 1 - t_1``).

    Args:
        data: Reference-cell data.
        phi: Nodal values, shape ``(ncells, ndofs)``.
        neg: Topological vertex sides from :func:`~xfem_contact.geometry.cut_topology.topology`,
            ``(ncells, nv)``.
        kind: Flags from :func:`~xfem_contact.geometry.cut_topology.topology`, ``(ncells,)``.
        through: Optional points to subdivide through, ``(ncells, 2)``, NaN rows: none.
        across: Optional directions to cross there, ``(ncells, 2)``, NaN rows: any.
    """
    n, nv = neg.shape
    P = np.full((n, 2), np.nan) if through is None else through.copy()
    d = np.full((n, 2), np.nan) if across is None else across
    interior = np.flatnonzero(((kind & INTERIOR) != 0) & ((kind & TWICE) == 0))
    if interior.size:
        values = interior_values(data, phi, interior)
        sign = np.where(neg[interior].any(axis=1), 1.0, -1.0)  # towards the other side
        P[interior] = data.lattice[np.argmax(sign[:, None] * values, axis=1)]
    P = np.clip(P, _MARGIN, 1.0 - _MARGIN)
    t = np.full((n, nv), 0.5)
    has, free = ~np.isnan(P[:, 0]), np.isnan(d[:, 0])
    if data.cell_type == "triangle":
        # Lines through P parallel to edge (1, 2), (0, 2), (0, 1): the cuts of corners 0, 1, 2
        directions = np.array([[1.0, -1.0], [0.0, 1.0], [1.0, 0.0]])
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        dd = np.nan_to_num(d)
        cross = np.abs(dd[:, [0]] * directions[:, 1] - dd[:, [1]] * directions[:, 0])
        line = np.where(free, 0, np.argmax(cross, axis=1))
        x, y = P[:, 0], P[:, 1]
        s = np.clip(x + y, _MARGIN, 1.0 - _MARGIN)
        options = [{0: s, 2: 1.0 - s}, {0: x, 1: 1.0 - x}, {2: 1.0 - y, 1: y}]
        for k, option in enumerate(options):
            rows = has & (line == k)
            for edge, value in option.items():
                t[rows, edge] = value[rows]
    else:
        along_x = np.abs(d[:, 0]) >= np.abs(d[:, 1])  # cross such directions by an X = c line
        t[:, 0] = np.where(has & (free | along_x), P[:, 0], t[:, 0])
        t[:, 1] = np.where(has & (free | ~along_x), P[:, 1], t[:, 1])
    start, _, A, B = loop_edges(data, phi)
    tol = TANGENCY * np.abs(phi).max(axis=1)
    double, tstar = double_crossings(start, A, B, neg, tol)
    tstar = np.clip(np.where(double, tstar, 0.5), _MARGIN, 1.0 - _MARGIN)
    if data.cell_type == "triangle":
        t = np.where(double, tstar, t)
    else:  # per axis: the first of the two parallel edges that is crossed twice
        for axis in (0, 1):
            first, other = tstar[:, axis], 1.0 - tstar[:, axis + 2]
            adaptive = np.where(double[:, axis], first, other)
            t[:, axis] = np.where(double[:, axis] | double[:, axis + 2], adaptive, t[:, axis])
        t[:, 2:] = 1.0 - t[:, :2]
    return t


def child_cells(data: CellData, vertices: np.ndarray, t: np.ndarray) -> npt.NDArray[np.float64]:
    """The four children of cells subdivided at the loop-edge parameters ``t``
    (``(m, nv)``, from :func:`subdivision_parameters`).

    Triangles have three corner triangles and a middle one as children; quadrilaterals
    (axis-parallel rectangles in the coordinates of ``vertices``) into four
    rectangles. Children keep the orientation of the parent, and vertices shared
    by siblings are the same floating-point numbers.

    Args:
        data: Reference-cell data.
        vertices: Vertices of the cells in Basix order, shape ``(m, nv, 2)``.
        t: Subdivision parameters, shape ``(m, nv)``.

    Returns:
        Vertices of the children, shape ``(m, 4, nv, 2)``.
    """

    def point(a: np.ndarray, b: np.ndarray, s: np.ndarray) -> np.ndarray:
        s = s[:, None]
        return (1.0 - s) * a + s * b  # symmetric in (a, b) for s = 1/2

    V = [vertices[:, i] for i in range(vertices.shape[1])]
    if data.cell_type == "triangle":
        p01, p12, p20 = (
            point(V[0], V[1], t[:, 0]),
            point(V[1], V[2], t[:, 1]),
            point(V[2], V[0], t[:, 2]),
        )
        children = [(V[0], p01, p20), (p01, V[1], p12), (p20, p12, V[2]), (p12, p20, p01)]
    else:
        x0, x1, y0, y1 = V[0][:, 0], V[1][:, 0], V[0][:, 1], V[2][:, 1]
        xs = point(x0[:, None], x1[:, None], t[:, 0])[:, 0]
        ys = point(y0[:, None], y1[:, None], t[:, 1])[:, 0]
        children = []
        for ya, yb in ((y0, ys), (ys, y1)):
            for xa, xb in ((x0, xs), (xs, x1)):
                corners = [(xa, ya), (xb, ya), (xa, yb), (xb, yb)]
                children.append(tuple(np.stack(c, axis=1) for c in corners))
    return np.stack([np.stack(c, axis=1) for c in children], axis=1)


def straight_triangles(data: CellData, vertices: np.ndarray) -> npt.NDArray[np.float64]:
    """Straight P2 triangles tiling cells, counter-clockwise, Basix node order:
    shape ``(m, 1, 6, 2)`` for triangles, ``(m, 2, 6, 2)`` for quadrilaterals
    (diagonal from vertex 0 to vertex 3), from vertices ``(m, nv, 2)`` (Basix order)."""
    tris = [(0, 1, 2)] if data.cell_type == "triangle" else [(0, 1, 3), (0, 3, 2)]
    v = vertices[:, np.array(tris)]  # (m, ntri, 3, 2)
    mids = 0.5 * (v[:, :, [1, 0, 0]] + v[:, :, [2, 2, 1]])
    return np.concatenate([v, mids], axis=2)
