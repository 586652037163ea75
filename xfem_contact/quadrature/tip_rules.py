"""Quadrature near a crack tip: Duffy rules with radial grading on the tip's fan triangles and lips.

Pure numpy and Basix. The tip cell's sub-triangles all have the tip as vertex 0
(:class:`~xfem_contact.geometry.crack_tip_cell.TipCut`). :func:`duffy_rule` maps the
square ``(s, v)`` in ``[0, 1]^2`` onto the reference triangle, collapsing the
square's edge ``s = 0`` onto vertex 0:
``u = s^g``, ``xi = (u (1 - v), u v)``, ``dxi = g s^(g-1) u ds dv``, with tensor
Gauss-Legendre points in ``s`` and ``v``. On a fan triangle the distance to the tip
is ``r = u rho(v) + O(u^2)`` and the polar angle a smooth function of ``(u, v)``. With
the grading ``g = 2`` (the default, the almost-polar rule of Laborde et al. 2005)
the Williams fields' integrands become smooth in ``(s, v)``: ``sqrt(r) f(theta)``,
their gradients times a smooth function (``r^(-1/2)``) and the energy density
``|grad(sqrt(r) f(theta))|^2 ~ 1/r`` are, on straight fans, polynomials in ``s``
times smooth functions of ``v``. With ``g = 1`` (plain Duffy) only ``1/r`` is.

:func:`tip_lip_rule` grades Gauss-Legendre points the same way along the crack
piece, from the tip: ``t = sigma^g`` is the SEG3 parameter measured from the tip's end.

Points are in the parent cell's reference coordinates and weights in its reference
measure, as in :mod:`xfem_contact.quadrature.rules`: sides sum to reference areas, the
lip rule stores ``ds / |det J|``.

Cells next to a tip cell see the singularity from just outside:
:func:`near_tip_side_rules` collapses the same Duffy rule onto the vertex of each of
their sub-triangles nearest the tip (for a cell the crack or its extension enters, the
point where it enters, on the crack line).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.crack_tip_cell import TipCut
from xfem_contact.geometry.cut import CutGeometry
from xfem_contact.geometry.cut_topology import seg3_basis
from xfem_contact.quadrature.rules import RuleSet, curve_rules, triangle_rules

__all__ = ["duffy_rule", "gauss_interval", "near_tip_side_rules", "tip_lip_rule", "tip_side_rules"]

#: Node permutations of a P2 triangle (Basix order) making vertex ``k`` vertex 0,
#: orientation kept: row ``k``
_ROTATIONS = np.array(
    [[k, (k + 1) % 3, (k + 2) % 3, 3 + k, 3 + (k + 1) % 3, 3 + (k + 2) % 3] for k in range(3)]
)


def gauss_interval(n: int) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Gauss-Legendre points ``(n,)`` and weights ``(n,)`` on ``[0, 1]``."""
    if not (isinstance(n, int | np.integer) and n >= 1):
        raise ValueError(f"number of points must be an integer >= 1, got {n!r}")
    x, w = np.polynomial.legendre.leggauss(int(n))
    return 0.5 * (x + 1.0), 0.5 * w


def _check_grading(grading: int) -> None:
    if grading not in (1, 2):
        raise ValueError(f"grading must be 1 (plain Duffy) or 2 (almost polar), got {grading!r}")


def duffy_rule(
    n_radial: int, n_angular: int | None = None, grading: int = 2
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Collapsed (Duffy) rule on the reference triangle, singular point at vertex 0 ``(0, 0)``.

    Exact for polynomials of degree ``n_radial - 2`` (grading 2) or ``2 n_radial - 2``
    (grading 1) in ``xi`` when ``n_angular >= n_radial``; its purpose is the
    singular functions of the module docstring.

    Args:
        n_radial: Gauss points along ``s`` (from the singular vertex).
        n_angular: Gauss points along ``v`` (default ``n_radial``).
        grading: 1 (plain Duffy) or 2 (``u = s^2``, almost polar).

    Returns:
        Points ``(n_radial * n_angular, 2)`` and positive weights summing to ``1/2``.
    """
    _check_grading(grading)
    s, ws = gauss_interval(n_radial)
    v, wv = gauss_interval(n_radial if n_angular is None else n_angular)
    u = s**grading
    jac = grading * s ** (grading - 1) * u * ws  # du/ds * u (Duffy) * weight
    points = np.stack([np.outer(u, 1.0 - v), np.outer(u, v)], axis=-1).reshape(-1, 2)
    return points, np.outer(jac, wv).reshape(-1)


def tip_side_rules(cut: TipCut, side: int, n_radial: int, grading: int = 2) -> RuleSet:
    """Rules of one side of every tip cell through its fan triangles and :func:`duffy_rule`.

    Args:
        cut: Fan sub-triangulation of the tip cells.
        side: -1 (``phi < 0``) or +1.
        n_radial: Gauss points per direction on each fan triangle.
        grading: See :func:`duffy_rule`.

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet`, one rule per tip cell.
    """
    if side not in (-1, 1):
        raise ValueError(f"side must be -1 or +1, got {side!r}")
    tri, cell = (
        (cut.tri_minus, cut.tri_minus_cell) if side == -1 else (cut.tri_plus, cut.tri_plus_cell)
    )
    return triangle_rules(tri, cell, cut.num_cells, *duffy_rule(n_radial, grading=grading))


def near_tip_side_rules(
    geom: CutGeometry,
    side: int,
    rows: npt.NDArray[np.int64],
    distance: Callable[[np.ndarray, np.ndarray], np.ndarray],
    n_radial: int,
    grading: int = 2,
) -> RuleSet:
    """Rules of one side of cut cells near a tip: each curved sub-triangle by
    :func:`duffy_rule` collapsed onto its vertex nearest the tip.

    Args:
        geom: Sub-triangulation of all cut cells.
        side: -1 (``phi < 0``) or +1.
        rows: Distinct cut-cell rows, shape ``(m,)``.
        distance: ``(rows (k,), X (k, 2)) -> (k,)``: distance (m) from the reference
            points ``X`` of cut cells ``rows`` to the nearest tip.
        n_radial: Gauss points per direction.
        grading: See :func:`duffy_rule`.

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet`, rule ``k`` for cell ``rows[k]``.
    """
    if side not in (-1, 1):
        raise ValueError(f"side must be -1 or +1, got {side!r}")
    tri, cell = (
        (geom.tri_minus, geom.tri_minus_cell) if side == -1 else (geom.tri_plus, geom.tri_plus_cell)
    )
    position = np.full(geom.num_cells, -1, dtype=np.int64)
    position[rows] = np.arange(len(rows))
    keep = position[cell] >= 0
    order = np.argsort(position[cell[keep]], kind="stable")
    tri, cell = tri[keep][order], position[cell[keep]][order]
    nearest = np.zeros(len(tri), dtype=np.int64)
    if len(tri):
        nearest = np.argmin([distance(rows[cell], tri[:, k]) for k in range(3)], axis=0)
    tri = np.take_along_axis(tri, _ROTATIONS[nearest][:, :, None], axis=1)
    return triangle_rules(tri, cell, len(rows), *duffy_rule(n_radial, grading=grading))


def tip_lip_rule(
    cut: TipCut,
    n: int,
    jacobian: Callable[[np.ndarray, np.ndarray], np.ndarray],
    grad_phi_ref: Callable[[np.ndarray, np.ndarray], np.ndarray],
    grading: int = 2,
) -> RuleSet:
    """Graded Gauss rule on the crack piece of every tip cell, points clustered at the tip.

    Args:
        cut: Fan sub-triangulation of the tip cells.
        n: Gauss points per piece.
        jacobian: ``(rows (m,), X (m, 2)) -> (m, gdim, 2)``: the parent maps' Jacobians
            at reference points of tip cells ``rows``.
        grad_phi_ref: ``(rows (m,), X (m, 2)) -> (m, 2)``: reference gradient of ``phi``
            (orients the normal from side -1 to side +1).
        grading: 1 (plain Gauss-Legendre) or 2 (``t = sigma^2`` from the tip).

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` with normals ``(N, gdim)``, one
        rule per tip cell; weights ``ds / |det J|`` (``ds`` physical arc length).
    """
    _check_grading(grading)
    sigma, w_sigma = gauss_interval(n)
    t = sigma**grading
    dt = grading * sigma ** (grading - 1) * w_sigma
    s = np.where(cut.crack_tip_end[:, None] == 0, t, 1.0 - t)  # (ntip, n)
    N, dN = seg3_basis(s.reshape(-1))
    pieces = np.repeat(cut.crack, n, axis=0)
    X = np.einsum("qk,qkd->qd", N, pieces)
    dX = np.einsum("qk,qkd->qd", dN, pieces)
    rows = np.repeat(np.arange(cut.num_cells), n)
    return curve_rules(
        X, dX, np.tile(dt, cut.num_cells), rows, cut.num_cells, jacobian, grad_phi_ref
    )
