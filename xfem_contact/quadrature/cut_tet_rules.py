"""Quadrature rules of tetrahedra cut by planes (from a
:class:`~xfem_contact.geometry.cut_tets.TetCut`).

Pure numpy and Basix. Points are in the parent's reference coordinates, weights in
the parent reference measure (see :mod:`xfem_contact.quadrature.surface_rules` for
the interface). Sub-cells are straight, so a Basix rule of degree ``q`` mapped to each
sub-tetrahedron or interface triangle integrates polynomials of degree ``q`` exactly
(in reference coordinates, and in physical ones for affine parents).
"""

from __future__ import annotations

import basix
import numpy as np

from xfem_contact.geometry.cut_tets import TetCut
from xfem_contact.quadrature.rules import RuleSet
from xfem_contact.quadrature.surface_rules import Jacobian, surface_rules

__all__ = ["tet_interface_rule", "tet_side_rules"]


def tet_side_rules(cut: TetCut, side: int, degree: int) -> RuleSet:
    """Rules of one side of every cell through its sub-tetrahedra.

    ``X = V_0 + sum_k (V_k - V_0) xi_k`` and ``w = w_hat |det(V_k - V_0)|`` for each
    point ``(xi, w_hat)`` of ``basix.make_quadrature(tetrahedron, degree)``: all
    weights are positive.

    Args:
        cut: The cut cells.
        side: -1 or +1.
        degree: Polynomial degree of the tetrahedron rule.

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` of ``cut.num_cells`` rules (no
        normals); cells with no part on this side get empty rules.
    """
    if side not in (-1, 1):
        raise ValueError(f"side must be -1 or +1, got {side!r}")
    tets, rows = (
        (cut.tet_minus, cut.tet_minus_cell) if side == -1 else (cut.tet_plus, cut.tet_plus_cell)
    )
    xi, w_hat = basix.make_quadrature(basix.CellType.tetrahedron, degree)
    edges = tets[:, 1:] - tets[:, :1]  # (n, 3, 3): rows k = V_k - V_0
    X = tets[:, None, 0] + np.einsum("qk,nkd->nqd", xi, edges)
    weights = np.abs(np.linalg.det(edges))[:, None] * w_hat
    point_rows = np.repeat(rows, xi.shape[0])
    offsets = np.searchsorted(point_rows, np.arange(cut.num_cells + 1)).astype(np.int64)
    return RuleSet(X.reshape(-1, 3), weights.reshape(-1), offsets)


def tet_interface_rule(cut: TetCut, degree: int, jacobian: Jacobian | None = None) -> RuleSet:
    """Rules on the interface triangles of every cell, with physical unit normals.

    A point ``(s, w_hat)`` of ``basix.make_quadrature(triangle, degree)`` maps to
    ``X = A + (B - A) s_0 + (C - A) s_1`` with area vector ``|(B - A) x (C - A)| n``
    (``n`` the triangle's reference unit normal, towards side +1), then through
    :func:`~xfem_contact.quadrature.surface_rules.surface_rules`.

    Args:
        cut: The cut cells.
        degree: Polynomial degree of the triangle rule.
        jacobian: ``(rows, X) -> (m, 3, 3)`` parent Jacobians; ``None``: reference
            cells (weights are reference areas, normals reference normals).

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` of ``cut.num_cells`` rules with
        normals ``(N, 3)``; cells without interface triangles get empty rules.
    """
    s, w_hat = basix.make_quadrature(basix.CellType.triangle, degree)
    tri = cut.tri
    X = tri[:, None, 0] + np.einsum("qk,nkd->nqd", s, tri[:, 1:] - tri[:, :1])
    area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    area = area[:, None] * cut.tri_normal
    nq = s.shape[0]
    return surface_rules(
        X.reshape(-1, 3),
        np.repeat(area, nq, axis=0),
        np.tile(w_hat, tri.shape[0]),
        np.repeat(cut.tri_cell, nq),
        cut.num_cells,
        jacobian,
    )
