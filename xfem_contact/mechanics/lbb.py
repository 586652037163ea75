"""Reduction of the nodal contact-multiplier space for the inf-sup (LBB) condition.

Contact multipliers live on the vertices of cut cells (P1). That space is too
rich and oscillates. Following Moës, Béchet & Tourbier (2006) and Béchet, Moës
& Wohlmuth (2009), the space is restricted by equality / linear relations
built on *cut edges* (mesh edges whose two end vertices lie on opposite sides
of the interface, sides ``-1``/``+1`` per vertex):

* every cut edge gets exactly one *vital vertex*, one of its two ends
  (:func:`vital_vertices`): by a greedy covering (the vertex on most cut edges first),
  the end nearer the interface, or the covering after the ends of the crossings near
  them (the rule per cell type:
  :data:`xfem_contact.mechanics.lbb_space.VITAL_RULE`);
* every vital vertex carries one independent multiplier unknown; the
  multiplier at the intersection point of a cut edge is that of its vital
  vertex;
* in nodal form, the multiplier at each vertex of a cut edge is a linear
  combination of the vital unknowns, ``lambda_nodal = P @ lambda_reduced``
  (:func:`prolongation`): a vital vertex takes its own unknown, a non-vital
  vertex the average of the vital vertices of its cut edges (an equality when
  it lies on a single cut edge). Constants are reproduced (row sums of ``P``
  are 1).

Everything here is pure numpy and works on *global* vertex ids: every MPI rank
that gathers the same global set of cut edges computes the same vital vertices
and the same ``P``, whatever the order of the edges or of their two ends.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["prolongation", "restriction_stats", "vital_vertices"]


def _canonical_edges(
    edges: npt.ArrayLike,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Unique undirected edges ``(k, 2)`` (smaller id first, rows sorted) and, for
    each input row, its row in that array ``(m,)``."""
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if np.any(edges[:, 0] == edges[:, 1]):
        raise ValueError("a cut edge has twice the same vertex")
    canon = np.sort(edges, axis=1)
    if canon.shape[0] == 0:
        return canon, np.zeros(0, dtype=np.int64)
    unique, inverse = np.unique(canon, axis=0, return_inverse=True)
    return unique, inverse.reshape(-1).astype(np.int64)


def _check_sides(edges: npt.NDArray[np.int64], sides: npt.ArrayLike) -> None:
    """Raise unless each edge joins opposite sides and each vertex has one side."""
    sides = np.asarray(sides).reshape(-1, 2)
    if sides.shape != edges.shape:
        raise ValueError(f"sides has shape {sides.shape}, edges {edges.shape}")
    if not np.all(np.isin(sides, (-1, 1))):
        raise ValueError("sides must be -1 or +1")
    if np.any(sides[:, 0] == sides[:, 1]):
        raise ValueError("an edge given as cut has both ends on the same side")
    pairs = np.unique(np.stack([edges.ravel(), sides.ravel().astype(np.int64)], axis=1), axis=0)
    if np.any(pairs[1:, 0] == pairs[:-1, 0]):
        raise ValueError("a vertex is given on both sides by different edges")


def vital_vertices(
    edges: npt.ArrayLike,
    sides: npt.ArrayLike,
    distances: npt.ArrayLike | None = None,
    near_share: float | None = None,
) -> npt.NDArray[np.int64]:
    """The vital vertex of each cut edge: by deterministic greedy covering, (given
    ``distances``) the end nearer the interface, or (given both ``distances`` and
    ``near_share``) the covering after the near crossings' ends.

    Greedy covering (``distances`` None): duplicate edges (in either orientation) are
    merged. Each vertex gets a count, the number of its cut edges not yet assigned.
    Repeatedly, the vertex with the largest count (ties: smallest global vertex id)
    is made vital and all its not-yet-assigned cut edges are assigned to it; the
    counts of the other ends of those edges drop accordingly. The loop stops when
    every cut edge is assigned. Only the set of (undirected) edges matters, so the
    result does not depend on the order of the rows nor of the two ends within a
    row: all MPI ranks holding the same gathered global edge set agree.

    Properties: each cut edge's vital vertex is one of its ends; a vital
    vertex is vital for at least one edge; a non-vital vertex has all of its
    cut edges assigned to their other end (a vital vertex). An edge may have
    both ends vital (its first-picked end is its vital vertex), and then the
    second-picked end is vital for other edges.

    This is the greedy selection only (in the spirit of Moës et al. 2006). The
    additional rules of Béchet, Moës & Wohlmuth (2009) (their modified
    algorithm and its stability proof for P1-P1 on triangles) are *not*
    applied here.

    Nearer end (``distances`` given): each cut edge's vital vertex is its end of the
    smaller distance to the interface (ties: the smaller global id), the end whose
    shape function is at least 1/2 at the edge's crossing. Every vertex that is the
    nearer end of one of its cut edges is vital; an edge may have both ends vital
    (its farther end being nearer on another edge).

    Near crossings first (``near_share``): an edge whose crossing lies within
    ``near_share`` of its length from one end (``min(d) / (d_0 + d_1) < near_share``)
    makes that end vital, and every cut edge of such a vertex is assigned to it (to
    its nearer end when both ends are such vertices); the greedy covering then assigns
    the other edges. A vertex that (nearly) lies on the interface is thus never the
    mean of farther vertices, whose shape functions hardly reach the crossing.

    Args:
        edges: ``(m, 2)`` global vertex ids of the two ends of each cut edge.
        sides: ``(m, 2)`` side (``-1`` or ``+1``) of those ends; checked for
            consistency (opposite sides on each edge, one side per vertex).
        distances: ``(m, 2)`` distance (or absolute level set, any unit) of those ends
            to the interface; the same value for a vertex in every row.
        near_share: with ``distances``, the share of an edge's length (0 .. 1/2) within
            which its crossing makes its nearer end vital before the covering.

    Returns:
        ``(m,)`` int64: the global id of the vital vertex of each input edge.
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    _check_sides(edges, sides)
    if near_share is not None and not 0.0 <= near_share <= 0.5:
        raise ValueError(f"near_share must be in [0, 1/2], got {near_share}")
    if distances is not None and near_share is None:
        return _nearer_ends(edges, distances)
    canon, inverse = _canonical_edges(edges)
    k = canon.shape[0]
    if k == 0:
        return np.zeros(0, dtype=np.int64)

    # Local vertex numbers follow the sorted global ids, so argmax's "first
    # maximum" is the smallest global id among ties.
    verts, local = np.unique(canon, return_inverse=True)
    local = local.reshape(k, 2)
    nv = verts.shape[0]
    # CSR incidence vertex -> edges.
    ends = local.ravel()
    order = np.argsort(ends, kind="stable")
    inc_edges = (order // 2).astype(np.int64)
    offsets = np.zeros(nv + 1, dtype=np.int64)
    np.cumsum(np.bincount(ends, minlength=nv), out=offsets[1:])

    owner = np.full(k, -1, dtype=np.int64)  # local id of the vital vertex
    if near_share is not None:
        owner = _near_crossings(edges, distances, near_share, verts, local, inverse)
    count = np.bincount(local[owner < 0].ravel(), minlength=nv).astype(np.int64)
    remaining = int(np.count_nonzero(owner < 0))
    while remaining > 0:
        v = int(np.argmax(count))
        incident = inc_edges[offsets[v] : offsets[v + 1]]
        new = incident[owner[incident] < 0]
        owner[new] = v
        remaining -= new.size
        others = local[new, 0] + local[new, 1] - v
        np.subtract.at(count, others, 1)
        count[v] = 0
    return verts[owner][inverse]


def _near_crossings(edges, distances, near_share, verts, local, inverse) -> np.ndarray:
    """``(k,)`` local vital vertex of each unique edge (``local``, ``(k, 2)``, of the
    sorted vertex ids ``verts``; ``inverse`` the unique edge of each input row) assigned
    by the near crossings' ends of :func:`vital_vertices`, -1 for the others."""
    distances = np.asarray(distances, dtype=np.float64).reshape(-1, 2)
    if distances.shape != edges.shape:
        raise ValueError(f"distances has shape {distances.shape}, edges {edges.shape}")
    share = distances.min(axis=1) / distances.sum(axis=1)
    near = _nearer_ends(edges, distances)
    forced = np.isin(verts, near[share < near_share])
    # each unique edge's nearer end (local id), from its first input row
    first = np.zeros(local.shape[0], dtype=np.int64)
    first[inverse[::-1]] = np.arange(inverse.size)[::-1]
    nearer = np.searchsorted(verts, near[first])
    a, b = forced[local[:, 0]], forced[local[:, 1]]
    return np.where(a & b, nearer, np.where(a, local[:, 0], np.where(b, local[:, 1], -1)))


def _nearer_ends(edges: npt.NDArray[np.int64], distances: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """The end of each edge ``(m, 2)`` of the smaller distance ``(m, 2)`` (ties: the
    smaller id)."""
    distances = np.asarray(distances, dtype=np.float64).reshape(-1, 2)
    if distances.shape != edges.shape:
        raise ValueError(f"distances has shape {distances.shape}, edges {edges.shape}")
    first = (distances[:, 0] < distances[:, 1]) | (
        (distances[:, 0] == distances[:, 1]) & (edges[:, 0] < edges[:, 1])
    )
    return np.where(first, edges[:, 0], edges[:, 1])


def prolongation(
    edges: npt.ArrayLike, vital: npt.ArrayLike
) -> tuple[
    npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.int64]
]:
    """Sparse prolongation ``P`` from vital unknowns to nodal multipliers.

    ``lambda[v] = sum_j P[v, j] * lambda_reduced[j]`` for each vertex ``v`` of a
    cut edge, with:

    * ``v`` vital: ``P[v, col(v)] = 1``;
    * ``v`` not vital, on ``d`` cut edges: their vital vertices are their other
      ends ``u_1..u_d`` and ``P[v, col(u_i)] = 1 / d`` (equal-weight average;
      ``d = 1`` is the equality ``lambda_v = lambda_u``).

    Each row sums to 1 (constants are reproduced). Vertices of cut cells that
    lie on no cut edge have no row: the caller drops (or zeroes) them.

    Args:
        edges: ``(m, 2)`` global vertex ids of the cut edges (as given to
            :func:`vital_vertices`; duplicates are merged).
        vital: ``(m,)`` vital vertex of each edge, one of its ends.

    Returns:
        ``rows`` ``(nnz,)`` int64 global vertex ids; ``cols`` ``(nnz,)`` int64
        positions in ``reduced_ids``; ``vals`` ``(nnz,)`` float64;
        ``reduced_ids`` ``(r,)`` int64, the sorted unique vital vertex ids
        (column ``j`` is the unknown of vertex ``reduced_ids[j]``). Triplets are
        sorted by row, then column, with no duplicates.
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    vital = np.asarray(vital, dtype=np.int64).reshape(-1)
    if vital.shape[0] != edges.shape[0]:
        raise ValueError(f"{vital.shape[0]} vital vertices for {edges.shape[0]} edges")
    if np.any((vital != edges[:, 0]) & (vital != edges[:, 1])):
        raise ValueError("a vital vertex is not an end of its edge")
    # Merge duplicate edges; they must agree on their vital vertex.
    canon, inverse = _canonical_edges(edges)
    vital_c = np.full(canon.shape[0], -1, dtype=np.int64)
    vital_c[inverse] = vital
    if np.any(vital_c[inverse] != vital):
        raise ValueError("duplicate edges with different vital vertices")

    reduced_ids = np.unique(vital_c)
    other = canon[:, 0] + canon[:, 1] - vital_c
    dependent = ~np.isin(other, reduced_ids)  # edges whose other end is not vital

    # Non-vital vertex w: one entry per cut edge (all of them have w as their
    # non-vital end, as w is vital for none), weight 1 / (number of such edges).
    w = other[dependent]
    u = vital_c[dependent]
    w_ids, w_inv, w_deg = np.unique(w, return_inverse=True, return_counts=True)
    rows = np.concatenate([reduced_ids, w])
    cols = np.concatenate(
        [np.arange(reduced_ids.size, dtype=np.int64), np.searchsorted(reduced_ids, u)]
    )
    vals = np.concatenate([np.ones(reduced_ids.size), 1.0 / w_deg[w_inv.reshape(-1)]])
    order = np.lexsort((cols, rows))
    return rows[order], cols[order].astype(np.int64), vals[order], reduced_ids


def restriction_stats(edges: npt.ArrayLike, vital: npt.ArrayLike) -> dict[str, int | float]:
    """Counts describing the reduced multiplier space, for reporting.

    Args:
        edges: ``(m, 2)`` global vertex ids of the cut edges (duplicates merged).
        vital: ``(m,)`` vital vertex of each edge.

    Returns:
        ``n_cut_edges`` (distinct cut edges), ``n_edge_vertices`` (distinct
        vertices on cut edges = nodal multipliers kept), ``n_vital`` (reduced
        unknowns), ``n_equality`` (non-vital vertices on one cut edge),
        ``n_average`` (non-vital vertices averaging several vital vertices),
        ``n_both_vital_edges`` (cut edges whose two ends are vital),
        ``max_edges_per_vital`` and ``reduction`` (``n_vital /
        n_edge_vertices``, 0 when empty).
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    vital = np.asarray(vital, dtype=np.int64).reshape(-1)
    canon, inverse = _canonical_edges(edges)
    vital_c = np.full(canon.shape[0], -1, dtype=np.int64)
    vital_c[inverse] = vital
    verts = np.unique(canon)
    reduced = np.unique(vital_c)
    other = canon[:, 0] + canon[:, 1] - vital_c
    both = np.isin(other, reduced)
    _, deg = np.unique(other[~both], return_counts=True)
    _, per_vital = np.unique(vital_c, return_counts=True)
    return {
        "n_cut_edges": int(canon.shape[0]),
        "n_edge_vertices": int(verts.size),
        "n_vital": int(reduced.size),
        "n_equality": int(np.count_nonzero(deg == 1)),
        "n_average": int(np.count_nonzero(deg > 1)),
        "n_both_vital_edges": int(np.count_nonzero(both)),
        "max_edges_per_vital": int(per_vital.max(initial=0)),
        "reduction": float(reduced.size / verts.size) if verts.size else 0.0,
    }
