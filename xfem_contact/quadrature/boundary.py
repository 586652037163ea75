"""Pieces of boundary facets on one side of the interface.

Exterior facets of uncut cells are integrated with FFCx's standard facet rule;
the pieces of facets of cut cells lying on one side are straight segments of
the cell's reference edges, read off the sub-triangulation, and integrated with
runtime cell rules (points on the edge, weights ``ds / |det J|``), one rule set
per local facet index so that the facet normal is known to each kernel.

Each piece carries the orientation of its sub-triangle: +1 where the triangle runs
along the facet counter-clockwise around the cell (every piece of a valid
sub-triangulation), -1 the other way, which only a folded fallback fan of
:mod:`xfem_contact.geometry.cut_subcells` produces. Weighted by it, the pieces are the
oriented boundary of the side's sub-triangles: overlapping pieces of a fold cancel, so
every point of a facet is counted once, as the side rules with the signed ``det J``
count every point of the side once.
"""

from __future__ import annotations

from collections.abc import Callable

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut import CutGeometry
from xfem_contact.quadrature.rules import RuleSet

_ON_EDGE_TOL = 1e-12


def reference_facets(cell: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(nfacets, 2, tdim)`` and outward unit normals ``(nfacets, tdim)``
    of the reference cell's facets, in DOLFINx's local facet order."""
    cell_type = basix.CellType[cell]
    vertices = basix.geometry(cell_type)
    facets = np.array(basix.topology(cell_type)[1])
    return vertices[facets], basix.cell.facet_outward_normals(cell_type)


def facet_pieces(
    geometry: CutGeometry, side: int, cell: str
) -> tuple[
    npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.float64], npt.NDArray[np.float64]
]:
    """Segments of the reference cell's edges bounding the side-``side`` sub-triangles.

    Returns:
        ``rows`` (m,): cut-cell row of each piece; ``facets`` (m,): local facet
        index; ``ends`` (m, 2, tdim): the piece's end points (reference coords);
        ``signs`` (m,): its orientation, +1 or -1 (see the module docstring).
    """
    tri = geometry.tri_minus if side == -1 else geometry.tri_plus
    owner = geometry.tri_minus_cell if side == -1 else geometry.tri_plus_cell
    fverts, normals = reference_facets(cell)
    rows, facets, ends, signs = [], [], [], []
    for i, j, mid in ((0, 1, 5), (1, 2, 3), (2, 0, 4)):
        p, q, m = tri[:, i], tri[:, j], tri[:, mid]
        for f, (a, b) in enumerate(fverts):
            t = b - a
            nrm = np.array([-t[1], t[0]]) / np.linalg.norm(t)
            on = (
                (np.abs((p - a) @ nrm) < _ON_EDGE_TOL)
                & (np.abs((q - a) @ nrm) < _ON_EDGE_TOL)
                & (np.abs((m - a) @ nrm) < _ON_EDGE_TOL)
                & (np.linalg.norm(q - p, axis=1) > 0.0)
            )
            counter_clockwise = np.array([-normals[f][1], normals[f][0]])
            rows.append(owner[on])
            facets.append(np.full(on.sum(), f))
            ends.append(np.stack([p[on], q[on]], axis=1))
            signs.append(np.where((q[on] - p[on]) @ counter_clockwise > 0, 1.0, -1.0))
    return tuple(np.concatenate(a) for a in (rows, facets, ends, signs))


def facet_rules(
    rows: np.ndarray,
    ends: np.ndarray,
    signs: np.ndarray,
    ncut: int,
    degree: int,
    jacobian: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> RuleSet:
    """Gauss–Legendre rules on the pieces, grouped per cut-cell row.

    Args:
        rows: Cut-cell row of each piece, shape ``(m,)``.
        ends: End points of each piece, shape ``(m, 2, tdim)``.
        signs: Orientation of each piece (+1 or -1, :func:`facet_pieces`), shape ``(m,)``.
        ncut: Number of cut cells (rules are indexed by row).
        degree: Polynomial degree integrated exactly along a piece.
        jacobian: ``(rows (k,), X (k, tdim)) -> (k, gdim, tdim)`` parent Jacobian.

    Returns:
        Rules whose weights are ``sign ds / |det J|`` (physical arc length after
        FFCx's ``|det J|`` factor, negative on the reversed pieces of a fold).
    """
    t, w = basix.make_quadrature(basix.CellType.interval, degree)
    t, nq = t[:, 0], w.size
    order = np.argsort(rows, kind="stable")
    rows, ends, signs = rows[order], ends[order], signs[order]
    p, q = ends[:, 0], ends[:, 1]
    X = (p[:, None, :] + t[None, :, None] * (q - p)[:, None, :]).reshape(-1, p.shape[1])
    prow = np.repeat(rows, nq)
    J = jacobian(prow, X)
    tangent = np.einsum("kij,kj->ki", J, np.repeat(q - p, nq, axis=0))
    weights = np.tile(w, rows.size) * np.linalg.norm(tangent, axis=1) / np.abs(np.linalg.det(J))
    weights *= np.repeat(signs, nq)
    counts = np.bincount(prow, minlength=ncut)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return RuleSet(points=X, weights=weights, offsets=offsets)
