"""Exterior-face measures of the sides of a cut 3D mesh: uncut faces and pieces of cut ones.

The 3D counterpart of :func:`~xfem_contact.fem.cut_boundary.boundary_parts`. A face of a
cut cell is classified by its own level set (the cell's restricted to it, exactly): one on
side ``side`` gets FFCx's standard facet rule, like the faces of that side's uncut cells;
one the interface cuts gets the runtime rules of its piece on that side
(:func:`~xfem_contact.quadrature.cut3d_faces.face_rules`), one rule set per local face
index so that each kernel knows its reference normal.
"""

from __future__ import annotations

import basix
import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.geometry import cut as cut2d
from xfem_contact.quadrature.cell_rules import IntegrationPart
from xfem_contact.quadrature.cut3d_faces import FACE_KIND, face_rules, face_values

__all__ = ["boundary_parts_3d"]


def boundary_parts_3d(cut, side: int, facets: np.ndarray) -> list[IntegrationPart]:
    """The integration parts of exterior ``facets`` (owned, local indices) on ``side`` of a
    3D :class:`~xfem_contact.fem.cutmesh.CutMesh`. Collective (every rank makes the same
    parts, so forms have the same integrals)."""
    mesh = cut.mesh
    cell = mesh.topology.cell_name()
    pairs = dolfinx.fem.compute_integration_domains(
        dolfinx.fem.IntegralType.exterior_facet, mesh.topology, facets
    ).reshape(-1, 2)
    cell_side = cut.cell_sides[pairs[:, 0]]
    on_cut = np.flatnonzero(cell_side == 0)
    cells, local = pairs[on_cut, 0], pairs[on_cut, 1]
    values = face_values(cell, cut.degree, cut.maps.nodal_values(cells), local)
    face_side = cut2d.classify(FACE_KIND[cell], cut.degree, values)
    whole = np.zeros(pairs.shape[0], dtype=bool)
    whole[cell_side == side] = True
    whole[on_cut[face_side == side]] = True
    parts = [IntegrationPart("exterior_facet", entities=pairs[whole].ravel())]
    crossed = face_side == 0
    reference_normals = basix.cell.facet_outward_normals(basix.CellType[cell])
    nfaces = len(reference_normals)
    counts = mesh.comm.allreduce(np.bincount(local[crossed], minlength=nfaces))
    J = ufl.Jacobian(mesh)
    maps = cut.maps
    for f in range(nfaces):
        if not counts[f]:  # no rank has a crossed face f: no integral anywhere
            continue
        mine = np.flatnonzero(crossed & (local == f))
        rows_cells = cells[mine]
        rules = face_rules(
            cell,
            cut.degree,
            f,
            values[mine],
            side,
            cut.quadrature_degree,
            lambda rows, X, c=rows_cells: maps.jacobian(c[rows], X),
        )
        normal = ufl.dot(ufl.inv(J).T, ufl.as_vector(reference_normals[f].tolist()))
        normal = normal / ufl.sqrt(ufl.inner(normal, normal))
        parts.append(
            IntegrationPart(
                "cell",
                rules=cut._rules(rows_cells, rules),
                replace={ufl.FacetNormal(mesh): normal},
            )
        )
    return parts
