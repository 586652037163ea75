"""The outline of the region a 2D grid covers, found on its edges (numpy, no VTK filter).

A region's outline is the set of cell edges that only one cell of it owns, once
coincident nodes of neighbouring cells are merged (a sub-triangulated cut cell has
nodes of its own). Where a cut cell's sub-triangles divide an edge that its neighbour
keeps whole or divides elsewhere (hanging nodes), the pieces of both sides look like
outline edges too; they are dropped: edges that overlap along one curve. Edges are
curved (quadratic cells: ends and mid node) and sampled as polylines. Cost: a sort of
the edges, linear in the cells, where merging the points of a subdivided surface
(VTK's clean filter) took seconds for tens of thousands of cells.
"""

from __future__ import annotations

import numpy as np
import pyvista

#: VTK cell type: its edges as (end, end, mid node or -1), in the cell's local nodes
_EDGES = {
    5: ((0, 1, -1), (1, 2, -1), (2, 0, -1)),  # triangle
    9: ((0, 1, -1), (1, 2, -1), (2, 3, -1), (3, 0, -1)),  # quadrilateral
    22: ((0, 1, 3), (1, 2, 4), (2, 0, 5)),  # quadratic triangle
    23: ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7)),  # quadratic quadrilateral
    28: ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7)),  # biquadratic quadrilateral
}


def region_outline(grid: pyvista.DataSet, samples: int = 8) -> pyvista.PolyData:
    """Polylines along the outline of the region ``grid`` covers (2D cells of the
    types of :data:`_EDGES`), each edge in ``samples`` pieces. Not collective."""
    points = np.asarray(grid.points, dtype=np.float64)
    edges, counts = _distinct_edges(grid, points)
    outline = edges[counts == 1]
    outline = outline[~_overlapping(outline, points)]
    return _polylines(outline, points, samples)


def cell_outlines(grid: pyvista.DataSet, samples: int = 8) -> pyvista.PolyData:
    """Polylines along every cell edge of ``grid`` (an edge two cells share drawn
    once), each in ``samples`` pieces. Not collective."""
    points = np.asarray(grid.points, dtype=np.float64)
    return _polylines(_distinct_edges(grid, points)[0], points, samples)


def _distinct_edges(grid: pyvista.DataSet, points: np.ndarray):
    """The distinct cell edges (rows ``(end, end, mid or -1)``, coincident nodes
    merged) and the number of cells sharing each."""
    edges = _cell_edges(grid)
    if edges.shape[0] == 0:
        return edges, np.zeros(0, dtype=np.int64)
    ids = _merged_ids(points, 1e-9 * max(grid.length, 1e-300))
    ends = np.sort(ids[edges[:, :2]], axis=1)
    _, first, counts = np.unique(ends, axis=0, return_index=True, return_counts=True)
    return edges[first], counts


def _cell_edges(grid: pyvista.DataSet) -> np.ndarray:
    """Every cell's edges as rows ``(end, end, mid or -1)`` of point indices."""
    if grid.n_cells == 0:
        return np.zeros((0, 3), dtype=np.int64)
    types = np.asarray(grid.celltypes)
    unknown = set(np.unique(types).tolist()) - set(_EDGES)
    if unknown:
        raise ValueError(f"region_outline: VTK cell types {sorted(unknown)} not handled")
    offsets, connectivity = np.asarray(grid.cell_offsets), np.asarray(grid.cell_connectivity)
    rows = []
    for kind, local in _EDGES.items():
        cells = np.flatnonzero(types == kind)
        if cells.size == 0:
            continue
        local = np.array(local)
        nodes = connectivity[offsets[cells][:, None] + np.maximum(local, 0).ravel()]
        nodes = nodes.reshape(cells.size, len(local), 3)
        nodes[:, local[:, 2] < 0, 2] = -1
        rows.append(nodes.reshape(-1, 3))
    return np.concatenate(rows).astype(np.int64)


def _merged_ids(points: np.ndarray, tol: float) -> np.ndarray:
    """One id per distinct position (points closer than about ``tol`` share it)."""
    keys = np.rint(points[:, :2] / tol).astype(np.int64)
    return np.unique(keys, axis=0, return_inverse=True)[1].ravel()


def _curve(edges: np.ndarray, points: np.ndarray, t: np.ndarray):
    """Position and derivative in ``t`` of each edge's curve (ends ``a, b``, mid node
    ``m``, the chord's midpoint for a straight edge) at parameters ``t`` of shape
    ``(E, k)``: two arrays ``(E, k, 3)``."""
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    m = np.where((edges[:, 2] >= 0)[:, None], points[np.maximum(edges[:, 2], 0)], 0.5 * (a + b))
    a, b, m, t = a[:, None], b[:, None], m[:, None], t[..., None]
    x = (1 - t) * (1 - 2 * t) * a + t * (2 * t - 1) * b + 4 * t * (1 - t) * m
    dx = (4 * t - 3) * a + (4 * t - 1) * b + (4 - 8 * t) * m
    return x, dx


def _overlapping(outline: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Which outline edges overlap another one along the same curve (True to drop):
    a cut cell's sub-triangles divide an edge that its neighbour keeps whole or divides
    elsewhere, so both look like outline edges although the region lies on both sides.
    Two edges overlap when both ends of one lie on the other's curve (extended beyond
    its ends) and their parameter ranges share a piece of positive length."""
    a, b = points[outline[:, 0], :2], points[outline[:, 1], :2]
    middle = _curve(outline, points, np.full((outline.shape[0], 1), 0.5))[0][:, 0, :2]
    size = max(float(np.linalg.norm(b - a, axis=1).max()), 1e-300)
    bins: dict[tuple[int, int], list[int]] = {}
    cells = np.floor(middle / size).astype(np.int64)
    for k, (i, j) in enumerate(cells):
        bins.setdefault((int(i), int(j)), []).append(k)
    pairs = [
        (k, f)
        for k, (i, j) in enumerate(cells)
        for di in (-1, 0, 1)
        for dj in (-1, 0, 1)
        for f in bins.get((int(i) + di, int(j) + dj), ())
        if f != k
    ]
    drop = np.zeros(outline.shape[0], dtype=bool)
    if not pairs:
        return drop
    whole, other = np.array(pairs).T
    edges = outline[whole]
    t = np.stack([_parameter(edges, points, points[outline[other, i]]) for i in (0, 1)], axis=1)
    x = _curve(edges, points, t)[0]
    p = points[outline[other][:, :2]]
    scale = np.linalg.norm(b[whole] - a[whole], axis=1)
    on = np.all(np.linalg.norm(x - p, axis=2) <= 1e-6 * scale[:, None], axis=1)
    eps = 1e-6
    on &= (t.min(axis=1) < 1 - eps) & (t.max(axis=1) > eps)
    drop[whole[on]] = True
    drop[other[on]] = True
    return drop


def _parameter(edges: np.ndarray, points: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The parameter of the point of each edge's (extended) curve nearest to ``p``
    (shape ``(E, 3)``): Newton on ``|x(t) - p|^2`` from the chord's projection."""
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    chord = b - a
    t = ((p - a) * chord).sum(axis=1) / np.maximum((chord**2).sum(axis=1), 1e-300)
    for _ in range(5):
        x, dx = (v[:, 0] for v in _curve(edges, points, t[:, None]))
        t = t - ((x - p) * dx).sum(axis=1) / np.maximum((dx**2).sum(axis=1), 1e-300)
    return t


def _polylines(edges: np.ndarray, points: np.ndarray, samples: int) -> pyvista.PolyData:
    """Each edge's curve as a polyline of ``samples`` pieces."""
    if edges.shape[0] == 0:
        return pyvista.PolyData()
    t = np.broadcast_to(np.linspace(0.0, 1.0, samples + 1), (edges.shape[0], samples + 1))
    xyz = _curve(edges, points, t)[0].reshape(-1, 3)
    m = samples + 1
    lines = np.c_[np.full(edges.shape[0], m), np.arange(edges.shape[0] * m).reshape(-1, m)]
    return pyvista.PolyData(xyz, lines=lines.ravel())
