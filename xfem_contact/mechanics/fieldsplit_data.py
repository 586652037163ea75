"""What a fieldsplit preconditioner needs to know of a problem's mixed space.

:func:`fieldsplit_dofs` names the dofs of the displacements (``"u"``: both sides) and of
the multipliers (``"lambda"``: every multiplier field); :func:`rigid_modes` gives the
translations and the rotations of each side, the near null space of the displacement
block for algebraic multigrid (GAMG). Used by
:class:`~xfem_contact.mechanics.problem.Problem` for the ``"iterative"`` preset of
:data:`~xfem_contact.solvers.options.PRESETS`.
"""

from __future__ import annotations

from collections.abc import Iterator

import basix
import dolfinx.fem
import numpy as np

from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.mechanics.rigid_motions import rigid_motions

SIDE_FIELDS = (0, 1)


def fieldsplit_dofs(space: EnrichedSpace) -> dict[str, np.ndarray]:
    """``{"u": nodes, "lambda": dofs}``: local dofs of ``space.W`` (owned and ghost) of
    the displacement fields, one row ``(x, y)`` per node and side, and of the multiplier
    fields (no ``"lambda"`` without a multiplier). Not collective."""
    W = space.W

    def dofs(fields):
        return np.unique(np.concatenate([W.sub(f).dofmap.list.ravel() for f in fields]))

    nodes = []
    for field in SIDE_FIELDS:
        parts = [W.sub(field).sub(c).dofmap.list.ravel() for c in range(W.mesh.geometry.dim)]
        nodes.append(np.unique(np.stack(parts, axis=1), axis=0))
    dofs_of = {"u": np.concatenate(nodes)}
    multipliers = [field for field, _, _ in space.multiplier_fields]
    if multipliers:
        dofs_of["lambda"] = dofs(multipliers)
    dofs_of["band"] = np.union1d(_band_displacements(space), dofs_of.get("lambda", []))
    return dofs_of


def _band_displacements(space: EnrichedSpace) -> np.ndarray:
    """Local dofs of ``space.W`` of both displacement fields on the cut cells and on
    the cells sharing a facet with one (where the ghost penalty acts). Not collective
    (ghost cells are local cells too)."""
    mesh = space.cut.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim, tdim - 1)
    mesh.topology.create_connectivity(tdim - 1, tdim)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    cut = space.cut.cut_cells
    facets = np.unique(np.concatenate([c2f.links(c) for c in cut] or [np.zeros(0, np.int32)]))
    cells = np.unique(np.concatenate([cut] + [f2c.links(f) for f in facets]))
    dofs = [space.W.sub(field).dofmap.list[cells].ravel() for field in SIDE_FIELDS]
    return np.unique(np.concatenate(dofs))


def vertex_interpolation(space: EnrichedSpace):
    """The interpolation of each displacement field from its vertex values (degree 1 in
    degree 2: the coarse level of a two-level p-multigrid), or ``None`` for degree 1.

    Returns:
        ``(rows, cols, weights)``: local dofs of ``space.W`` (``rows`` active, owned or
        ghost: a dof's owner need not hold a cell on which the field is active around
        it; ``cols`` the active vertex dofs of the same field and component) and the
        weights of the degree-1 basis at the rows' nodes; each ``(row, col)`` once here,
        taken from a cell on which the field is active. Not collective.
    """
    if space.degree == 1:
        return None
    W, active = space.W, space.active
    cell_name = W.mesh.basix_cell()
    fine = basix.create_element(basix.ElementFamily.P, cell_name, space.degree)
    coarse = basix.create_element(basix.ElementFamily.P, cell_name, 1)
    table = coarse.tabulate(0, fine.points)[0, :, :, 0]  # (fine nodes, vertices)
    gdim = W.mesh.geometry.dim
    node, vertex = np.nonzero(np.abs(table) > 1e-14)  # the nonzero weights
    rows, cols, weights = [], [], []
    for field in SIDE_FIELDS:
        dofs = W.sub(field).dofmap.list  # (cells, nodes * gdim), a node's components together
        dofs = dofs[np.all(active[dofs], axis=1)]
        for c in range(gdim):
            rows.append(dofs[:, gdim * node + c].ravel())
            cols.append(dofs[:, gdim * vertex + c].ravel())
            weights.append(np.tile(table[node, vertex], dofs.shape[0]))
    rows, cols, weights = (np.concatenate(a) for a in (rows, cols, weights))
    _, first = np.unique(rows.astype(np.int64) * active.size + cols, return_index=True)
    return rows[first], cols[first], weights[first]


def rigid_modes(space: EnrichedSpace) -> Iterator[dolfinx.fem.Function]:
    """The rigid motions of each side separately (:func:`~xfem_contact.mechanics.
    rigid_motions.rigid_motions` about the origin: 3 per side field in 2D, 6 in 3D) on
    ``space.W`` (m): one Function, refilled with the next mode at each step of the
    iteration (a Function on ``W`` is large; use each mode before taking the next).
    Collective iteration."""
    W = space.W
    gdim = W.mesh.geometry.dim
    mode = dolfinx.fem.Function(W)
    for field in SIDE_FIELDS:
        V, dofs = space.field_space(field)  # dofs: the W dof of each (unrolled) V dof
        x = V.tabulate_dof_coordinates()[:, :gdim]  # (nodes, gdim)
        motions = rigid_motions(x)  # (nodes, gdim, m): a node's components together
        for k in range(motions.shape[2]):
            mode.x.array[:] = 0.0
            mode.x.array[dofs] = motions[:, :, k].ravel()
            yield mode
