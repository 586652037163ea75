"""Exterior-facet measures of the sides of a cut mesh: uncut facets and pieces of cut ones."""

from __future__ import annotations

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cut3d_boundary import boundary_parts_3d
from xfem_contact.quadrature import boundary
from xfem_contact.quadrature.cell_rules import IntegrationPart


def facet_array(mesh: dolfinx.mesh.Mesh, facets, value: int | None) -> np.ndarray:
    """The owned exterior facets (local indices, sorted) of an array of facet indices or
    of a facet ``MeshTags`` with its tag ``value``. Collective (counts the tagged facets).

    Raises:
        ValueError: tags of another dimension, a missing ``value``, a tag no facet
            carries, or facets that are not exterior facets.
    """
    fdim = mesh.topology.dim - 1
    if isinstance(facets, dolfinx.mesh.MeshTags):
        if facets.dim != fdim:
            raise ValueError(f"Facet tags must have dimension {fdim}, got {facets.dim}")
        if value is None:
            raise ValueError("Give the tag value with a MeshTags: cut.ds(side, tags, value)")
        facets = facets.find(value)
        found = mesh.comm.allreduce(facets.size, op=MPI.SUM)
        if found == 0:
            raise ValueError(f"No facet carries the tag value {value}")
    facets = np.unique(np.asarray(facets, dtype=np.int32))
    num_owned = mesh.topology.index_map(fdim).size_local
    facets = facets[facets < num_owned]  # ghost facets are integrated by their owner
    mesh.topology.create_connectivity(fdim, fdim + 1)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    bad = np.setdiff1d(facets, exterior)
    if bad.size:
        raise ValueError(f"Facets {bad[:5].tolist()} are not exterior facets of the mesh")
    return facets


def boundary_parts(cut, side: int, facets: np.ndarray) -> list[IntegrationPart]:
    """The integration parts of exterior ``facets`` on ``side`` of a
    :class:`~xfem_contact.fem.cutmesh.CutMesh`: the facets of the side's uncut cells
    (standard rule) and, per reference facet, the pieces on that side of the cut cells'
    facets (runtime rules, ``ufl.FacetNormal`` replaced by the facet's normal); in 3D
    :func:`~xfem_contact.fem.cut3d_boundary.boundary_parts_3d`. Collective."""
    mesh, tdim = cut.mesh, cut.mesh.topology.dim
    cell_name = mesh.topology.cell_name()
    mesh.topology.create_connectivity(tdim - 1, tdim)
    mesh.topology.create_connectivity(tdim, tdim - 1)
    if tdim == 3:
        return boundary_parts_3d(cut, side, facets)
    pairs = dolfinx.fem.compute_integration_domains(
        dolfinx.fem.IntegralType.exterior_facet, mesh.topology, facets
    ).reshape(-1, 2)
    keep = cut.cell_sides[pairs[:, 0]] == side
    parts = [IntegrationPart("exterior_facet", entities=pairs[keep].ravel())]
    # Pieces on cut cells: only those on facets of the set
    rows, local, ends, signs = boundary.facet_pieces(cut.geometry, side, cell_name)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    cell_facets = c2f.array.reshape(-1, c2f.offsets[1] - c2f.offsets[0])
    in_set = np.isin(cell_facets[cut.cut_cells[rows], local], facets)
    rows, local, ends, signs = rows[in_set], local[in_set], ends[in_set], signs[in_set]
    _, ref_normals = boundary.reference_facets(cell_name)
    J = ufl.Jacobian(mesh)
    # A reference facet no cut cell has on the set, on any rank, gets no integral
    pieces = mesh.comm.allreduce(np.bincount(local, minlength=len(ref_normals)))
    for f, n_ref in enumerate(ref_normals):
        mine = local == f
        if not pieces[f]:
            continue
        cells_rows = np.unique(rows[mine])
        rule = boundary.facet_rules(
            np.searchsorted(cells_rows, rows[mine]),
            ends[mine],
            signs[mine],
            cells_rows.size,
            cut.quadrature_degree,
            lambda r, X, cr=cells_rows: cut.maps.jacobian(cut.cut_cells[cr[r]], X),
        )
        normal = ufl.dot(ufl.inv(J).T, ufl.as_vector(n_ref.tolist()))
        normal = normal / ufl.sqrt(ufl.inner(normal, normal))
        rules = cut._rules(cut.cut_cells[cells_rows], rule)
        parts.append(IntegrationPart("cell", rules=rules, replace={ufl.FacetNormal(mesh): normal}))
    return parts
