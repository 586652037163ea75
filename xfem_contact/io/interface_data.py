"""The interface laws' state at the nodes of ``interface.vtu`` (point data per lip node).

The nodes are those of :func:`~xfem_contact.io.vtu.interface_arrays` (three per curved
piece: end ``a``, end ``b``, mid-node) in 2D, of
:func:`~xfem_contact.io.solid_grids.interface_arrays_3d` (three per triangle) in 3D. For a
law acting on one cell (small sliding) its ``state`` is evaluated at these nodes with
the same definitions and normal as at its rule points; a law that pairs two cells (large
sliding) is sampled at the nearest of its own points in the same cut cell. Point data
(each ``(npoints,)``): ``lambda_n``, ``lambda_t`` (multipliers, Pa), ``gap``, ``slip``
(m) and ``status`` (0 open, 1 stick, 2 slip; frictionless contact is slip, a bonded
interface stick, a free one open); in 3D ``lambda_t`` and ``slip`` are Cartesian vectors
``(npoints, 3)``. Local to each process.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from xfem_contact.quadrature.rules import RuleSet

#: Point data of ``interface.vtu`` (its ``status`` holds the codes of
#: :meth:`~xfem_contact.mechanics.laws.base.InterfaceLaw.point_status`)
KEYS = ("lambda_n", "lambda_t", "gap", "slip")


def _interface_pieces(cut) -> tuple[np.ndarray, np.ndarray]:
    """The pieces of ``interface.vtu``: their rows of ``cut.cut_cells`` ``(P,)`` (sorted)
    and reference nodes ``(P, 3, tdim)``."""
    if cut.geometry is not None:
        return cut.geometry.seg_cell, cut.geometry.seg
    from xfem_contact.io.solid_grids import cut_pieces

    cells, X = cut_pieces(cut).interface
    return np.searchsorted(cut.cut_cells, cells), X


def _node_rules(cut, rows: np.ndarray, nodes: np.ndarray) -> RuleSet:
    """Rules (rows ``cut.cut_cells``) whose points are the ``nodes`` ``(P, 3, tdim)`` of
    pieces in the cut cells ``rows`` ``(P,)`` (sorted)."""
    counts = np.bincount(rows, minlength=cut.cut_cells.size) * 3
    offsets = np.zeros(cut.cut_cells.size + 1, dtype=np.int64)
    np.cumsum(counts, out=offsets[1:])
    points = np.ascontiguousarray(nodes.reshape(-1, nodes.shape[-1]))
    return RuleSet(points, np.zeros(points.shape[0]), offsets)


def _nearest(cut, rules: RuleSet, state: dict, pieces: np.ndarray) -> dict:
    """``state`` (at the points of ``rules``) at the nodes of ``pieces``: the value of
    the nearest point of the same cut cell (0 where the cell has none)."""
    g = cut.geometry
    nodes = g.seg[pieces].reshape(-1, 2)
    node_rows = np.repeat(g.seg_cell[pieces], 3)
    out = {k: np.zeros(nodes.shape[0]) for k, v in state.items() if np.ndim(v) == 1}
    if rules.points.shape[0] == 0:
        return out
    rows = rules.point_rows
    for row in np.unique(node_rows):
        mine, theirs = np.flatnonzero(node_rows == row), np.flatnonzero(rows == row)
        if theirs.size == 0:
            continue
        d = np.linalg.norm(nodes[mine, None, :] - rules.points[None, theirs, :], axis=2)
        pick = theirs[np.argmin(d, axis=1)]
        for k in out:
            out[k][mine] = np.asarray(state[k])[pick]
    return out


def interface_point_data(problem) -> dict[str, np.ndarray]:
    """``lambda_n``, ``lambda_t``, ``gap``, ``slip`` and ``status`` at this process's
    ``interface.vtu`` nodes (all interfaces, in the order of
    :func:`~xfem_contact.io.vtu.interface_arrays`). Collective (large-sliding laws
    pair their points across processes)."""
    cut = problem.cut
    piece_rows, piece_nodes = _interface_pieces(cut)
    npoints = 3 * piece_rows.size
    data = {k: np.zeros(npoints) for k in KEYS} | {"status": np.zeros(npoints, dtype=np.int8)}
    interface_of_piece = cut.cell_interface[piece_rows] if piece_rows.size else piece_rows
    couplings = getattr(problem, "couplings", {}) or {}
    for name, law in problem.laws.items():
        ctx = problem.contexts[name]
        k = list(cut.interface_names).index(name) if len(problem.laws) > 1 else None
        pieces = (
            np.flatnonzero(interface_of_piece == k) if k is not None else np.arange(piece_rows.size)
        )
        if name in couplings:
            state = _nearest(cut, ctx.rules, law.state(ctx, problem.w), pieces)
        else:
            rules = _node_rules(cut, piece_rows[pieces], piece_nodes[pieces])
            nodes = dataclasses.replace(ctx, rules=rules, _cache={})
            state = law.state(nodes, problem.w)
        rows = (3 * pieces[:, None] + np.arange(3)).ravel()
        for key in KEYS:
            if key in state:
                values = np.asarray(state[key])
                if data[key].shape != (npoints, *values.shape[1:]):  # vectors in 3D
                    data[key] = np.zeros((npoints, *values.shape[1:]))
                data[key][rows] = values
        data["status"][rows] = law.point_status(state, rows.size)
    return data


def sample_status(problem, name: str) -> list[int]:
    """The status codes (0 open, 1 stick, 2 slip) at the rule points of interface
    ``name`` of all processes, in the order of
    ``problem.interface_samples(problem.w, name)``.
    Collective."""
    law = problem.laws[name]
    state = problem.interface_state(problem.w, name)
    npoints = problem.contexts[name].rules.points.shape[0]
    local = law.point_status(state, npoints)
    return np.concatenate(problem.mesh.comm.allgather(local)).tolist()
