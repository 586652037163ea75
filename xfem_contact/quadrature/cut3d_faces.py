"""Rules on one side of the faces of cut 3D cells, for Neumann terms on boundary faces
that the interface cuts (pure numpy and Basix, no DOLFINx).

The level set restricted to a face of a tetrahedron (hexahedron) is a P1/P2 (Q1/Q2)
polynomial on a reference triangle (quadrilateral), read exactly off the cell's nodal
values at the face's nodes. The face is cut by the 2D cutter
(:func:`xfem_contact.geometry.cut.subtriangulate`) and its side rules
(:func:`xfem_contact.quadrature.rules.side_rules`) are mapped into the cell by the face's
affine parametrisation ``X = V_0 + (V_1 - V_0) s + (V_2 - V_0) t``, with the area vector
``(V_1 - V_0) x (V_2 - V_0)``: weights ``dA / |det J|`` by Nanson's formula
(:func:`~xfem_contact.quadrature.surface_rules.surface_rules`), as an interface rule.
The 2D cutter's tolerance policy applies on the face (``phi < 0`` is side -1).
"""

from __future__ import annotations

import functools

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry import cut
from xfem_contact.quadrature.rules import RuleSet, side_rules
from xfem_contact.quadrature.surface_rules import Jacobian, surface_rules

__all__ = ["FACE_KIND", "face_nodes", "face_rules", "face_values"]

FACE_KIND = {"tetrahedron": "triangle", "hexahedron": "quadrilateral"}
"""The reference face of each 3D cell kind."""


@functools.cache
def face_nodes(cell: str, degree: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per local face of ``cell``: its origin ``(nfaces, 3)``, its two axes
    ``(nfaces, 2, 3)`` (reference coordinates of the cell), and the cell's level-set
    dofs at the face element's nodes ``(nfaces, face ndofs)`` (Basix ``gll_warped`` order
    of both elements)."""
    if cell not in FACE_KIND:
        raise ValueError(f"cell must be one of {list(FACE_KIND)}, got {cell!r}")
    variant = basix.LagrangeVariant.gll_warped
    ctype, ftype = basix.CellType[cell], basix.CellType[FACE_KIND[cell]]
    points = basix.create_element(basix.ElementFamily.P, ctype, degree, variant).points
    face_points = basix.create_element(basix.ElementFamily.P, ftype, degree, variant).points
    vertices = basix.geometry(ctype)
    faces = np.array(basix.topology(ctype)[2])
    origin = vertices[faces[:, 0]]
    axes = np.stack([vertices[faces[:, 1]] - origin, vertices[faces[:, 2]] - origin], axis=1)
    mapped = origin[:, None] + np.einsum("kj,fjd->fkd", face_points, axes)
    distance = np.linalg.norm(mapped[:, :, None] - points[None, None], axis=3)
    dofs = distance.argmin(axis=2)
    assert np.all(distance.min(axis=2) < 1e-12), "face nodes are cell nodes"
    return origin, axes, dofs


def face_values(
    cell: str, degree: int, phi: npt.ArrayLike, faces: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """The cell level sets ``phi`` ``(n, ndofs)`` restricted to local faces ``faces``
    ``(n,)``: nodal values of the face element, shape ``(n, face ndofs)`` (exact copies)."""
    dofs = face_nodes(cell, degree)[2]
    phi = np.asarray(phi, dtype=np.float64)
    return np.take_along_axis(phi, dofs[np.asarray(faces)], axis=1)


def face_rules(
    cell: str,
    degree: int,
    face: int,
    values: npt.ArrayLike,
    side: int,
    quadrature_degree: int,
    jacobian: Jacobian | None = None,
) -> RuleSet:
    """Rules of side ``side`` on local face ``face`` of cut cells.

    Args:
        cell: ``"tetrahedron"`` or ``"hexahedron"``.
        degree: Level-set degree, 1 or 2.
        face: Local face index (DOLFINx / Basix order), the same for all rows.
        values: Face level-set values :func:`face_values`, shape ``(n, face ndofs)``.
        side: -1 or +1.
        quadrature_degree: Degree of the rules on the curved sub-triangles of the face.
        jacobian: ``(rows, X) -> (m, 3, 3)`` parent Jacobians; ``None``: reference cells.

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` of ``n`` rules: points in the
        cell's reference coordinates, weights ``dA / |det J|``, normals the face's
        physical unit normal (orientation of the face's parametrisation).
    """
    origin, axes, _ = face_nodes(cell, degree)
    values = np.asarray(values, dtype=np.float64)
    n = values.shape[0]
    geometry = cut.subtriangulate(FACE_KIND[cell], degree, values)
    rule = side_rules(geometry, side, quadrature_degree, n)
    X = origin[face] + rule.points @ axes[face]
    area = np.broadcast_to(np.cross(axes[face, 0], axes[face, 1]), X.shape)
    return surface_rules(X, area, rule.weights, rule.point_rows, n, jacobian)
