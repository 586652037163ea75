"""The prolongation ``R`` from a reduced space to the full mixed space.

Full dofs ``x = R y``: ``R`` selects the active dofs of an
:class:`~xfem_contact.fem.enrichment.EnrichedSpace` (identity columns; a crack's tied
dofs share their column) and, where a
multiplier prolongation is given (LBB restriction, :mod:`xfem_contact.mechanics.lbb`),
expresses multiplier dofs as combinations of fewer reduced unknowns. Both solvers
use it: the linear solves (:mod:`xfem_contact.solvers.linear`) solve
``R^T A R y = R^T b``, Newton (:mod:`xfem_contact.solvers.newton`) solves
``R^T J R dy = -R^T F``.
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.fem.tip_dofs import branch_groups


class MultiplierProlongation:
    """Multiplier dofs as combinations of reduced unknowns (local rows, global columns).

    The process-local part of a sparse ``(m, n_mult)`` matrix in coordinate form:
    row ``k`` expresses the multiplier dof ``dofs[k]`` of ``W`` in the
    ``n_mult`` (global) reduced multiplier unknowns, of which this process owns
    ``num_owned`` (consecutive, in rank order). Not collective.

    Attributes:
        dofs: Local (owned) multiplier dofs of ``W`` the prolongation replaces, ``(m,)``.
        rows: Index into ``dofs`` of each entry, ``(nnz,)``.
        cols: Global reduced-unknown index (0-based among the multiplier unknowns), ``(nnz,)``.
        vals: Entries, ``(nnz,)``.
        num_owned: Reduced multiplier unknowns owned by this process.
    """

    def __init__(self, dofs, rows, cols, vals, num_owned: int):
        self.dofs = np.asarray(dofs, dtype=np.int64)
        self.rows = np.asarray(rows, dtype=np.int64)
        self.cols = np.asarray(cols, dtype=np.int64)
        self.vals = np.asarray(vals, dtype=np.float64)
        self.num_owned = int(num_owned)


def prolongation_matrix(
    space: EnrichedSpace,
    prolongation: MultiplierProlongation | None = None,
    fixed: np.ndarray | None = None,
) -> PETSc.Mat:
    """Build the prolongation ``R`` with ``x = R y``. Collective.

    Columns (reduced unknowns) are numbered process by process: on each, first
    its owned active dofs in increasing order (an identity column each), then
    its ``prolongation.num_owned`` multiplier unknowns.

    Args:
        space: The enriched space; its active owned dofs are kept, but those of its
            :attr:`~xfem_contact.fem.enrichment.EnrichedSpace.aggregation` (with cell
            aggregation), whose rows are their roots' dofs' columns.
        prolongation: Optional multiplier prolongation; its dofs are removed
            from the identity part and replaced by its entries.
        fixed: Local dofs of ``W`` that stay unknowns whatever the aggregation (the
            Dirichlet ones: their values are imposed), or None. An aggregated dof whose
            extension reads some of them keeps, in ``R``, its entries on the others:
            its prescribed part is the offset of :func:`prescribed_extension`.

    Returns:
        ``R`` as a PETSc AIJ matrix of global shape ``(dim W, n_reduced)``;
        its rows are laid out as the dofs of ``space.W`` (owned dofs of each
        process), its columns as the reduced unknowns above. The caller
        destroys it.
    """
    imap, bs = space.W.dofmap.index_map, space.W.dofmap.index_map_bs
    comm = imap.comm
    n_owned = imap.size_local * bs
    active = space.active[:n_owned].copy()
    ties = space.ties
    active[ties[:, 1]] = False  # a follower is its kept dof's column
    if prolongation is not None:
        active[prolongation.dofs] = False
    aggregation = _aggregation_parts(space, prolongation, fixed)[0]
    if aggregation is not None:
        active[aggregation.dofs] = False
    leaders = _gathered_leaders(space, active)  # global leader dof per follower, or None
    if leaders is not None:
        followers = np.flatnonzero(leaders >= 0)
        active[followers] = False
    selected = np.flatnonzero(active)
    n_sel = selected.size
    n_mult = 0 if prolongation is None else prolongation.num_owned
    n_red = n_sel + n_mult
    offset = comm.exscan(n_red, op=MPI.SUM) or 0
    sel_offset = offset
    mult_offset = offset + n_sel
    # Global column of multiplier unknown j: its owner's mult_offset + local position.
    owners_offsets = comm.allgather((mult_offset, n_mult))
    entries_rows = [selected]
    entries_cols = [np.arange(n_sel) + sel_offset]
    entries_vals = [np.ones(n_sel)]
    if ties.size:
        entries_rows.append(ties[:, 1])
        entries_cols.append(np.searchsorted(selected, ties[:, 0]) + sel_offset)
        entries_vals.append(np.ones(len(ties)))
    if prolongation is not None and prolongation.vals.size:
        starts = np.cumsum([0] + [n for _, n in owners_offsets])
        global_mult = np.array([o for o, _ in owners_offsets])
        owner = np.searchsorted(starts, prolongation.cols, side="right") - 1
        entries_rows.append(prolongation.dofs[prolongation.rows])
        entries_cols.append(global_mult[owner] + prolongation.cols - starts[owner])
        entries_vals.append(prolongation.vals)
    column = np.full(n_owned, -1, dtype=np.int64)
    column[selected] = np.arange(n_sel) + sel_offset
    column[ties[:, 1]] = column[ties[:, 0]]
    if leaders is not None:
        wanted = leaders[followers]
        entries_rows.append(followers)
        entries_cols.append(_global_lookup(column, imap.local_range[0] * bs, wanted, comm))
        entries_vals.append(np.ones(followers.size))
    if aggregation is not None:
        source = _global_lookup(column, imap.local_range[0] * bs, aggregation.sources, comm)
        known = source >= 0  # an inactive source dof is 0
        entries_rows.append(aggregation.dofs[aggregation.rows[known]])
        entries_cols.append(source[known])
        entries_vals.append(aggregation.vals[known])
    rows = np.concatenate(entries_rows)
    cols = np.concatenate(entries_cols)
    vals = np.concatenate(entries_vals)
    n_cols = comm.allreduce(n_red, op=MPI.SUM)  # on every process (ties may be on some)
    if len(entries_rows) > 1:  # sum repeated (row, column) pairs; sort by row, column
        keys, inverse = np.unique(rows * n_cols + cols, return_inverse=True)
        rows, cols = np.divmod(keys, n_cols)
        vals = np.bincount(inverse, weights=vals, minlength=keys.size)
    indptr = np.searchsorted(rows, np.arange(n_owned + 1)).astype(PETSc.IntType)
    R = PETSc.Mat().createAIJ(((n_owned, PETSc.DETERMINE), (n_red, PETSc.DETERMINE)), comm=comm)
    R.setPreallocationCSR((indptr, cols.astype(PETSc.IntType), vals))
    R.assemble()
    return R


def prescribed_extension(
    space: EnrichedSpace,
    prolongation: MultiplierProlongation | None = None,
    fixed: np.ndarray | None = None,
) -> PETSc.Mat | None:
    """The prescribed part ``E`` of the aggregated dofs' extension: with the Dirichlet
    values ``g`` (on the dofs ``fixed``, zero elsewhere) the full dofs are
    ``x = E g + R y`` (``R`` of :func:`prolongation_matrix` with the same arguments):
    an aggregated dof whose root holds Dirichlet dofs takes their prescribed values,
    ``E g`` is zero on the Dirichlet dofs themselves. Collective.

    Returns:
        ``E`` as a PETSc AIJ matrix of global shape ``(dim W, dim W)``, rows and columns
        laid out as the owned dofs of ``space.W``; None (on every process) when no
        aggregated dof reads a Dirichlet dof. The caller destroys it.
    """
    imap, bs = space.W.dofmap.index_map, space.W.dofmap.index_map_bs
    comm = imap.comm
    prescribed = _aggregation_parts(space, prolongation, fixed)[1]
    count = 0 if prescribed is None else prescribed.vals.size
    if comm.allreduce(count, op=MPI.SUM) == 0:
        return None
    n_owned = imap.size_local * bs
    rows = prescribed.dofs[prescribed.rows]
    order = np.argsort(rows, kind="stable")
    rows, cols, vals = rows[order], prescribed.sources[order], prescribed.vals[order]
    indptr = np.searchsorted(rows, np.arange(n_owned + 1)).astype(PETSc.IntType)
    E = PETSc.Mat().createAIJ(((n_owned, PETSc.DETERMINE), (n_owned, PETSc.DETERMINE)), comm=comm)
    E.setPreallocationCSR((indptr, cols.astype(PETSc.IntType), vals))
    E.assemble()
    return E


def prescribed_offset(E: PETSc.Mat, bcs: list, W) -> PETSc.Vec:
    """``E g`` for the current values ``g`` of the Dirichlet conditions ``bcs`` on ``W``
    (:func:`prescribed_extension`): a vector laid out as ``W``'s owned dofs. The caller
    destroys it. Collective."""
    g = dolfinx.fem.Function(W)
    dolfinx.fem.petsc.set_bc(g.x.petsc_vec, bcs)
    offset = E.createVecLeft()
    E.mult(g.x.petsc_vec, offset)
    return offset


def _aggregation_parts(space, prolongation, fixed) -> tuple:
    """The aggregation of ``space`` as ``R`` and ``E`` take it: without the dofs
    ``fixed`` (local) and the multiplier prolongation's, split into the entries reading
    unknowns and those reading a dof of ``fixed`` (on any process); ``(None, None)``
    without aggregation. Collective when ``fixed`` is given."""
    aggregation = space.aggregation
    if aggregation is None:
        return None, None
    if prolongation is not None:  # the restriction's own
        aggregation = aggregation.without(prolongation.dofs)
    if fixed is None:
        return aggregation, None
    imap, bs = space.W.dofmap.index_map, space.W.dofmap.index_map_bs
    fixed = np.asarray(fixed, dtype=np.int64)
    aggregation = aggregation.without(fixed)
    owners = imap.local_to_global((fixed // bs).astype(np.int32)) * bs + fixed % bs
    return aggregation.split_sources(np.concatenate(imap.comm.allgather(owners)))


def _gathered_leaders(space: EnrichedSpace, active: np.ndarray) -> np.ndarray | None:
    """With gathered tip dofs (:func:`~xfem_contact.fem.tip_dofs.branch_groups`): per
    owned dof of ``W``, the global dof whose column it shares (the group's least active
    global dof, on any process) if it is another active dof of a group, else -1; None
    without gathering. Collective."""
    groups = branch_groups(space)
    comm = space.W.dofmap.index_map.comm
    if not comm.allreduce(groups is not None, op=MPI.LOR):
        return None
    imap, bs = space.W.dofmap.index_map, space.W.dofmap.index_map_bs
    dofs = np.arange(groups.size, dtype=np.int64) + imap.local_range[0] * bs
    member = active[: groups.size] & (groups >= 0)
    count = comm.allreduce(int(groups.max(initial=-1)) + 1, op=MPI.MAX)
    least = np.full(count, np.iinfo(np.int64).max, dtype=np.int64)
    np.minimum.at(least, groups[member], dofs[member])
    comm.Allreduce(MPI.IN_PLACE, least, op=MPI.MIN)
    leaders = np.full(groups.size, -1, dtype=np.int64)
    leaders[member] = least[groups[member]]
    leaders[dofs == leaders] = -1  # the leaders keep their own column
    return leaders


def _global_lookup(values, start, wanted, comm: MPI.Comm) -> np.ndarray:
    """``values`` (per owned dof, the first at global index ``start``) at the global
    indices ``wanted`` owned by any process (-1 where no process has a value >= 0).
    Collective: every process's requests are gathered."""
    requests = np.unique(np.concatenate(comm.allgather(np.asarray(wanted, dtype=np.int64))))
    local = requests - start
    here = (local >= 0) & (local < values.size)
    answers = np.full(requests.size, -1, dtype=np.int64)
    answers[here] = values[local[here]]
    comm.Allreduce(MPI.IN_PLACE, answers, op=MPI.MAX)
    return answers[np.searchsorted(requests, wanted)]
