"""Cell aggregation: the dofs of badly cut cells extended from a well cut neighbour.

Aggregated unfitted finite elements (Badia, Verdugo and Martín, CMAME 336, 2018): a cut
cell whose part on side ``s`` is less than ``threshold`` of its area is *badly cut* for
side ``s``. Each badly cut cell is attached to a *root*: a cell of side ``s`` that is not
badly cut, reached from it in the fewest facet steps through cells side ``s`` touches
(nearest root centroid among those at that distance). A dof of side ``s``'s displacement
whose support on that side holds badly cut cells only is not an unknown: it takes the
polynomial of one root extended to its node,

    u_c = sum_j N_j^root(X_c) u_j,      X_c = F_root^-1(x_c),

over the root cell's dofs ``j`` of the same field and component (``N_j`` the Lagrange
basis on the reference cell, ``F_root`` the root's geometry map, pulled back by Newton's
method). Its root is chosen among the roots of its badly cut cells and their well cut
facet neighbours: the one whose reference cell ``X_c`` lies least outside of (the
shortest extrapolation; ties by position). Every remaining unknown has a well cut cell
in its support, so the scaled operator's conditioning does not depend on where the
interface cuts.

A multiplier field (Lagrange on the cut cells of its interface) is aggregated the same
way, a cell's interface measure taking the place of its side area: a cell carrying the
interface is badly cut for the multiplier when the interface's measure in it is below
``threshold`` times ``|K|^((d-1)/d)`` (``|K|`` the cell's measure, ``d`` its dimension;
a straight cut through the middle of a square cell measures 1). A multiplier dof whose
interface cells are all badly cut takes a root's multiplier polynomial, the root found
through the cells that carry the interface. Multiplier dofs that a law's multiplier
prolongation (the LBB restriction) already replaces stay its own.

A crack's cells are aggregated only where the crack crosses them: its tip cells and the
cells cut by its extension ahead of a tip are never badly cut (their nodes are tied: one
unknown for both sides, whatever a side's share), and tied dofs are never constrained.
Nor are they roots or on the way to one: their side polynomial is the other side's too,
and extended to a badly cut cell behind the tip it would give both sides one field there.
A crossed cell next to a tip cell is aggregated like any other, its untied dofs extended
and its tied ones kept: its sliver on one side leaves that side's untied dofs with
nothing else in their support. The branch unknowns are unchanged (gathered ones take a
ramp of the displacement degree, :func:`~xfem_contact.fem.tip_dofs.ramp_degree`): in
the tip zone only the side fields of badly cut cells are extended.

All arrays here are process-local unless stated; the functions that gather are
collective. The cells and roots are gathered on every process (interface-sized data).
"""

from __future__ import annotations

import logging
import typing

import basix
import dolfinx.fem
import dolfinx.la
import numpy as np
import numpy.typing as npt
import ufl
from mpi4py import MPI

from xfem_contact.geometry.crack import CROSSED

if typing.TYPE_CHECKING:
    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.fem.enrichment import EnrichedSpace

_logger = logging.getLogger(__name__)
#: Newton steps of the pull-back of a node into its root cell (bilinear maps: 2-3 suffice)
_PULL_BACK_STEPS = 20
#: Codes of a cell for one side: not touched by the side, well cut (or uncut), badly cut,
#: and touched but never a root nor on the way to one (a crack's tip cells and the cells
#: its extension cuts: their two sides share their dofs)
_OUTSIDE, _WELL, _BAD, _SHARED = 0, 1, 2, 3


class Aggregation(typing.NamedTuple):
    """The constrained dofs of this process and their rows in the root cells' dofs.

    Attributes:
        dofs: Owned dofs of ``W`` (local indices) that are not unknowns, ``(m,)``.
        rows: Index into ``dofs`` of each entry, ``(nnz,)``.
        sources: Global dof of ``W`` (of a root cell, an unknown) of each entry, ``(nnz,)``.
        vals: Entries ``N_j^root(X_c)``, ``(nnz,)``.
    """

    dofs: npt.NDArray[np.int64]
    rows: npt.NDArray[np.int64]
    sources: npt.NDArray[np.int64]
    vals: npt.NDArray[np.float64]

    def without(self, fixed: npt.NDArray[np.int64]) -> Aggregation:
        """The same with the dofs ``fixed`` (local dofs of ``W``, e.g. Dirichlet ones)
        left as unknowns."""
        keep = ~np.isin(self.dofs, fixed)
        position = np.cumsum(keep) - 1
        entries = keep[self.rows]
        return Aggregation(
            self.dofs[keep],
            position[self.rows[entries]],
            self.sources[entries],
            self.vals[entries],
        )

    def split_sources(self, prescribed: npt.NDArray[np.int64]) -> tuple[Aggregation, Aggregation]:
        """The entries whose source is not in ``prescribed`` (global dofs of ``W``, e.g.
        all processes' Dirichlet ones) and those whose source is: the same constrained
        dofs in both, ``u_c = sum_j N_j u_j`` split into its unknown and its prescribed
        part."""
        reads = np.isin(self.sources, prescribed)
        return (
            Aggregation(self.dofs, self.rows[~reads], self.sources[~reads], self.vals[~reads]),
            Aggregation(self.dofs, self.rows[reads], self.sources[reads], self.vals[reads]),
        )


def check_threshold(threshold: float | None) -> None:
    """Refuse an aggregation threshold outside ``(0, 1)`` (None: off)."""
    if threshold is not None and not (isinstance(threshold, float | int) and 0 < threshold < 1):
        raise ValueError(
            f"aggregation must be None (off) or a side volume fraction in (0, 1), got {threshold!r}"
        )


def cell_areas(cut: CutMesh) -> npt.NDArray[np.float64]:
    """Areas of the owned cells (m^2 in 2D), shape ``(num_owned,)``. Collective."""
    mesh = cut.mesh
    V0 = dolfinx.fem.functionspace(mesh, ("DG", 0))
    v = ufl.TestFunction(V0)
    vec = dolfinx.fem.assemble_vector(dolfinx.fem.form(v * ufl.dx))
    return vec.array[V0.dofmap.list[: cut.cell_sides.size, 0]]


def abs_det_at(cut: CutMesh, rules) -> npt.NDArray[np.float64]:
    """|det J| at every point of ``rules`` (points of cut cells), shape ``(N,)``."""
    J = cut.maps.jacobian(cut.cut_cells[rules.point_rows], rules.points)
    return np.abs(np.linalg.det(J))


def side_areas(cut: CutMesh, side: int, areas: npt.NDArray[np.float64]) -> np.ndarray:
    """Area of each owned cell on ``side``: ``areas`` on that side's uncut cells, 0 on
    the other side's, the cut part of cut cells. Shape ``(num_owned,)``."""
    side_area = np.where(cut.cell_sides == side, areas, 0.0)
    rules = cut.side_rules(side)
    side_area[cut.cut_cells] = rules.sums(rules.weights * abs_det_at(cut, rules))
    return side_area


def aggregate(space: EnrichedSpace, threshold: float, active: npt.NDArray[np.bool_]) -> Aggregation:
    """The constrained dofs of both displacement fields and of the multiplier fields of
    ``space`` (module docstring). Collective.

    Args:
        space: The enriched space (its ties, branch support and marks set).
        threshold: Side volume fraction below which a cut cell is badly cut, in (0, 1).
        active: Active flags of the local dofs of ``W`` (only active, untied dofs are
            constrained).
    """
    cut = space.cut
    areas = cell_areas(cut)
    eligible = _eligible_cells(space)
    codes = [
        (field, _cell_codes(cut, side, threshold, areas, eligible))
        for field, side in ((0, -1), (1, 1))
    ]
    codes += [
        (field, _interface_codes(cut, name, threshold, areas, eligible))
        for field, _, name in space.multiplier_fields
    ]
    parts = [_field_aggregation(space, field, c, active) for field, c in codes]
    offsets = np.cumsum([0] + [p.dofs.size for p in parts])
    return Aggregation(
        np.concatenate([p.dofs for p in parts]),
        np.concatenate([p.rows + o for p, o in zip(parts, offsets, strict=False)]),
        np.concatenate([p.sources for p in parts]),
        np.concatenate([p.vals for p in parts]),
    )


def _eligible_cells(space: EnrichedSpace) -> np.ndarray:
    """Per owned cell: whether it may be badly cut (a cut cell; with a crack, one it
    crosses, with or without tied dofs). Not collective."""
    cut = space.cut
    eligible = np.zeros(cut.cell_sides.size, dtype=bool)
    eligible[cut.cut_cells] = True
    if cut.crack is not None:
        eligible[cut.cut_cells[cut.crack.kind != CROSSED]] = False
    return eligible


def _cell_codes(cut, side, threshold, areas, eligible) -> npt.NDArray[np.float64]:
    """Per owned cell: :data:`_OUTSIDE`, :data:`_WELL`, :data:`_BAD` or :data:`_SHARED`
    for ``side``."""
    fraction = side_areas(cut, side, areas) / areas
    touched = (cut.cell_sides == side) | (cut.cell_sides == 0)
    codes = np.where(touched, _WELL, _OUTSIDE).astype(np.float64)
    codes[touched & eligible & (fraction < threshold)] = _BAD
    if cut.crack is not None:
        codes[cut.cut_cells[cut.crack.kind != CROSSED]] = _SHARED
    return codes


def _interface_codes(cut, name, threshold, areas, eligible) -> npt.NDArray[np.float64]:
    """Per owned cell: :data:`_OUTSIDE` (no part of interface ``name``), :data:`_WELL`
    or :data:`_BAD` for that interface's multiplier (module docstring)."""
    rules = cut.interface_rules_of(name)
    measure = np.zeros(cut.cell_sides.size)
    measure[cut.cut_cells] = rules.sums(rules.weights * abs_det_at(cut, rules))
    if cut.crack is not None:  # a crack's multipliers: the crossed cells only
        measure[cut.cut_cells[cut.crack.kind != CROSSED]] = 0.0
    tdim = cut.mesh.topology.dim
    fraction = measure / areas ** ((tdim - 1) / tdim)
    # a piece along a line of the reference coordinates leaves vertex modes without a
    # trace, which the law's extension term fixes on the cell itself: extended from a
    # root, they would carry that strong term onto the root's multiplier
    aligned = np.zeros(cut.cell_sides.size, dtype=bool)
    aligned[cut.cut_cells[cut.trace_nullity(name) >= 2]] = True
    codes = np.where(measure > 0.0, _WELL, _OUTSIDE).astype(np.float64)
    codes[(measure > 0.0) & eligible & ~aligned & (fraction < threshold)] = _BAD
    return codes


def _field_degree(space, field: int) -> int:
    """The Lagrange degree of field ``field`` of ``space.W`` (a displacement or a
    multiplier)."""
    return space.multiplier_degrees.get(field, space.degree)


def _field_aggregation(space, field, owned_codes, active) -> Aggregation:
    """The constrained dofs of field ``field`` for the cell codes ``owned_codes`` (per
    owned cell). Collective."""
    cut = space.cut
    mesh = cut.mesh
    comm = mesh.comm
    tdim, gdim = mesh.topology.dim, mesh.geometry.dim
    cell_map = mesh.topology.index_map(tdim)
    n_owned = cell_map.size_local
    codes = _ghosted_cell_values(mesh, owned_codes)
    bad = np.flatnonzero(codes[:n_owned] == _BAD).astype(np.int32)
    well = np.flatnonzero(np.isin(codes[:n_owned], (_WELL, _SHARED))).astype(np.int32)
    W = space.W
    n_dofs = W.dofmap.index_map.size_local
    of_field = np.zeros(active.size, dtype=bool)
    of_field[W.sub(field).dofmap.list.ravel()] = True
    # owned and ghost dofs of the field with badly cut cells alone in their support
    candidate = active & ~(space._mark(field, well) > 0) & of_field
    constrained = candidate.copy()  # owned ones, untied
    constrained[n_dofs:] = False
    constrained[space.ties.ravel()] = False
    if comm.allreduce(int(bad.size), op=MPI.SUM) == 0:
        return _empty()
    # Every process: the badly cut cells, their neighbours and roots
    centroids = _centroids(mesh)
    table = _gather_bad_cells(mesh, bad, codes, centroids)
    roots = _roots(table)
    # candidate roots of a badly cut cell: its root and its well cut facet neighbours
    candidates = {cell: {root} for cell, root in roots.items()}
    for cell, other in table.neighbours.tolist():
        if table.codes[other] == _WELL and cell in candidates:
            candidates[cell].add(other)
    # The candidates' geometry and dofs, from their owners
    root_ids = np.unique(np.array([r for c in candidates.values() for r in c], dtype=np.int64))
    root_table = _gather_roots(space, field, root_ids)
    # Each constrained owned dof: the root nearest its node among its badly cut cells'
    dofmap = W.sub(field).dofmap.list
    degree = _field_degree(space, field)
    element = basix.ufl.element("Lagrange", mesh.basix_cell(), degree).basix_element
    # (cells, nodes, gdim), also for a process without badly cut cells
    lattice = cut.maps.push_forward_lattice(bad, element.points)
    nodes = lattice.reshape(bad.size, element.points.shape[0], gdim)
    bs = dofmap.shape[1] // element.dim  # the field's components
    mine = candidate[dofmap[bad].ravel()]
    local_dof = dofmap[bad].ravel()[mine]
    owner_cell = cell_map.local_to_global(np.repeat(bad, dofmap.shape[1]))[mine]
    node = np.repeat(nodes, bs, axis=1).reshape(-1, gdim)[mine]
    # a dof's cells are all badly cut, owned by some process: gather its (dof, root) pairs
    pairs = [(k, r) for k, c in enumerate(owner_cell) for r in sorted(candidates.get(int(c), ()))]
    pick = np.array([k for k, _ in pairs], dtype=np.int64)
    root = np.array([r for _, r in pairs], dtype=np.int64)
    element = cut.maps.coordinate_element
    choice = _nearest_roots(
        comm, W, local_dof[pick], root, node[pick], element, root_table, constrained
    )
    dofs, cell_root, x = choice
    if dofs.size:
        rows, sources, vals = _extension_rows(space, dofs, cell_root, x, root_table, field)
    else:
        rows, sources, vals = _empty()[1:]
    unreached = comm.allreduce(int(np.sum(constrained[:n_dofs])) - int(dofs.size), op=MPI.SUM)
    if unreached:
        _logger.warning(
            "aggregation: %d dofs of field %d lie in badly cut cells no root reaches; "
            "they stay unknowns",
            unreached,
            field,
        )
    return Aggregation(dofs.astype(np.int64), rows, sources, vals)


def _empty() -> Aggregation:
    z = np.zeros(0, dtype=np.int64)
    return Aggregation(z, z, z, np.zeros(0))


def _ghosted_cell_values(mesh, owned: np.ndarray) -> np.ndarray:
    """``owned`` (per owned cell) extended to the ghost cells. Collective."""
    imap = mesh.topology.index_map(mesh.topology.dim)
    vec = dolfinx.la.vector(imap, 1)
    vec.array[: owned.size] = owned
    vec.scatter_forward()
    return vec.array.copy()


def _centroids(mesh) -> np.ndarray:
    """Mean of the geometry nodes of every local cell, shape ``(cells, gdim)``."""
    gdim = mesh.geometry.dim
    return mesh.geometry.x[mesh.geometry.dofmaps[0], :gdim].mean(axis=1)


class _BadCells(typing.NamedTuple):
    """The badly cut cells of all processes and their facet neighbours (global ids)."""

    ids: np.ndarray  # (b,) global cell ids
    centroids: np.ndarray  # (b, gdim)
    neighbours: np.ndarray  # (k, 2): (badly cut cell id, neighbour id)
    codes: dict  # neighbour id -> code
    neighbour_centroids: dict  # neighbour id -> centroid


def _gather_bad_cells(mesh, bad, codes, centroids) -> _BadCells:
    """Gather the badly cut cells and their neighbours on every process. Collective."""
    comm = mesh.comm
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim, tdim - 1)
    mesh.topology.create_connectivity(tdim - 1, tdim)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    cell_map = mesh.topology.index_map(tdim)
    pairs = []
    for cell in bad:
        for facet in c2f.links(cell):
            pairs += [(cell, other) for other in f2c.links(facet) if other != cell]
    pairs = np.array(pairs, dtype=np.int32).reshape(-1, 2)
    to_global = cell_map.local_to_global
    local = (
        to_global(bad),
        centroids[bad],
        np.stack([to_global(pairs[:, 0]), to_global(pairs[:, 1])], axis=1),
        codes[pairs[:, 1]],
        centroids[pairs[:, 1]],
    )
    parts = comm.allgather(local)
    ids = np.concatenate([p[0] for p in parts])
    neighbours = np.concatenate([p[2] for p in parts]).reshape(-1, 2)
    neighbour_codes = np.concatenate([p[3] for p in parts])
    neighbour_centroids = np.concatenate([p[4] for p in parts])
    return _BadCells(
        ids,
        np.concatenate([p[1] for p in parts]),
        neighbours,
        dict(zip(neighbours[:, 1].tolist(), neighbour_codes.tolist(), strict=True)),
        dict(zip(neighbours[:, 1].tolist(), map(tuple, neighbour_centroids), strict=True)),
    )


def _roots(table: _BadCells) -> dict[int, int]:
    """The root of each badly cut cell (global ids), the same on every process: layer
    by layer from the well cut cells, each cell taking, among its neighbours' roots of
    the previous layers, the one whose centroid is nearest (ties by position)."""
    centroid = dict(table.neighbour_centroids)
    centroid.update(zip(table.ids.tolist(), map(tuple, table.centroids), strict=True))
    root = {c: c for c, code in table.codes.items() if code == _WELL}
    adjacent: dict[int, list[int]] = {}
    for cell, other in table.neighbours.tolist():
        if table.codes[other] in (_WELL, _BAD):
            adjacent.setdefault(cell, []).append(other)
    pending = set(table.ids.tolist())
    while pending:
        layer = {}
        for cell in pending:
            candidates = {root[o] for o in adjacent.get(cell, []) if o in root}
            if candidates:
                c = np.asarray(centroid[cell])
                layer[cell] = min(
                    candidates,
                    key=lambda r: (float(np.linalg.norm(np.asarray(centroid[r]) - c)), centroid[r]),
                )
        if not layer:
            break  # a cluster of badly cut cells with no well cut neighbour
        root.update(layer)
        pending -= set(layer)
    return {cell: root[cell] for cell in table.ids.tolist() if cell in root}


class _Roots(typing.NamedTuple):
    """The root cells of all processes: geometry nodes and field dofs (global)."""

    index: dict  # root id -> row
    nodes: np.ndarray  # (r, geometry nodes, gdim)
    dofs: np.ndarray  # (r, field dofs) global dofs of W


def _gather_roots(space, field, root_ids) -> _Roots:
    """Geometry nodes and global field dofs of the roots, from their owners. Collective."""
    mesh = space.cut.mesh
    tdim, gdim = mesh.topology.dim, mesh.geometry.dim
    cell_map = mesh.topology.index_map(tdim)
    owned_ids = cell_map.local_to_global(np.arange(cell_map.size_local, dtype=np.int32))
    mine = np.flatnonzero(np.isin(owned_ids, root_ids)).astype(np.int32)
    nodes = mesh.geometry.x[mesh.geometry.dofmaps[0][mine], :gdim]
    dofmap = space.W.sub(field).dofmap.list[mine]
    dofs = space.W.dofmap.index_map.local_to_global(dofmap.ravel()).reshape(dofmap.shape)
    parts = mesh.comm.allgather((owned_ids[mine], nodes, dofs))
    ids = np.concatenate([p[0] for p in parts])
    return _Roots(
        {int(c): k for k, c in enumerate(ids)},
        np.concatenate([p[1] for p in parts]),
        np.concatenate([p[2] for p in parts]),
    )


def _nearest_roots(comm, W, local_dof, root, node, element, root_table, constrained):
    """For each owned constrained dof: among its candidate roots (``root``, one per
    entry, the dof ``local_dof`` at ``node`` repeated per candidate), the one its node
    lies nearest to in reference coordinates (the distance outside the reference cell:
    the least extrapolation; ties by position), and its node. Collective: the candidates
    of every process are gathered, since a dof's cells may be owned elsewhere."""
    imap = W.dofmap.index_map
    global_dof = imap.local_to_global(local_dof.astype(np.int32))
    rows = np.array([root_table.index[int(r)] for r in root], dtype=np.int64)
    distance = np.zeros(root.size)
    if root.size:
        X = _pull_back(element, root_table.nodes[rows], node)
        distance = _outside(element.cell_type, X)
    parts = comm.allgather((global_dof, root, distance, node))
    g = np.concatenate([p[0] for p in parts])
    r = np.concatenate([p[1] for p in parts])
    d = np.concatenate([p[2] for p in parts])
    x = np.concatenate([p[3] for p in parts]).reshape(-1, node.shape[1])
    root_centroid = root_table.nodes[[root_table.index[int(c)] for c in r]].mean(axis=1)
    keys = [root_centroid[:, k] for k in reversed(range(root_centroid.shape[1]))]
    order = np.lexsort([*keys, d, g])  # by dof, then distance, then root position
    g, r, x = g[order], r[order], x[order]
    first = np.ones(g.size, dtype=bool)
    first[1:] = g[1:] != g[:-1]
    g, r, x = g[first], r[first], x[first]
    start = imap.local_range[0]
    owned = (g >= start) & (g < imap.local_range[1])
    local = (g[owned] - start).astype(np.int64)
    keep = constrained[local]
    return local[keep], r[owned][keep], x[owned][keep]


def _extension_rows(space, dofs, roots, x, root_table, field):
    """Rows ``u_c = sum_j N_j^root(X_c) u_j`` of the dofs ``dofs`` (owned, local) whose
    nodes are ``x`` ``(m, gdim)`` in the roots ``roots`` (global ids)."""
    mesh = space.cut.mesh
    rows_of_root = np.array([root_table.index[int(r)] for r in roots], dtype=np.int64)
    X = _pull_back(space.cut.maps.coordinate_element, root_table.nodes[rows_of_root], x)
    degree = _field_degree(space, field)
    element = basix.ufl.element("Lagrange", mesh.basix_cell(), degree).basix_element
    N = element.tabulate(0, X)[0, :, :, 0]  # (m, nodes)
    # the component of each constrained dof: its place in a cell's field dofs (node-major)
    dofmap = space.W.sub(field).dofmap.list
    bs = dofmap.shape[1] // element.dim
    imap = space.W.dofmap.index_map
    component = np.full(imap.size_local + imap.num_ghosts, -1, dtype=np.int64)
    component[dofmap.ravel()] = np.tile(np.arange(dofmap.shape[1]) % bs, dofmap.shape[0])
    comp = component[dofs]
    sources = root_table.dofs[rows_of_root].reshape(dofs.size, -1, bs)
    sources = sources[np.arange(dofs.size), :, comp]  # (m, nodes)
    rows = np.repeat(np.arange(dofs.size, dtype=np.int64), N.shape[1])
    return rows, sources.ravel().astype(np.int64), N.ravel()


def _outside(cell_type, X) -> np.ndarray:
    """How far each reference point of ``X`` ``(m, tdim)`` lies outside the reference
    cell (max norm; 0 inside), shape ``(m,)``."""
    if cell_type in (basix.CellType.triangle, basix.CellType.tetrahedron):
        beyond = np.concatenate([-X, X.sum(axis=1, keepdims=True) - 1.0], axis=1)
    else:
        beyond = np.concatenate([-X, X - 1.0], axis=1)
    return np.maximum(beyond.max(axis=1), 0.0)


def _pull_back(element, nodes, x) -> np.ndarray:
    """Reference points ``X`` with ``F(X) = x`` for the maps of geometry ``nodes``
    ``(m, geometry nodes, gdim)``, by Newton's method from the reference centroid
    (exact after one step for affine maps). Shape ``(m, tdim)``."""
    X = np.tile(basix.geometry(element.cell_type).mean(axis=0), (x.shape[0], 1))
    for _ in range(_PULL_BACK_STEPS):
        tab = element.tabulate(1, X)[:, :, :, 0]  # (1 + tdim, m, geometry nodes)
        F = np.einsum("pi,pid->pd", tab[0], nodes)
        J = np.einsum("kpi,pid->pdk", tab[1:], nodes)
        step = np.linalg.solve(J, (x - F)[..., None])[..., 0]
        X += step
        if np.abs(step).max(initial=0.0) < 1e-14:
            break
    return X
