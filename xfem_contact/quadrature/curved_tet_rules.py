"""Rules of tetrahedra cut by P2 level sets (curved interfaces): Saye's rules on the four
hexahedra of each tetrahedron, pure numpy and Basix.

The reference tetrahedron is subdivided into four hexahedra, one per vertex ``i``, with corners
``i``, the midpoints of its three edges, the centroids of its three faces and the
centroid of the tetrahedron. Each is the image of the unit cube by a trilinear map ``M``
with a positive Jacobian determinant (a polynomial bounded away from zero). A P2
polynomial composed with ``M`` has degree at most 2 in each cube coordinate: a Q2
polynomial, obtained exactly by interpolating the composition at the 27 Q2 nodes.
Saye's rules of those polynomials (:func:`~xfem_contact.quadrature.saye.saye_points`)
map back through ``M``: volume weights times ``det dM``, interface area vectors by
Nanson's formula ``cof(dM) a``. Nothing is triangulated along the interface, so
nothing can tangle, and all weights are positive. The rules are not exact for planes
(the composed level set is not planar) but converge as Saye's rules do as ``order``
grows.

Tolerance policy and refusals are Saye's (:mod:`xfem_contact.quadrature.saye`): side -1 is
``phi < 0``, side +1 ``phi >= 0``; a zero set with a singular point is refused naming the
tetrahedron.
"""

from __future__ import annotations

import functools

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_topology import nodal_values
from xfem_contact.geometry.tensor_levelset import coefficients
from xfem_contact.quadrature.saye import (
    MAX_DEPTH,
    CutRules,
    certified_sides,
    rules_from_points,
    saye_points,
)
from xfem_contact.quadrature.surface_rules import Jacobian, surface_rules

__all__ = ["HEXAHEDRA", "classify_p2_tets", "hexahedron_map", "p2_tet_cut_rules"]


def _subdivision() -> np.ndarray:
    """Corners ``(4, 8, 3)`` of the four hexahedra of the reference tetrahedron, in Basix
    hexahedron vertex order."""
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    hexes = []
    for i in range(4):
        a, b, c = (j for j in range(4) if j != i)
        if i % 2:  # keep every map orientation-preserving
            b, c = c, b
        mid = {j: 0.5 * (V[i] + V[j]) for j in (a, b, c)}
        face = {(j, k): (V[i] + V[j] + V[k]) / 3.0 for j, k in ((a, b), (a, c), (b, c))}
        hexes.append(
            [V[i], mid[a], mid[b], face[a, b], mid[c], face[a, c], face[b, c], V.mean(axis=0)]
        )
    return np.array(hexes)


HEXAHEDRA = _subdivision()
"""Corners of the four hexahedra of the reference tetrahedron, shape ``(4, 8, 3)``."""


def hexahedron_map(U: npt.NDArray[np.float64], k: int) -> tuple[np.ndarray, np.ndarray]:
    """The trilinear map of hexahedron ``k`` at cube points ``U`` ``(N, 3)``: tetrahedron
    points ``(N, 3)`` and Jacobians ``dM/dU`` ``(N, 3, 3)``."""
    P = np.transpose(HEXAHEDRA[k].reshape(2, 2, 2, 3), (2, 1, 0, 3)).reshape(8, 3)  # (u, v, w)
    lin = [np.stack([1.0 - U[:, d], U[:, d]], axis=1) for d in range(3)]  # (N, 2) each
    step = np.broadcast_to([-1.0, 1.0], lin[0].shape)

    def corners(a, b, c):  # (N, 8) products, u slowest
        return (a[:, :, None, None] * b[:, None, :, None] * c[:, None, None, :]).reshape(-1, 8)

    X = corners(*lin) @ P
    J = np.stack(
        [
            corners(step, lin[1], lin[2]) @ P,
            corners(lin[0], step, lin[2]) @ P,
            corners(lin[0], lin[1], step) @ P,
        ],
        axis=2,
    )
    return X, J


@functools.cache
def _to_cubes() -> np.ndarray:
    """Matrix ``(4 * 27, 10)``: P2 tetrahedron nodal values -> values of the compositions
    with the four hexahedron maps at the Q2 nodes of the cube (Basix orders)."""
    q2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, 2, basix.LagrangeVariant.gll_warped
    )
    p2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    X = np.concatenate([hexahedron_map(q2.points, k)[0] for k in range(4)])
    return p2.tabulate(0, X)[0, :, :, 0]


def _cube_coefficients(phi: npt.ArrayLike) -> np.ndarray:
    phi = nodal_values(phi, 10, "P2 tetrahedron", "tetrahedron")
    values = (phi @ _to_cubes().T).reshape(-1, 27)  # row 4 c + k: hexahedron k of cell c
    return coefficients(values, 2)


def classify_p2_tets(phi: npt.ArrayLike) -> npt.NDArray[np.int8]:
    """Side of each tetrahedron certified by the Bernstein coefficients on its four
    hexahedra: -1, +1, or 0 (possibly cut).

    Args:
        phi: P2 nodal values, shape ``(ncells, 10)`` (Basix order).

    Returns:
        ``int8`` array of shape ``(ncells,)``.
    """
    sides = certified_sides(_cube_coefficients(phi)).reshape(-1, 4)
    return np.where((sides == -1).all(axis=1), -1, np.where((sides == 1).all(axis=1), 1, 0)).astype(
        np.int8
    )


def p2_tet_cut_rules(
    phi: npt.ArrayLike,
    order: int = 4,
    *,
    max_depth: int = MAX_DEPTH,
    jacobian: Jacobian | None = None,
) -> CutRules:
    """Rules of both sides and of the interface of tetrahedra with P2 level sets.

    Args:
        phi: P2 nodal values, shape ``(ncells, 10)`` (Basix ``gll_warped`` order).
        order: Gauss-Legendre points per interval of Saye's rules.
        max_depth: Box subdivision levels on the cube.
        jacobian: ``(rows, X) -> (m, 3, 3)`` parent Jacobians for the interface rule;
            ``None``: reference cells.

    Returns:
        A :class:`~xfem_contact.quadrature.saye.CutRules`: points in the reference
        tetrahedron, weights in its measure (all positive).

    Raises:
        ValueError: Bad shape or values, or a singular point of the zero set (naming
            the tetrahedron).
    """
    C = _cube_coefficients(phi)
    ncells = C.shape[0] // 4
    points = saye_points(C, order, max_depth=max_depth, kind="tetrahedron")
    sides = []
    for rows, U, w in (points.minus, points.plus):
        X, J = _mapped(rows, U)
        weights = w * np.linalg.det(J)
        sides.append(rules_from_points(rows // 4, X, weights, ncells))
    rows, U, w, area = points.interface
    X, J = _mapped(rows, U)
    c0, c1, c2 = J[:, :, 0], J[:, :, 1], J[:, :, 2]
    cofactor = np.stack([np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)], axis=2)
    area = np.einsum("nij,nj->ni", cofactor, area)  # det(J) J^{-T} a
    interface = surface_rules(X, area, w, rows // 4, ncells, jacobian)  # rows are sorted
    reduced = np.unique(points.reduced // 4).astype(np.int64)
    return CutRules(*sides, interface, reduced)


def _mapped(rows: np.ndarray, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedron points and ``dM/dU`` of cube points ``U`` of sub-hexahedra ``rows``
    (row ``4 c + k``: hexahedron ``k`` of cell ``c``)."""
    X, J = np.empty_like(U), np.empty((U.shape[0], 3, 3))
    for k in range(4):
        mine = rows % 4 == k
        X[mine], J[mine] = hexahedron_map(U[mine], k)
    return X, J
