"""VTK grids of a cut 3D mesh (tetrahedra, hexahedra) and its results, as
:class:`~xfem_contact.io.vtu.GridArrays`.

A 3D cut keeps no sub-cells (its rules come from the level set itself), so the grids are
drawn from the level-set interpolant ``phi_h``: each cut cell is split into linear
sub-tetrahedra (``2^levels`` per edge; a hexahedron's sub-cubes into six tetrahedra
each), ``phi_h`` is taken at their vertices, and each sub-tetrahedron is clipped where
``phi_h`` vanishes on its edges (marching tetrahedra): on each side a tetrahedron or a
wedge, and the triangles of the interface between them, whose nodes lie on ``phi_h = 0``
(the surface drawn is within ``O((h / 2^levels)^2)`` of it between them; the rules of the
cut do not use it). Uncut cells are the mesh's linear cells. Fields are evaluated at
every node of every piece in its parent cell (the exact P2/Q2 values there), each side
with its own field, so the lips are separate. Coordinates in m; every grid holds this
process's owned cells.

Cell data: ``side`` (-1, +1; 0 on the interface), ``cut`` (1 in cut cells), ``cell``
(local index of the parent cell).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.vtu import GridArrays, _Block, grid_arrays

#: VTK cell types (``vtkCellType.h``)
TRIANGLE, TETRA, HEXAHEDRON, WEDGE = 5, 10, 12, 13
#: Reference vertices of the uncut cells in VTK order, and their VTK type
_VERTICES = {
    "tetrahedron": (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float), TETRA),
    "hexahedron": (
        np.array(
            [[x, y, z] for z in (0, 1) for x, y in ((0, 0), (1, 0), (1, 1), (0, 1))], dtype=float
        ),
        HEXAHEDRON,
    ),
}
#: A (VTK-ordered) hexahedron as six tetrahedra around its diagonal 0-6 (Kuhn's split:
#: the split faces of neighbouring sub-cubes match)
_HEX_TETS = np.array(
    [[0, 1, 2, 6], [0, 2, 3, 6], [0, 3, 7, 6], [0, 7, 4, 6], [0, 4, 5, 6], [0, 5, 1, 6]]
)


def _red_refinement(tets: np.ndarray) -> np.ndarray:
    """Each tetrahedron ``(n, 4, 3)`` split in eight by its edge midpoints (the faces in
    four triangles each, so neighbours' refinements match), shape ``(8 n, 4, 3)``."""
    v = [tets[:, k] for k in range(4)]
    m = {(i, j): 0.5 * (v[i] + v[j]) for i in range(4) for j in range(i + 1, 4)}
    children = [
        (v[0], m[0, 1], m[0, 2], m[0, 3]),
        (m[0, 1], v[1], m[1, 2], m[1, 3]),
        (m[0, 2], m[1, 2], v[2], m[2, 3]),
        (m[0, 3], m[1, 3], m[2, 3], v[3]),
    ]  # the octahedron around its diagonal m02 - m13, ring m01, m12, m23, m03
    ring = [m[0, 1], m[1, 2], m[2, 3], m[0, 3]]
    children += [(m[0, 2], m[1, 3], ring[k], ring[(k + 1) % 4]) for k in range(4)]
    return np.stack([np.stack(c, axis=1) for c in children], axis=1).reshape(-1, 4, 3)


def reference_subcells(cell: str, levels: int) -> tuple[np.ndarray, int]:
    """Linear sub-cells of the reference ``cell`` (tetrahedron, hexahedron), ``2^levels``
    per edge: vertices ``(m, nv, 3)`` in VTK order, and their VTK type."""
    if cell == "tetrahedron":
        tets = _VERTICES["tetrahedron"][0][None]
        for _ in range(levels):
            tets = _red_refinement(tets)
        return tets, TETRA
    k = 2**levels
    origins = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 1, 3)
    return (origins + _VERTICES["hexahedron"][0]) / k, HEXAHEDRON


def reference_tets(cell: str, levels: int) -> np.ndarray:
    """:func:`reference_subcells` as tetrahedra ``(m, 4, 3)`` (sub-cubes split in six)."""
    sub, vtk_type = reference_subcells(cell, levels)
    return sub if vtk_type == TETRA else sub[:, _HEX_TETS].reshape(-1, 4, 3)


@dataclasses.dataclass(frozen=True)
class Pieces:
    """The linear pieces of the cut cells: for each side (-1, +1) the tetrahedra and
    wedges inside it, and the interface triangles; each as parent cells ``(n,)`` (local
    indices) and reference nodes ``(n, k, 3)`` in VTK order."""

    sides: dict
    interface: tuple


#: Regula falsi steps (Illinois) that move an edge point onto the zero of the level set
ROOT_STEPS = 10


def _edge_points(
    X: np.ndarray, phi: np.ndarray, i: np.ndarray, j: np.ndarray, value=None
) -> np.ndarray:
    """Where ``phi`` vanishes on the edges ``(i, j)`` of each tetrahedron: ``X (n, 4, 3)``,
    ``phi (n, 4)`` its values at the vertices, ``i, j (n,)`` -> ``(n, 3)``. The zero of
    the linear interpolant, or with ``value`` (the field at points ``(n, 3)`` of the
    tetrahedra, ``(n,)``) the zero of the field itself on the edge, by
    :data:`ROOT_STEPS` steps of the Illinois regula falsi."""
    rows = np.arange(X.shape[0])
    fa, fb = phi[rows, i], phi[rows, j]
    a, b = np.zeros(rows.size), np.ones(rows.size)
    t = fa / (fa - fb)
    start, step = X[rows, i], X[rows, j] - X[rows, i]
    last = np.zeros(rows.size, dtype=np.int8)  # the end moved last: -1 a, +1 b
    for _ in range(ROOT_STEPS if value is not None else 0):
        ft = value(start + t[:, None] * step)
        left = np.sign(ft) == np.sign(fa)  # the root is in (t, b): a moves
        fb = np.where(left & (last == -1), 0.5 * fb, fb)  # the same end twice: Illinois
        fa = np.where(~left & (last == 1), 0.5 * fa, fa)
        a, fa = np.where(left, t, a), np.where(left, ft, fa)
        b, fb = np.where(left, b, t), np.where(left, fb, ft)
        last = np.where(left, -1, 1).astype(np.int8)
        t = np.clip(a - fa * (b - a) / np.where(fb != fa, fb - fa, 1.0), a, b)
    return start + t[:, None] * step


def clip_tets(X: np.ndarray, phi: np.ndarray, value=None) -> tuple[dict, np.ndarray, np.ndarray]:
    """Marching tetrahedra. ``X (n, 4, 3)``, ``phi (n, 4)`` (a field at the vertices of
    each tetrahedron): per side ``s`` (-1 where ``phi < 0``, +1 else) the pieces inside
    it, ``{s: [(rows, nodes, vtk_type), ...]}`` (``rows`` the tetrahedra they come from,
    ``nodes`` ``(r, 4, 3)`` tetrahedra or ``(r, 6, 3)`` wedges), and the interface
    triangles ``(rows, nodes (r, 3, 3))``. Their nodes on edges are the zeros of the
    linear interpolant of ``phi``, or with ``value(rows, points)`` (the field at points
    ``(r, 3)`` of the tetrahedra ``rows``) those of the field on the edges."""
    inside = phi < 0.0
    count = inside.sum(axis=1)
    order = np.argsort(~inside, axis=1, kind="stable")  # side -1's vertices first
    sides = {-1: [], 1: []}
    tri_rows, tri_nodes = [], []
    for k in (1, 2, 3):
        rows = np.flatnonzero(count == k)
        if rows.size == 0:
            continue
        Xr, pr, o = X[rows], phi[rows], order[rows]
        v = [Xr[np.arange(rows.size), o[:, m]] for m in range(4)]

        at = None if value is None else (lambda points, rows=rows: value(rows, points))

        def e(a, b, Xr=Xr, pr=pr, o=o, at=at):
            return _edge_points(Xr, pr, o[:, a], o[:, b], at)

        if k == 1:  # vertex 0 on side -1
            ends = [e(0, 1), e(0, 2), e(0, 3)]
            sides[-1].append((rows, np.stack([v[0], *ends], axis=1), TETRA))
            sides[1].append((rows, np.stack([v[1], v[2], v[3], *ends], axis=1), WEDGE))
            tris = [np.stack(ends, axis=1)]
        elif k == 3:  # vertex 3 on side +1
            ends = [e(0, 3), e(1, 3), e(2, 3)]
            sides[1].append((rows, np.stack([v[3], *ends], axis=1), TETRA))
            sides[-1].append((rows, np.stack([v[0], v[1], v[2], *ends], axis=1), WEDGE))
            tris = [np.stack(ends, axis=1)]
        else:  # vertices 0, 1 on side -1, 2, 3 on side +1
            e02, e03, e12, e13 = e(0, 2), e(0, 3), e(1, 2), e(1, 3)
            sides[-1].append((rows, np.stack([v[0], e02, e03, v[1], e12, e13], axis=1), WEDGE))
            sides[1].append((rows, np.stack([v[2], e02, e12, v[3], e03, e13], axis=1), WEDGE))
            tris = [np.stack([e02, e03, e13], axis=1), np.stack([e02, e13, e12], axis=1)]
        for t in tris:
            tri_rows.append(rows)
            tri_nodes.append(t)
    for s, whole in ((-1, count == 4), (1, count == 0)):
        rows = np.flatnonzero(whole)
        sides[s].append((rows, X[rows], TETRA))
    if tri_rows:
        return sides, np.concatenate(tri_rows), np.concatenate(tri_nodes)
    return sides, np.zeros(0, dtype=np.int64), np.zeros((0, 3, 3))


def cut_pieces(cut: CutMesh, levels: int = 1) -> Pieces:
    """The cut cells of ``cut`` (owned, this process) split into linear pieces (see the
    module), the interface triangles sorted by parent cell."""
    tets = reference_tets(cut.mesh.topology.cell_name(), levels)
    m = tets.shape[0]
    cells = np.repeat(cut.cut_cells, m).astype(np.int32)
    X = np.tile(tets, (cut.cut_cells.size, 1, 1))
    phi = cut.maps.values(np.repeat(cells, 4), X.reshape(-1, 3)).reshape(-1, 4)
    sides, rows, nodes = clip_tets(X, phi, lambda rows, x: cut.maps.values(cells[rows], x))
    pieces = {s: [(cells[r], n, t) for r, n, t in blocks] for s, blocks in sides.items()}
    order = np.argsort(cells[rows], kind="stable")
    parents = cells[rows][order]
    return Pieces(pieces, (parents, _outward(cut, parents, nodes[order])))


def _outward(cut: CutMesh, cells: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Triangles ``X (n, 3, 3)`` (reference nodes) turned so that their physical normal
    ``(x1 - x0) x (x2 - x0)`` points to side +1 (along the gradient of ``phi_h`` at their
    centroid)."""
    if cells.size == 0:
        return X
    centroid = X.mean(axis=1)
    J = cut.maps.jacobian(cells, centroid)  # (n, 3, 3)
    g = cut.maps.grad_ref(cells, centroid)[:, :, None]
    gradient = np.linalg.solve(J.transpose(0, 2, 1), g)[:, :, 0]
    x = cut.maps.push_forward(np.repeat(cells, 3), X.reshape(-1, 3)).reshape(-1, 3, 3)
    normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    inward = np.einsum("ij,ij->i", normal, gradient) < 0
    X = X.copy()
    X[inward] = X[inward][:, [0, 2, 1]]
    return X


def lips_arrays_3d(
    cut: CutMesh, u_minus, u_plus, fields: dict | None = None, levels: int = 1
) -> GridArrays:
    """Uncut cells and the pieces of the cut cells (:func:`cut_pieces`) of each side with
    point data ``u`` (m), each side's own, and the ``fields`` given (name to ``{-1:
    Function, 1: Function}``, e.g. ``stress``)."""
    named = {"u": {-1: u_minus, 1: u_plus}} | (fields or {})
    return grid_arrays(cut, _blocks(cut, cut_pieces(cut, levels), uncut=True), named)


def subcell_arrays_3d(cut: CutMesh, levels: int = 1) -> GridArrays:
    """The pieces of the cut cells of both sides (:func:`cut_pieces`)."""
    return grid_arrays(cut, _blocks(cut, cut_pieces(cut, levels), uncut=False))


#: Node swaps that turn a tetrahedron or a wedge inside out
_FLIP = {TETRA: [0, 2, 1, 3], WEDGE: [0, 2, 1, 3, 5, 4]}


def _oriented(cut: CutMesh, cells: np.ndarray, X: np.ndarray, vtk_type: int) -> np.ndarray:
    """The reference nodes ``X (n, k, 3)`` of tetrahedra or wedges with the nodes of those
    whose physical orientation is not VTK's swapped (VTK's volumes positive: the face or
    base 0 1 2 turns positively towards node 3)."""
    if cells.size == 0:
        return X
    a, b, c = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0], X[:, 3] - X[:, 0]
    volume = np.einsum("ij,ij->i", np.cross(a, b), c)
    det = np.linalg.det(cut.maps.jacobian(cells, X[:, 0]))
    wrong = volume * det < 0
    X = X.copy()
    X[wrong] = X[wrong][:, _FLIP[vtk_type]]
    return X


def _blocks(cut: CutMesh, pieces: Pieces, uncut: bool) -> list[_Block]:
    vertices, vtk_type = _VERTICES[cut.mesh.topology.cell_name()]
    blocks = []
    for side in (-1, 1):
        if uncut:
            cells = np.flatnonzero(cut.cell_sides == side).astype(np.int32)
            X = np.broadcast_to(vertices, (cells.size, *vertices.shape))
            blocks.append(_Block(side, 0, cells, X, vtk_type))
        for cells, X, kind in pieces.sides[side]:
            blocks.append(_Block(side, 1, cells, _oriented(cut, cells, X, kind), kind))
    return blocks


def interface_arrays_3d(cut: CutMesh, u_minus=None, levels: int = 1) -> GridArrays:
    """The interface triangles (:func:`cut_pieces`), cell data ``cell``, with point data
    ``u`` (m), the displacement ``u_minus`` of side -1, when given."""
    cells, X = cut_pieces(cut, levels).interface
    fields = {} if u_minus is None else {"u": {0: u_minus}}
    arrays = grid_arrays(cut, [_Block(0, 1, cells, X, TRIANGLE)], fields)
    return arrays._replace(cell_data={"cell": arrays.cell_data["cell"]})
