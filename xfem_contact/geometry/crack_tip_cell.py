"""The cell holding a crack tip, cut along the crack up to the tip into fans of curved triangles.

Pure numpy and Basix, no DOLFINx; reference coordinates of each parent cell, the
conventions of :class:`xfem_contact.geometry.cut.CutGeometry`. The zero line of
``phi`` crosses a tip cell (:data:`xfem_contact.geometry.crack.TIP`) from the crack's
*entry* point, where ``psi < 0``, through the tip to its *exit* point on the
crack's extension (``psi > 0``). Both pieces, entry -> tip (the crack) and tip ->
exit (the extension, no discontinuity), are SEG3 with the tip as an end: straight
for degree 1, with the mid-node on the zero line of the ``phi`` interpolant
(bisector search of :mod:`xfem_contact.geometry.cut_simple`) for degree 2. Each side
polygon of the cell is fanned around the tip: every sub-triangle has the tip as
vertex 0, so the singular functions of the tip need one collapsed vertex per
sub-triangle only (see :mod:`xfem_contact.quadrature.tip_rules`). An edge of a fan
triangle along the crack or its extension carries that piece's mid-node; the
others are straight. Zero-area triangles (the crack through a vertex, a tip on the
cell's boundary: on a node, on an edge, at the end of the ``phi`` cut) are dropped;
a fan that folds (a crack too curved for its cell) is refused.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_simple import _midnodes, cut_simple, interpolant
from xfem_contact.geometry.cut_subcells import _jacobian_bernstein
from xfem_contact.geometry.cut_topology import (
    cell_data,
    check_values,
    describe_cells,
    side_polygon,
    topology,
)

__all__ = ["TipCut", "cut_tip_cells"]

_EPS = np.finfo(np.float64).eps


@dataclass(frozen=True)
class TipCut:
    """Fan sub-triangulation of tip cells (reference coordinates of each parent).

    Attributes:
        tip: Tip of each cell, shape ``(ntip, 2)``.
        tri_minus: P2 sub-triangles of side -1 (``phi < 0``), shape ``(nt_m, 6, 2)``:
            vertex 0 is the tip, then vertices 1, 2 and the mid-nodes of edges
            (1, 2), (0, 2), (0, 1) (Basix order), counter-clockwise.
        tri_minus_cell: Tip-cell row of each, shape ``(nt_m,)``, sorted.
        tri_plus: P2 sub-triangles of side +1, shape ``(nt_p, 6, 2)``, the same layout.
        tri_plus_cell: Their rows, shape ``(nt_p,)``, sorted.
        crack: SEG3 crack piece (entry -> tip or tip -> entry) of each cell, shape
            ``(ntip, 3, 2)``: end ``a``, end ``b``, mid-node; side -1 on the left of ``a -> b``.
        crack_tip_end: Which end of ``crack`` is the tip (0: ``a``, 1: ``b``), ``(ntip,)``.
        extension: SEG3 of the crack's extension (``phi = 0``, ``psi > 0``) in the
            cell, shape ``(ntip, 3, 2)``, oriented as ``crack``.
        num_cells: Number of tip cells.
    """

    tip: npt.NDArray[np.float64]
    tri_minus: npt.NDArray[np.float64]
    tri_minus_cell: npt.NDArray[np.int64]
    tri_plus: npt.NDArray[np.float64]
    tri_plus_cell: npt.NDArray[np.int64]
    crack: npt.NDArray[np.float64]
    crack_tip_end: npt.NDArray[np.int64]
    extension: npt.NDArray[np.float64]
    num_cells: int


def cut_tip_cells(
    cell_type: str,
    degree: int,
    phi: npt.ArrayLike,
    psi: npt.ArrayLike,
    tip: npt.ArrayLike,
    xtol: float = 1e-14,
) -> TipCut:
    """Cut tip cells along the crack up to the tip, both sides fanned around the tip.

    Args:
        cell_type: ``"triangle"`` or ``"quadrilateral"``.
        degree: Level-set degree, 1 or 2.
        phi: Normal level set of the tip cells only, nodal values ``(ntip, ndofs)``.
        psi: Tangential level set, ``(ntip, ndofs)``.
        tip: Reference tip positions ``(ntip, 2)``, e.g.
            :attr:`xfem_contact.geometry.crack.CrackCells.tip`.
        xtol: Root tolerance for the mid-nodes (reference coordinates).

    Returns:
        The :class:`TipCut`.

    Raises:
        ValueError: Bad shapes, cells that ``phi`` does not cut simply or whose
            crack entry is not on side ``psi < 0``, and fans that fold.
    """
    data = cell_data(cell_type, degree)
    phi, psi = check_values(data, phi), check_values(data, psi)
    tip = np.asarray(tip, dtype=np.float64)
    n = phi.shape[0]
    if psi.shape != phi.shape or tip.shape != (n, 2):
        raise ValueError(
            f"psi must have shape {phi.shape} and tip ({n}, 2), got {psi.shape} and {tip.shape}"
        )
    neg, flags = topology(data, phi)
    bad = np.flatnonzero((flags != 0) | neg.all(axis=1) | ~neg.any(axis=1))
    if bad.size:
        raise ValueError(
            f"cut_tip_cells takes cells that phi cuts simply, but not {describe_cells(bad)}; "
            "pass the tip cells of classify_crack"
        )
    seg = cut_simple(data, phi, neg, None, xtol)[4]
    c_mp, c_pm = seg[:, 0], seg[:, 1]
    psi_mp = interpolant(data, psi, c_mp)[0]
    psi_pm = interpolant(data, psi, c_pm)[0]
    entry_mp = psi_mp < psi_pm  # the other end is the exit, or the tip itself
    wrong = np.flatnonzero(np.minimum(psi_mp, psi_pm) >= 0)
    if wrong.size:
        raise ValueError(
            f"psi is not negative at either end of phi = 0 in {describe_cells(wrong)}: "
            "not tip cells (see classify_crack)"
        )
    m_mp = _midnodes(data, phi, c_mp, tip, None, xtol)  # piece c_mp -> tip
    m_pm = _midnodes(data, phi, tip, c_pm, None, xtol)  # piece tip -> c_pm
    first = np.stack([c_mp, tip, m_mp], axis=1)
    second = np.stack([tip, c_pm, m_pm], axis=1)
    e = entry_mp[:, None, None]
    crack, extension = np.where(e, first, second), np.where(e, second, first)
    tip_end = np.where(entry_mp, 1, 0).astype(np.int64)
    nv = data.nv
    table = np.concatenate(
        [np.broadcast_to(data.loop_coords, (n, nv, 2)), c_pm[:, None], c_mp[:, None]], axis=1
    )
    mids = {nv: m_pm, nv + 1: m_mp}  # curved tip edges, by the table index of their end
    codes = (neg * (1 << np.arange(nv))).sum(axis=1)
    sides = [_fans(table, tip, mids, codes, side) for side in (-1, 1)]
    return TipCut(tip, *sides[0], *sides[1], crack, tip_end, extension, n)


def _fans(
    table: np.ndarray, tip: np.ndarray, mids: dict, codes: np.ndarray, side: int
) -> tuple[np.ndarray, np.ndarray]:
    """Fan triangles ``(m, 6, 2)`` around the tip of one side, and their rows ``(m,)``;
    straight interior edges, or bent where a straight fan folds (:func:`_fan_nodes`)."""
    tri, cell, folded = _fan_nodes(table, tip, mids, codes, side, 0.0)
    retry = np.isin(cell, cell[folded])
    if retry.any():
        bent, bent_cell, still = _fan_nodes(table, tip, mids, codes, side, 1.0)
        again = np.isin(bent_cell, cell[folded])
        if still[again].any():
            bad = describe_cells(np.unique(bent_cell[still & again]))
            raise ValueError(
                f"the fan around the crack tip folds in {bad} (a crack too curved for its "
                "cell); refine the mesh near the tip"
            )
        tri = np.concatenate([tri[~retry], bent[again]])
        cell = np.concatenate([cell[~retry], bent_cell[again]])
    order = np.argsort(cell, kind="stable")
    return tri[order], cell[order]


def _fan_nodes(
    table: np.ndarray, tip: np.ndarray, mids: dict, codes: np.ndarray, side: int, bend: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fan triangles ``(m, 6, 2)``, their rows ``(m,)`` and which fold ``(m,)``.

    The tip edges along the crack and its extension carry their pieces' mid-nodes;
    the tip edge next to each is bent by ``bend`` times that piece's bulge (the
    mid-node's offset from its chord), which unfolds thin triangles beside a curved
    piece; the other edges are straight.
    """
    nv = table.shape[1] - 2
    tris, cells = [np.zeros((0, 6, 2))], [np.zeros(0, dtype=np.int64)]
    for code in np.unique(codes):
        rows = np.flatnonzero(codes == code)
        polygon = side_polygon(int(code), nv, side)
        T, last = tip[rows], len(polygon) - 1
        bulge = {q: mids[q][rows] - 0.5 * (T + table[rows, q]) for q in (polygon[0], polygon[-1])}
        edge_mids = []
        for j, q in enumerate(polygon):
            mid = mids[q][rows] if j in (0, last) else 0.5 * (T + table[rows, q])
            if j == 1:
                mid = mid + bend * bulge[polygon[0]]
            if j == last - 1:
                mid = mid + bend * bulge[polygon[-1]]
            edge_mids.append(mid)
        for j in range(last):
            P, Q = table[rows, polygon[j]], table[rows, polygon[j + 1]]
            nodes = np.stack([T, P, Q, 0.5 * (P + Q), edge_mids[j + 1], edge_mids[j]], axis=1)
            scale = np.abs(nodes).max(axis=(1, 2))
            flat = np.abs(nodes[:, [1, 4]] - nodes[:, [2, 5]]).max(axis=(1, 2))
            keep = flat > 4 * _EPS * scale  # zero area: P == Q and the same tip edges
            # ... or a tip on the cell's boundary: on P or Q, or on the straight edge P Q
            area = np.abs(_jacobian_bernstein(nodes)).max(axis=1)
            keep &= area > 64 * _EPS * scale**2
            tris.append(nodes[keep])
            cells.append(rows[keep])
    tri, cell = np.concatenate(tris), np.concatenate(cells)
    bern = _jacobian_bernstein(tri)
    area = np.abs(bern).max(axis=1)
    return tri, cell, (bern < -64 * _EPS * area[:, None]).any(axis=1)
