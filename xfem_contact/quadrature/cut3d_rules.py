"""Rules of 3D cut cells by cell kind and level-set degree: one entry point over the
three kernels (pure numpy and Basix, no DOLFINx).

=============  ======  ===========================================================
cell           degree  kernel
=============  ======  ===========================================================
tetrahedron    1       exact planar cut (:mod:`~xfem_contact.quadrature.cut_tet_rules`)
tetrahedron    2       Saye on truncated boxes (:mod:`~xfem_contact.quadrature.curved_tet_rules`)
hexahedron     1, 2    Saye (:mod:`~xfem_contact.quadrature.saye`)
=============  ======  ===========================================================

Points are in the parent's reference coordinates, weights in its reference measure;
interface weights are ``ds / |det J|`` with physical unit normals (``jacobian`` given).
The tolerance policy (``phi < 0`` is side -1, ``phi >= 0`` side +1, a face where
``phi`` vanishes belongs to the cell on its negative side) is the kernels'.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_tets import classify_tets, cut_tets
from xfem_contact.geometry.exact_lines import ExactLevelSet
from xfem_contact.quadrature.curved_tet_rules import classify_p2_tets, p2_tet_cut_rules
from xfem_contact.quadrature.cut_tet_rules import tet_interface_rule, tet_side_rules
from xfem_contact.quadrature.saye import CutRules, classify_hexes, hex_cut_rules
from xfem_contact.quadrature.surface_rules import Jacobian

__all__ = ["CELLS_3D", "classify_3d", "cut_rules_3d", "saye_order"]

CELLS_3D = ("tetrahedron", "hexahedron")
"""The 3D cell kinds that can be cut."""


def _check(cell: str, degree: int) -> None:
    if cell not in CELLS_3D:
        raise ValueError(f"cell must be one of {CELLS_3D} to be cut in 3D, got {cell!r}")
    if degree not in (1, 2):
        raise ValueError(f"level-set degree must be 1 or 2, got {degree!r}")


def saye_order(quadrature_degree: int) -> int:
    """Gauss-Legendre points per interval of Saye's rules for a polynomial degree:
    ``ceil((q + 1) / 2)`` (exact for degree ``q`` along each line)."""
    return max(1, math.ceil((quadrature_degree + 1) / 2))


def classify_3d(
    cell: str, degree: int, phi: npt.ArrayLike, exact: ExactLevelSet | None = None
) -> npt.NDArray[np.int8]:
    """Side of every cell: -1, +1, or 0 when it may be cut (then :func:`cut_rules_3d`
    decides; a cell certified on one side is never cut).

    Args:
        cell: ``"tetrahedron"`` or ``"hexahedron"``.
        degree: Level-set degree, 1 or 2.
        phi: Nodal values, shape ``(ncells, ndofs)`` (Basix ``gll_warped`` order).
        exact: For P2 tetrahedra, the level set that ``phi`` interpolates, as in
            :func:`cut_rules_3d`: cells near its zero set are certified with a bound of
            its distance from the interpolant
            (:func:`~xfem_contact.quadrature.curved_tet_rules.classify_p2_tets`). Ignored
            for the other kinds and degrees.

    Returns:
        ``int8`` array of shape ``(ncells,)``.
    """
    _check(cell, degree)
    if cell == "hexahedron":
        return classify_hexes(phi, degree)
    return classify_tets(phi) if degree == 1 else classify_p2_tets(phi, exact)


def cut_rules_3d(
    cell: str,
    degree: int,
    phi: npt.ArrayLike,
    quadrature_degree: int,
    jacobian: Jacobian | None = None,
    exact: ExactLevelSet | None = None,
) -> CutRules:
    """Rules of both sides and of the interface of every cell (row of ``phi``).

    Args:
        cell: ``"tetrahedron"`` or ``"hexahedron"``.
        degree: Level-set degree, 1 or 2.
        phi: Nodal values, shape ``(ncells, ndofs)`` (Basix ``gll_warped`` order).
        quadrature_degree: Polynomial degree of the rules on the straight sub-cells of
            P1 tetrahedra; Saye's rules take :func:`saye_order` points per interval.
        jacobian: ``(rows, X) -> (m, 3, 3)`` parent Jacobians for the interface rule;
            ``None``: reference cells.
        exact: For ``degree = 2``: ``(rows, X) -> (m,)``, the level set that ``phi``
            interpolates at reference points ``X`` ``(m, 3)`` of cells ``rows``; Saye's
            rules then follow its zero set (see
            :func:`~xfem_contact.quadrature.saye.hex_cut_rules`). Ignored for
            ``degree = 1`` (the rules of the P1/Q1 interpolant).

    Returns:
        A :class:`~xfem_contact.quadrature.saye.CutRules` (``reduced`` lists the cells
        where Saye used its lower-order fallback; none for P1 tetrahedra).
    """
    _check(cell, degree)
    order = saye_order(quadrature_degree)
    exact = exact if degree == 2 else None
    if cell == "hexahedron":
        return hex_cut_rules(phi, degree, order, jacobian=jacobian, exact=exact)
    if degree == 2:
        return p2_tet_cut_rules(phi, order, jacobian=jacobian, exact=exact)
    cut = cut_tets(phi)
    q = quadrature_degree
    return CutRules(
        tet_side_rules(cut, -1, q),
        tet_side_rules(cut, +1, q),
        tet_interface_rule(cut, q, jacobian),
        np.zeros(0, dtype=np.int64),
    )
