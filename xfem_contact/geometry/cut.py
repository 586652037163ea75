"""Cut cells by the zero line of a level set: classification and curved
sub-triangulation in reference coordinates (pure numpy and Basix, no DOLFINx).

Each cell's level set is the Lagrange interpolant (degree 1 or 2, Basix
``gll_warped`` node order) of its nodal values ``phi``, shape ``(ncells, ndofs)``.
All coordinates are the parent cell's (dimensionless) reference coordinates.

Tolerance policy: ``phi < 0`` is side -1 and ``phi >= 0`` is side +1, by exact
floating-point comparison (an exact zero counts as +1); the interface normal
points from side -1 to side +1. Exact zeros at vertices and near-tangent edges
follow the rules of :mod:`xfem_contact.geometry.cut_topology` (a zero vertex is on side
-1 for its cell's topology when the interface leaves it along an edge; dips of
an edge polynomial within ``64 eps max|phi|`` of zero are tangency). Roots are
placed to ``xtol`` (reference coordinates), a crossing within ``xtol`` of a vertex
on the vertex; interface mid-nodes within 8 ulp
(relative to the chord) of the chord midpoint are snapped onto it.

A *simple* cut crosses the cell boundary exactly twice and is represented by
one SEG3 (:mod:`xfem_contact.geometry.cut_simple`). Cells whose interpolant crosses an
edge twice, crosses the boundary more than twice or changes sign inside only
are subdivided, and cells that vanish along two edges carry those edges as
interface pieces (:mod:`xfem_contact.geometry.cut_subdivision`, with the full
degeneracy policy); after ``max_depth`` levels (default :data:`MAX_DEPTH`)
:func:`subtriangulate` raises ``ValueError`` naming the cells and the reason.

This module is the driver. Data flows one way through its helpers:
:mod:`~xfem_contact.geometry.cut_topology` (reference cells, sign topology) ->
:mod:`~xfem_contact.geometry.cut_children` (subdividing cells) and
:mod:`~xfem_contact.geometry.cut_subcells` (side sub-triangles) ->
:mod:`~xfem_contact.geometry.cut_simple` (simply cut cells) ->
:mod:`~xfem_contact.geometry.cut_subdivision` (everything else) -> here.

All work is vectorised over cells; Python loops run over subdivision levels,
sign patterns, the few candidate triangulations and solver iterations only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_simple import ExactLevelSet, cut_simple
from xfem_contact.geometry.cut_subdivision import (
    Pieces,
    compose,
    corner_pieces,
    needs_subdivision,
    subdivide,
)
from xfem_contact.geometry.cut_topology import (
    CORNER,
    cell_data,
    check_values,
    describe_cells,
    topology,
)

__all__ = ["CutGeometry", "ExactLevelSet", "classify", "subtriangulate"]

MAX_DEPTH = 5
"""Default number of subdivision levels of :func:`subtriangulate`."""


@dataclass(frozen=True)
class CutGeometry:
    """Curved sub-triangulation of cut cells (reference coordinates of each parent).

    Attributes:
        tri_minus: P2 sub-triangles of side -1, shape ``(nt_m, 6, 2)``: vertices
            then mid-nodes of edges (1, 2), (0, 2), (0, 1) (Basix order),
            counter-clockwise. Only the interface edge is curved, except in the
            rare blended fallback for thin sides (:mod:`xfem_contact.geometry.cut_subcells`).
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

    Cells that :func:`subtriangulate` subdivides (see
    :mod:`xfem_contact.geometry.cut_subdivision`) count as cut, including a closed
    interface piece inside an otherwise uncut cell.

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
    """Subtriangulate cut cells: curved P2 sub-triangles on each side and SEG3 interface pieces.

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
    is used instead, see :mod:`xfem_contact.geometry.cut_subcells`. Cells that are not
    simply cut are subdivided first (:mod:`xfem_contact.geometry.cut_subdivision`).

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
        *tris, seg = cut_simple(data, phi, neg, exact, xtol)
        return CutGeometry(*tris, seg, np.arange(n), n, subdivided)
    simple = np.flatnonzero(kind == 0)
    tri_m, cell_m, tri_p, cell_p, seg = cut_simple(
        data, phi[simple], neg[simple], compose(exact, simple), xtol
    )
    corner = np.flatnonzero(kind == CORNER)
    recursive = np.flatnonzero(needs_subdivision(kind))
    reference = np.broadcast_to(data.vertices, (corner.size, data.nv, 2))
    pieces = [
        (tri_m, simple[cell_m], tri_p, simple[cell_p], seg, simple),
        corner_pieces(data, phi[corner], reference, corner),
        *subdivide(data, phi, recursive, neg[recursive], kind[recursive], exact, xtol, max_depth),
    ]
    return _collect(pieces, n, subdivided)


def _collect(pieces: list[Pieces], n: int, subdivided: np.ndarray) -> CutGeometry:
    """Concatenate pieces and sort every array by cell (stable)."""
    fields = [np.concatenate([p[k] for p in pieces]) for k in range(6)]
    for values, cells in ((0, 1), (2, 3), (4, 5)):
        order = np.argsort(fields[cells], kind="stable")
        fields[values], fields[cells] = fields[values][order], fields[cells][order]
    return CutGeometry(*fields, n, subdivided)
