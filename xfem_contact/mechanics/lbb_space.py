"""The vital-vertex restriction (:mod:`xfem_contact.mechanics.lbb`) applied to a
multiplier field of an enriched space, in parallel: the prolongation ``R`` uses."""

from __future__ import annotations

import typing

import basix
import dolfinx.fem
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.prolongation import MultiplierProlongation
from xfem_contact.geometry.crack import NONE, TIP
from xfem_contact.mechanics import lbb as lbb_module

#: Per cell type, how each cut edge's vital vertex is chosen, for an interface and for a
#: crack's lips (:func:`xfem_contact.mechanics.lbb.vital_vertices`): ``"nearer"``, the end
#: nearer the interface; ``"covering"``, the greedy covering; ``"covering, near
#: crossings"``, the covering after the ends of the crossings within
#: :data:`NEAR_SHARE` of an edge. The nodal multiplier's value where the interface
#: crosses a cut edge mixes its two ends, and a non-vital end takes the mean of several
#: vital vertices: where the covering made the farther end vital, the crossing hardly
#: sees that vertex's unknown, and the inf-sup constant of P1-P1 triangles fell with h
#: (docs' stability page). The nearer end's shape function is at least 1/2 at the
#: crossing. On a crack's lips on triangles the covering with the near crossings keeps
#: the larger constant and the stress intensity factors' accuracy that the nearer ends
#: lose; on tetrahedron edges the covering's few vital vertices lose the pressure's
#: accuracy.
VITAL_RULE = {
    "interval": ("covering", "covering"),
    "triangle": ("nearer", "covering, near crossings"),
    "quadrilateral": ("covering", "covering"),
    "tetrahedron": ("nearer", "nearer"),
    "hexahedron": ("nearer", "nearer"),
}
#: Share of a cut edge's length within which its crossing makes its nearer end vital
#: before the covering (rule ``"covering, near crossings"``)
NEAR_SHARE = 0.25


def _links(cell_type: dolfinx.mesh.CellType) -> np.ndarray:
    """``(k, 2)`` cell-local node pairs of a degree-2 Lagrange cell: each node off the
    vertices (one at the centre of each edge, and of each face and the interior of a
    quadrilateral or hexahedron) with each vertex of its entity (basix numbering), the
    nodes whose mean is that node's value in a linear (multilinear) field."""
    cell = basix.CellType[cell_type.name]
    element = basix.create_element(basix.ElementFamily.P, cell, 2, basix.LagrangeVariant.equispaced)
    topology = basix.topology(cell)
    pairs = [
        (node, vertex)
        for dim in range(1, len(topology))
        for entity, nodes in enumerate(element.entity_dofs[dim])
        for node in nodes
        for vertex in topology[dim][entity]
    ]
    return np.array(pairs, dtype=np.int64)


class _Nodes(typing.NamedTuple):
    """The nodes of a multiplier field, process-local (owned first, then ghosts)."""

    cells: np.ndarray  #: ``(num_cells, nodes per cell)`` local node of each cell's node
    side: np.ndarray  #: ``(num_nodes,)`` int8 side (-1, +1) of each node
    index_map: typing.Any  #: the nodes' index map (owned numbered contiguously)
    positions: typing.Callable  #: local nodes ``(k,)`` -> coordinates ``(k, gdim)``
    #: ``(k, 2)`` cell-local ``(node, vertex)``: each node off the vertices takes the mean
    #: of its linked vertices (:func:`_links`); empty for P1
    links: np.ndarray = np.zeros((0, 2), dtype=np.int64)


def vital_vertex_prolongation(
    cut: CutMesh, space, field: int = 2, interface: str | None = None
) -> MultiplierProlongation:
    """Multiplier prolongation from the vital vertices of the cut edges. Collective.

    Cut edges (end vertices on opposite sides of the interpolated level set) of
    the cut cells (a crack's: those it crosses and its tip cells, so that the tip
    cells' own vertices carry the multiplier too; not the cells cut ahead of its tips,
    where it would act on nothing) are gathered globally, vital vertices chosen
    identically on every process (:func:`xfem_contact.mechanics.lbb.vital_vertices`, by
    the rule of :data:`VITAL_RULE`; a crack's tip cell's edges crossed ahead of the tip
    left out), and
    each multiplier dof of a vertex on a cut edge expressed by
    :func:`xfem_contact.mechanics.lbb.prolongation`; a vertex of a cut cell on no cut
    edge takes the mean of the rows of its cut cells' vertices on one.

    For a P1 multiplier the nodes are the vertices. A P2 multiplier (vertices, edge
    nodes, and on quadrilaterals and hexahedra the face and cell centres) has its
    vertices restricted so, and every other node of a cut cell tied to the mean of its
    entity's vertices: the P1 (Q1) restricted space, written in the P2 (Q2) basis
    (richer relations measured in 2D: docs' stability page).

    Args:
        cut: The cut mesh.
        space: The :class:`~xfem_contact.fem.enrichment.EnrichedSpace`.
        field: The multiplier field of ``space.W``.
        interface: The interface whose cut cells carry the field (None: all).
    """
    mesh = cut.mesh
    rule = VITAL_RULE[mesh.topology.cell_type.name][cut.crack is not None]
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim, 1)
    mesh.topology.create_connectivity(1, 0)
    mesh.topology.create_connectivity(0, tdim)  # entities_to_geometry of the vertices
    c2e = mesh.topology.connectivity(tdim, 1)
    e2v = mesh.topology.connectivity(1, 0)
    vmap = mesh.topology.index_map(0)
    # Vertex sides from the level set at vertices (0 counts as +1)
    phi = cut.levelset.function
    V = phi.function_space
    c2v = mesh.topology.connectivity(tdim, 0)
    nv_cell = c2v.offsets[1] - c2v.offsets[0]
    cell_vertices = c2v.array.reshape(-1, nv_cell)
    vertex_phi = np.zeros(vmap.size_local + vmap.num_ghosts)
    vertex_phi[cell_vertices] = phi.x.array[V.dofmap.list[:, :nv_cell]]
    vertex_side = np.where(vertex_phi < 0.0, -1, 1).astype(np.int8)
    ne_cell = c2e.offsets[1] - c2e.offsets[0]
    cut_cells = cut.interface_cells(interface)
    if cut.crack is not None:  # not the cells cut ahead of a tip: the crack is not there
        cut_cells = cut_cells[np.isin(cut_cells, cut.cut_cells[cut.crack.kind != NONE])]
    edges = np.unique(c2e.array.reshape(-1, ne_cell)[cut_cells].ravel())
    ends = e2v.array.reshape(-1, 2)[edges]
    crossing = vertex_side[ends[:, 0]] != vertex_side[ends[:, 1]]
    edges, ends = edges[crossing], ends[crossing]
    if cut.crack is not None:
        ends = ends[~_extension_edges(cut, edges, ends, vertex_phi, cell_vertices, c2e)]
    degree = space.multiplier_degrees[field]
    if degree > 1:  # the vertices' nodes, and every other node tied to its vertices
        nodes, node_of_vertex = _lagrange_nodes(mesh, degree, cell_vertices, vertex_side)
        return _prolongation_of_nodes(
            mesh, space, field, nodes, node_of_vertex[ends], cut_cells, vertex_phi[ends], rule
        )
    gdim = mesh.geometry.dim

    def positions(vertices: np.ndarray) -> np.ndarray:
        nodes = dolfinx.mesh.entities_to_geometry(mesh, 0, vertices.astype(np.int32))
        return mesh.geometry.x[nodes.ravel(), :gdim]

    nodes = _Nodes(cell_vertices, vertex_side, vmap, positions)
    return _prolongation_of_nodes(
        mesh, space, field, nodes, ends, cut_cells, vertex_phi[ends], rule
    )


def _lagrange_nodes(mesh, degree: int, cell_vertices: np.ndarray, vertex_side: np.ndarray):
    """The nodes of the scalar Lagrange space of ``degree`` on ``mesh`` (the sides of the
    vertices' nodes ``vertex_side``, +1 elsewhere) and the node of each local vertex.
    Collective."""
    assert degree == 2, "MultiplierLaw admits degrees 1 and 2"
    S = dolfinx.fem.functionspace(mesh, ("Lagrange", degree))
    cells = S.dofmap.list
    node_of_vertex = np.full(vertex_side.size, -1, dtype=np.int64)
    node_of_vertex[cell_vertices] = cells[:, : cell_vertices.shape[1]]
    side = np.ones(S.dofmap.index_map.size_local + S.dofmap.index_map.num_ghosts, np.int8)
    side[node_of_vertex] = vertex_side
    x = S.tabulate_dof_coordinates()[:, : mesh.geometry.dim]
    links = _links(mesh.topology.cell_type)
    nodes = _Nodes(cells, side, S.dofmap.index_map, lambda k: x[k], links)
    return nodes, node_of_vertex


def _prolongation_of_nodes(
    mesh,
    space,
    field: int,
    nodes: _Nodes,
    ends: np.ndarray,
    cut_cells: np.ndarray,
    phi_ends: np.ndarray,
    rule: str,
) -> MultiplierProlongation:
    """The prolongation of ``field``'s dofs at ``nodes`` from the vital vertices of the
    cut edges ``ends`` (local node pairs of vertices, ``(m, 2)``; duplicates allowed, the
    level set at them ``phi_ends``) of ``cut_cells``, chosen by ``rule``
    (:data:`VITAL_RULE`); a vertex of a cut
    cell on no cut edge takes the mean of the rows of its cut cells' vertices on one, a
    node off the vertices that of its linked vertices (``nodes.links``). Collective."""
    comm, vmap = mesh.comm, nodes.index_map
    vertex_side = nodes.side
    nv_cell = nodes.cells.shape[1] - len({int(n) for n, _ in nodes.links})
    cell_vertices = nodes.cells[:, :nv_cell]
    global_ends = vmap.local_to_global(ends.ravel()).reshape(-1, 2)
    all_ends = np.concatenate(comm.allgather(global_ends))
    all_sides = np.concatenate(comm.allgather(vertex_side[ends]))
    # The greedy choice breaks ties by vertex label: label the vertices by position (the
    # global numbers depend on the partition: 2 ranks chose other vital vertices than 1)
    gdim = mesh.geometry.dim
    all_x = np.concatenate(comm.allgather(nodes.positions(ends.ravel())))
    all_x = all_x.reshape(-1, gdim)
    ids, first = np.unique(all_ends.ravel(), return_index=True)
    order = np.lexsort([np.round(all_x[first, k], 12) for k in reversed(range(gdim))])
    label = np.empty_like(order)
    label[order] = np.arange(order.size)
    by_position = label[np.searchsorted(ids, all_ends)]
    distances, near_share = None, None
    if rule != "covering":
        distances = np.concatenate(comm.allgather(np.abs(phi_ends).reshape(-1, 2)))
    if rule == "covering, near crossings":
        near_share = NEAR_SHARE
    vital = ids[order][lbb_module.vital_vertices(by_position, all_sides, distances, near_share)]
    rows, cols, vals, reduced = lbb_module.prolongation(all_ends, vital)
    # Vertices of cut cells on no cut edge (e.g. the far corner of a quadrilateral
    # cut near one vertex) take the mean of the prolongated rows of the cut-edge
    # vertices of their cut cells.
    cut_vertices = vmap.local_to_global(cell_vertices[cut_cells].ravel()).reshape(-1, nv_cell)
    cut_vertices = np.concatenate(comm.allgather(cut_vertices)).reshape(-1, nv_cell)
    on_edge = np.isin(cut_vertices, rows)
    pairs = {
        (f, nb)
        for cell, mask in zip(cut_vertices, on_edge, strict=True)
        for f in cell[~mask]
        for nb in cell[mask]
    }
    if pairs:
        extra_rows, extra_cols, extra_vals = [], [], []
        neighbours: dict[int, list[int]] = {}
        for f, nb in sorted(pairs):
            neighbours.setdefault(int(f), []).append(int(nb))
        for f, nbs in neighbours.items():
            for nb in nbs:
                sel = rows == nb
                extra_rows.append(np.full(sel.sum(), f))
                extra_cols.append(cols[sel])
                extra_vals.append(vals[sel] / len(nbs))
        rows = np.concatenate([rows, *extra_rows])
        cols = np.concatenate([cols, *extra_cols])
        vals = np.concatenate([vals, *extra_vals])
    rows, cols, vals = _linked_rows(comm, vmap, nodes, cut_cells, rows, cols, vals)
    # Multiplier dofs per node (the cell-local dof i sits at the cell's node i)
    cell_nodes = nodes.cells
    comps = {f: c for f, c, _ in space.multiplier_fields}[field]
    mdofs = space.W.sub(field).dofmap.list.reshape(cell_nodes.shape[0], cell_nodes.shape[1], comps)
    dof_of_vertex = np.full((vertex_side.size, comps), -1, dtype=np.int64)
    dof_of_vertex[cell_nodes] = mdofs
    # Reduced multiplier unknowns, numbered rank-major: each process owns the
    # unknowns of the vital vertices it owns, in increasing global id.
    owned_global = vmap.local_to_global(np.arange(vmap.size_local, dtype=np.int32))
    vital_owned = reduced[np.isin(reduced, owned_global)]
    rank_major = np.concatenate(comm.allgather(vital_owned))
    position = np.empty(rank_major.size, dtype=np.int64)
    position[np.searchsorted(reduced, rank_major)] = np.arange(rank_major.size)
    # Prolongation rows of owned vertices
    keep = np.isin(rows, owned_global)
    row_vertices, inverse = np.unique(rows[keep], return_inverse=True)
    local = row_vertices - vmap.local_range[0]  # owned vertices are numbered contiguously
    nrow = row_vertices.size
    dofs = np.concatenate([dof_of_vertex[local, c] for c in range(comps)])
    prow = np.concatenate([inverse.ravel() + c * nrow for c in range(comps)])
    pcol = np.concatenate([position[cols[keep]] * comps + c for c in range(comps)])
    pval = np.tile(vals[keep], comps)
    return MultiplierProlongation(dofs, prow, pcol, pval, num_owned=vital_owned.size * comps)


def _linked_rows(comm, vmap, nodes: _Nodes, cut_cells, rows, cols, vals):
    """``(rows, cols, vals)`` with, for each node off the vertices of the cut cells, the
    mean of the rows of its linked vertices (``nodes.links``; global node ids). Collective."""
    if nodes.links.size == 0:
        return rows, cols, vals
    linked = vmap.local_to_global(nodes.cells[cut_cells][:, nodes.links].ravel())
    linked = np.unique(np.concatenate(comm.allgather(linked)).reshape(-1, 2), axis=0)
    node, count = np.unique(linked[:, 0], return_counts=True)
    weight = 1.0 / count[np.searchsorted(node, linked[:, 0])]
    order = np.argsort(rows, kind="stable")
    start = np.searchsorted(rows[order], linked[:, 1], side="left")
    stop = np.searchsorted(rows[order], linked[:, 1], side="right")
    take = [order[i:j] for i, j in zip(start, stop, strict=True)]
    extra_rows = np.concatenate(
        [np.full(t.size, n) for t, n in zip(take, linked[:, 0], strict=True)]
    )
    extra_cols = np.concatenate([cols[t] for t in take])
    extra_vals = np.concatenate([vals[t] * w for t, w in zip(take, weight, strict=True)])
    return (
        np.concatenate([rows, extra_rows]),
        np.concatenate([cols, extra_cols]),
        np.concatenate([vals, extra_vals]),
    )


def combine_prolongations(
    prolongations: list[MultiplierProlongation], comm: MPI.Comm
) -> MultiplierProlongation | None:
    """One prolongation for several multiplier fields. Collective.

    Each input numbers its reduced unknowns rank-major (the unknowns owned by rank 0
    first); the result numbers, on each rank, the unknowns of the first input, then
    of the second, ..., keeping the rank-major order across ranks.
    """
    if not prolongations:
        return None
    if len(prolongations) == 1:
        return prolongations[0]
    owned = np.array([comm.allgather(p.num_owned) for p in prolongations])  # (inputs, ranks)
    rank_total = owned.sum(axis=0)
    rank_start = np.concatenate([[0], np.cumsum(rank_total)[:-1]])
    within = np.concatenate([np.zeros((1, owned.shape[1]), int), np.cumsum(owned, 0)[:-1]])
    dofs, rows, cols, vals, row0 = [], [], [], [], 0
    for k, p in enumerate(prolongations):
        starts = np.concatenate([[0], np.cumsum(owned[k])])
        owner = np.searchsorted(starts, p.cols, side="right") - 1
        cols.append(rank_start[owner] + within[k, owner] + p.cols - starts[owner])
        dofs.append(p.dofs)
        rows.append(p.rows + row0)
        vals.append(p.vals)
        row0 += p.dofs.size
    return MultiplierProlongation(
        np.concatenate(dofs),
        np.concatenate(rows),
        np.concatenate(cols),
        np.concatenate(vals),
        num_owned=int(owned[:, comm.rank].sum()),
    )


def _extension_edges(cut: CutMesh, edges, ends, vertex_phi, cell_vertices, c2e) -> np.ndarray:
    """Mask of the cut ``edges`` (local indices, ``(m,)``; their end vertices ``ends``,
    ``(m, 2)``) to leave out of the vital-vertex choice: the edges of a tip cell that the
    crack's zero line crosses ahead of the tip (``psi > 0`` at the crossing, ``psi`` the
    crack's tangential level set, a signed distance along the crack, interpolated
    linearly along the edge). No lip is there: a vital vertex of such an edge would
    carry an unknown seen only by the tip cell's piece of the crack, the nearer to the
    tip the less (the inf-sup constant's weakest mode sat on such vertices). An edge the
    crack itself crosses keeps its vertex. Not collective."""
    psi = cut.crack.tangent.function
    vertex_psi = np.zeros_like(vertex_phi)
    vertex_psi[cell_vertices] = psi.x.array[
        psi.function_space.dofmap.list[:, : cell_vertices.shape[1]]
    ]
    p, s = vertex_phi[ends], vertex_psi[ends]
    t = p[:, 0] / (p[:, 0] - p[:, 1])
    crossing_psi = s[:, 0] + t * (s[:, 1] - s[:, 0])
    num_edges = int(c2e.array.max(initial=-1)) + 1
    ne_cell = c2e.offsets[1] - c2e.offsets[0]
    tips = cut.cut_cells[cut.crack.kind == TIP]
    in_tip_cell = np.zeros(num_edges, dtype=bool)
    in_tip_cell[c2e.array.reshape(-1, ne_cell)[tips].ravel()] = True
    return in_tip_cell[edges] & (crossing_psi > 0.0)
