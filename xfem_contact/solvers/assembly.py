"""Bilinear forms assembled on the reduced space ``R^T A R`` of a prolongation ``R``.

A form on the mixed space ``W = (u_-, u_+, lambda, ...)`` couples every field on
every cell it integrates, and more than half of ``W``'s dofs are inactive, so a
matrix assembled in full and reduced by ``PtAP`` stores several times the entries of
the reduced one. When ``R`` only *selects* dofs (identity columns: every LBB treatment but the
vital-vertex restriction), :class:`ReducedMatrix` builds the sparsity of the active dofs alone and
assembles straight into it through a local-to-global map that sends each dof of
``W`` to its reduced column and each inactive dof to -1, which PETSc drops. With a
multiplier prolongation in ``R`` it assembles the full matrix and reduces it by
``PtAP``, reusing the product's symbolic phase.
"""

from __future__ import annotations

import itertools
import typing

import dolfinx.cpp
import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.la
import numpy as np
import numpy.typing as npt
from dolfinx.fem import IntegralType
from mpi4py import MPI
from petsc4py import PETSc

#: MPI tag of the consensus that builds the reduced index map
_TAG = 2718


class Selection:
    """The reduced column of every local dof of ``W`` for a selecting ``R``.

    Attributes:
        columns: Reduced global column of each local (owned and ghost) dof of ``W``,
            -1 for inactive ones, shape ``(num_local_dofs,)``.
        local: Reduced local index (owned first, then ghosts) or -1, same shape.
        index_map: Index map of the reduced space (owned columns of ``R``, ghosts).
    """

    def __init__(self, columns, local, index_map):
        self.columns, self.local, self.index_map = columns, local, index_map


def selection(R: PETSc.Mat, W: dolfinx.fem.FunctionSpace) -> Selection | None:
    """The :class:`Selection` of ``R`` if every process's rows of ``R`` select its own
    columns (at most one entry per row, equal to 1, each owned column once), else
    ``None``. Collective.

    Args:
        R: Prolongation, global shape ``(dim W, n_reduced)``, rows laid out as
            ``W``'s owned dofs.
        W: The mixed space of the rows of ``R``.
    """
    imap, bs = W.dofmap.index_map, W.dofmap.index_map_bs
    n_owned = imap.size_local * bs
    indptr, cols, vals = R.getValuesCSR()
    first, last = R.getOwnershipRangeColumn()
    counts = np.diff(indptr)
    is_selection = (
        counts.size == n_owned
        and np.all(counts <= 1)
        and np.all(vals == 1.0)
        and cols.size == last - first
        and np.array_equal(np.sort(cols), np.arange(first, last))
    )
    if not imap.comm.allreduce(bool(is_selection), op=MPI.LAND):
        return None
    owned = np.full(n_owned, -1.0)
    owned[counts == 1] = cols
    carrier = dolfinx.la.vector(imap, bs)  # exact for columns below 2^53
    carrier.array[:n_owned] = owned
    carrier.scatter_forward()
    columns = np.rint(carrier.array).astype(np.int64)
    ghost = np.flatnonzero(columns[n_owned:] >= 0)
    owners = np.repeat(imap.owners, bs)[ghost].astype(np.int32)
    index_map = dolfinx.cpp.common.IndexMap(
        imap.comm, last - first, columns[n_owned + ghost], owners, _TAG
    )
    local = np.full(columns.size, -1, dtype=np.int32)
    mine = np.flatnonzero(columns[:n_owned] >= 0)
    local[mine] = columns[mine] - first
    local[n_owned + ghost] = last - first + np.arange(ghost.size, dtype=np.int32)
    return Selection(columns, local, index_map)


def _coupled_cells(a: dolfinx.fem.Form) -> tuple[npt.NDArray, npt.NDArray]:
    """The local cells the integrals of ``a`` cover, and the cell pairs of its
    interior-facet integrals (whose dofs all couple), shapes ``(n,)`` and ``(m, 2)``."""
    cpp_form = a._cpp_object
    cells, pairs = [np.zeros(0, dtype=np.int32)], [np.zeros((0, 2), dtype=np.int32)]
    for itype in IntegralType:
        for i in range(cpp_form.num_integrals(itype, 0)):
            entities = cpp_form.domains(itype, i)
            if itype == IntegralType.cell:
                cells.append(entities)
            elif itype == IntegralType.interior_facet:  # (cell, facet, cell, facet)
                pairs.append(entities.reshape(-1, 4)[:, [0, 2]])
            else:  # (cell, local entity)
                cells.append(entities.reshape(-1, 2)[:, 0])
    return np.unique(np.concatenate(cells)), np.unique(np.concatenate(pairs), axis=0)


def _node_blocks(
    chosen: Selection, fields: list, bs: int, comm
) -> dolfinx.cpp.common.IndexMap | None:
    """The index map of the reduced unknowns taken ``bs`` by ``bs`` (the components of a
    node: ``bs`` the mesh's dimension), if every field (``fields``: the cell dofmaps of
    the fields of the mixed space ``W``) has ``bs`` components and the unknowns group up
    on every process (owned and ghost ones alike: counts divisible by ``bs``, ghost
    groups ``bs m, ..., bs m + bs - 1``), else ``None`` (e.g. a scalar multiplier:
    frictionless contact). Collective.

    A node's components are consecutive in ``W`` and active together, so they are
    consecutive in the reduced numbering too."""
    imap = chosen.index_map
    ghosts, owners = imap.ghosts, imap.owners
    first = imap.local_range[0]
    components = range(1, bs)
    grouped = (
        bs > 1
        and all(
            d.shape[1] % bs == 0 and all(np.all(d[:, k::bs] == d[:, 0::bs] + k) for k in components)
            for d in fields
        )
        and imap.size_local % bs == 0
        and first % bs == 0
        and ghosts.size % bs == 0
        and np.all(ghosts[0::bs] % bs == 0)
        and all(np.all(ghosts[k::bs] == ghosts[0::bs] + k) for k in components)
    )
    if not comm.allreduce(bool(grouped), op=MPI.LAND):
        return None
    return dolfinx.cpp.common.IndexMap(
        comm, imap.size_local // bs, ghosts[0::bs] // bs, owners[0::bs], _TAG + 1
    )


def reduced_matrix(
    a: dolfinx.fem.Form,
    chosen: Selection,
    blocks: bool = True,
    field_blocks: list[tuple[dolfinx.fem.Form, np.ndarray]] = (),
    fill: bool = True,
    node_storage: bool = False,
) -> PETSc.Mat:
    """An AIJ matrix with the sparsity of ``a`` (and of the ``field_blocks``: forms on
    a field's own space, with the parent dof in ``W`` of each of its local dofs) on
    the selected dofs, laid out as the reduced space, whose local-to-global map takes
    ``W``'s local dof numbers (the numbering :func:`dolfinx.fem.petsc.assemble_matrix`
    inserts with). Collective.

    With ``blocks`` and unknowns that group by node (:func:`_node_blocks`) the pattern is
    built on the nodes, as DOLFINx builds a vector space's (a quarter of the entries to
    sort in 2D, a ninth in 3D), and the matrix has the mesh's dimension as block size.
    With ``fill`` the whole pattern is stored (:func:`_fill_pattern`). With
    ``node_storage`` a matrix of node blocks is stored as such (BAIJ: one column index
    a block, about 30 % less memory in 3D than AIJ's one an entry); PETSc then extracts
    sub-matrices of whole blocks only (:func:`aij`)."""
    comm = a.mesh.comm  # lives as long as the mesh (the index map's own does not)
    W = a.function_spaces[0]
    dofmap = W.dofmap.map()  # (num_cells, dofs per cell)
    fields = [W.sub([i]).dofmap.map() for i in range(W.element.num_sub_elements)] or [dofmap]
    gdim = a.mesh.geometry.dim
    nodes_map = _node_blocks(chosen, fields, gdim, comm) if blocks else None
    bs = 1 if nodes_map is None else gdim
    index_map = chosen.index_map if nodes_map is None else nodes_map
    pattern = dolfinx.cpp.la.SparsityPattern(comm, [index_map] * 2, [bs, bs])
    cells, pairs = _coupled_cells(a)
    block = chosen.local // bs if bs > 1 else chosen.local  # -1 stays negative
    for row in _rows(block[dofmap[cells]]):
        pattern.insert(row, row)
    for field in fields:  # facet pairs couple a field with itself (the ghost penalty)
        for row in _rows(np.c_[block[field[pairs[:, 0]]], block[field[pairs[:, 1]]]]):
            pattern.insert(row, row)
    for form, parent in field_blocks:  # their cells, and their facets' cell pairs
        cells_i, pairs_i = _coupled_cells(form)
        rows = block[parent[_unrolled_dofs(form, cells_i)]]
        both = [block[parent[_unrolled_dofs(form, pairs_i[:, k])]] for k in (0, 1)]
        for row in itertools.chain(_rows(rows), _rows(np.hstack(both))):
            pattern.insert(row, row)
    pattern.insert_diagonal(np.arange(index_map.size_local, dtype=np.int32))
    pattern.finalize()
    A = dolfinx.cpp.la.petsc.create_matrix(
        comm, pattern, "baij" if node_storage and bs > 1 else None
    )
    if fill:
        _fill_pattern(A, pattern, bs)
    lgmap = PETSc.LGMap().create(chosen.columns.astype(PETSc.IntType), comm=comm)
    A.setLGMap(lgmap, lgmap)
    lgmap.destroy()
    _zeros_outside_the_pattern(A, fill)
    return A


def aij(A: PETSc.Mat) -> tuple[PETSc.Mat, bool]:
    """``A`` in a storage that extracts any rows and columns (``createSubMatrix``) and
    multiplies with AIJ matrices (``PtAP``): ``A`` itself if AIJ, else an AIJ copy (a
    node-block matrix, :func:`reduced_matrix`); and whether it is a copy (the caller
    destroys it). Collective."""
    if A.getType() in (PETSc.Mat.Type.SEQBAIJ, PETSc.Mat.Type.MPIBAIJ):
        return A.convert(PETSc.Mat.Type.AIJ, PETSc.Mat()), True  # (no out: in place)
    return A, False


def _fill_pattern(A: PETSc.Mat, pattern, bs: int) -> None:
    """Store an explicit zero at every entry of ``pattern`` (block size ``bs``), so
    that the matrix keeps the whole pattern: skipping the zeros a kernel inserts
    (:func:`_zeros_outside_the_pattern`) must not shrink it to the first assembly's
    nonzeros (an open contact's, say), or every later nonzero would be inserted
    slowly and change the structure, and the LU factorisation would analyse the
    matrix again at each Newton step. Collective."""
    columns, offsets = pattern.graph
    owned = pattern.index_map(0).size_local  # the graph also lists the ghost rows
    offsets = offsets[: owned + 1]
    columns = pattern.index_map(1).local_to_global(columns[: offsets[-1]])
    zeros = np.zeros(columns.size * bs * bs)
    rows, cols = offsets.astype(PETSc.IntType), columns.astype(PETSc.IntType)
    if bs == 1:
        A.setValuesCSR(rows, cols, zeros)
    else:
        A.setValuesBlockedCSR(rows, cols, zeros)
    A.assemble()


def _unrolled_dofs(a: dolfinx.fem.Form, cells: npt.NDArray[np.int32]) -> np.ndarray:
    """The local dofs (unrolled) of ``cells`` in the space of ``a``, ``(n, dofs per cell)``."""
    dofmap = a.function_spaces[0].dofmap
    cell_dofs, bs = dofmap.map(), dofmap.bs
    dofs = cell_dofs[cells][:, :, None] * bs + np.arange(bs)
    return dofs.reshape(len(cells), cell_dofs.shape[1] * bs)


def _block_lgmap(
    columns: np.ndarray, parent: np.ndarray, bs: int, comm
) -> tuple[PETSc.LGMap, bool]:
    """The local-to-global map of a field's own space into the reduced matrix (block
    size ``bs``): its dofs' reduced columns (``columns`` of their ``parent`` dofs), -1
    for inactive dofs. Made of ``bs`` x ``bs`` blocks when the field and the matrix
    group up at every node (then ``True``), else dof by dof. Local."""
    cols = columns[parent]
    if bs > 1 and cols.size % bs == 0:
        nodes = cols.reshape(-1, bs)
        first = nodes[:, 0]
        idle = np.all(nodes < 0, axis=1)
        whole = (
            (first >= 0)
            & (first % bs == 0)
            & np.all(nodes == first[:, None] + np.arange(bs), axis=1)
        )
        if np.all(idle | whole):
            blocks = np.where(idle, -1, first // bs).astype(PETSc.IntType)
            return PETSc.LGMap().create(blocks, bsize=bs, comm=comm), True
    return PETSc.LGMap().create(cols.astype(PETSc.IntType), comm=comm), False


def _zeros_outside_the_pattern(A: PETSc.Mat, skip: bool) -> None:
    """Facet kernels on ``W`` fill every field's block with explicit zeros: with
    ``skip`` these are skipped (and the pattern itself is stored whole,
    :func:`_fill_pattern`); without facet integrals on ``W`` (the ghost penalty assembled
    by field) every insertion lies in the pattern and zeros are stored. A nonzero
    outside the pattern (a facet term coupling two fields) is inserted, slowly, never
    dropped: the per-field pattern is an optimisation, not an assumption. Set before
    each assembly: a merge that grows the pattern (``MatAXPY``) makes new storage
    without these options."""
    A.setOption(PETSc.Mat.Option.IGNORE_ZERO_ENTRIES, skip)
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)


def _rows(cell_rows: np.ndarray):
    """The distinct non-negative entries of each row of ``cell_rows`` (int32, sorted),
    grouped by their number so that each group is sorted in one call."""
    cell_rows = np.sort(cell_rows, axis=1)
    distinct = np.ones(cell_rows.shape, dtype=bool)
    distinct[:, 1:] = cell_rows[:, 1:] != cell_rows[:, :-1]
    distinct &= cell_rows >= 0
    counts = distinct.sum(axis=1)
    for k in np.unique(counts[counts > 0]):
        group = cell_rows[counts == k][distinct[counts == k]].reshape(-1, k)
        yield from np.ascontiguousarray(group, dtype=np.int32)


def _assemble_unrolled(A: PETSc.Mat, a: dolfinx.fem.Form, bcs: list) -> None:
    """:func:`dolfinx.fem.petsc.assemble_matrix` of a form on one space (unit diagonal
    at the Dirichlet dofs) inserting dof by dof (``MatSetValuesLocal``), also into a
    matrix of block size > 1: DOLFINx inserts with ``MatSetValuesBlockedLocal``, which
    reads the mixed space's dof numbers as block numbers there. Collective."""
    constants = dolfinx.fem.pack_constants(a)
    coefficients = dolfinx.fem.pack_coefficients(a)
    cpp_bcs = [bc._cpp_object for bc in bcs]
    dolfinx.cpp.fem.petsc.assemble_matrix(A, a._cpp_object, constants, coefficients, cpp_bcs, True)
    A.assemblyBegin(PETSc.Mat.AssemblyType.FLUSH)
    A.assemblyEnd(PETSc.Mat.AssemblyType.FLUSH)
    dolfinx.cpp.fem.petsc.insert_diagonal(A, a.function_spaces[0], cpp_bcs, 1.0)


class _Block(typing.NamedTuple):
    """A field block of :class:`ReducedMatrix`, ready to assemble into the reduced matrix."""

    form: dolfinx.fem.Form
    #: Local-to-global map of its rows and columns in the reduced numbering
    lgmap: PETSc.LGMap
    #: Whether ``lgmap`` is blocked (a vector field's block size)
    blocked: bool
    #: 1 on its Dirichlet dofs, 0 elsewhere (int8, per dof of the field's space)
    fixed: np.ndarray
    #: Whether the block is constant over the Newton iterates
    constant: bool


class ReducedMatrix:
    """``R^T A R`` of a bilinear form on ``W``, assembled again on demand.

    Args:
        a: Bilinear form on the mixed space ``W`` (test and trial).
        bcs: Dirichlet conditions on ``W`` (zero rows and columns, unit diagonal,
            as :func:`dolfinx.fem.petsc.assemble_matrix` applies them).
        R: Prolongation, global shape ``(dim W, n_reduced)``. Not modified;
            kept for the ``PtAP`` path.
        blocks: Allow a pattern (and matrix) of node blocks (:func:`reduced_matrix`);
            off for matrices that others add to with a scalar pattern (``MatAXPY``).
        field_blocks: Forms on a field's own space to add, each with the parent dof
            in ``W`` of every local dof of that space and whether it is constant (no
            coefficient that changes in a solve, e.g. a linear bulk) (the uncut cells'
            blocks of :func:`xfem_contact.fem.field_blocks.uncut_field_blocks`): the matrix is
            ``R^T (A + sum_i P_i A_i P_i^T) R``. Only for an ``R`` that selects. After
            :meth:`keep_constant_blocks` the constant ones are assembled once more and
            then added from a copy.
        chosen: :func:`selection` of ``R``, if the caller has it.
        node_storage: Store node blocks as such (see :func:`reduced_matrix`).

    Construction is collective (sparsity, or the full matrix for ``PtAP``).
    """

    def __init__(
        self,
        a: dolfinx.fem.Form,
        bcs: list,
        R: PETSc.Mat,
        blocks: bool = True,
        field_blocks: list[tuple[dolfinx.fem.Form, np.ndarray, bool]] = (),
        chosen: Selection | None = None,
        node_storage: bool = False,
    ):
        self.a, self.bcs = a, bcs
        W = a.function_spaces[0]
        chosen = chosen or selection(R, W)
        #: Whether the form is assembled straight into the reduced numbering
        self.direct = chosen is not None
        self.R = None if self.direct else R  # only PtAP reads it again
        if field_blocks and not self.direct:
            raise ValueError("field blocks need a prolongation that selects dofs")
        #: The reduced column of every dof (:class:`Selection`; None for ``PtAP``)
        self.selection = chosen
        self._full = None if self.direct else dolfinx.fem.petsc.create_matrix(a)
        self.mat: PETSc.Mat | None = None
        self._blocks = []
        self._kept: PETSc.Mat | None = None  # the constant blocks' sum
        self._keep = False  # copy them at the next assembly
        #: Whether facet kernels on ``W`` insert zeros to skip (:func:`_zeros_outside_the_pattern`)
        self.skip_zeros = a.mesh.comm.allreduce(_coupled_cells(a)[1].size > 0, op=MPI.LOR)
        if self.direct:
            pairs = [b[:2] for b in field_blocks]
            self.mat = reduced_matrix(
                a, chosen, blocks, pairs, fill=self.skip_zeros, node_storage=node_storage
            )
            fixed = np.zeros(chosen.columns.size, dtype=np.int8)  # Dirichlet dofs of W
            for bc in bcs:
                fixed[bc.dof_indices()[0]] = 1
            bs, comm = self.mat.getBlockSize(), a.mesh.comm
            for form, parent, constant in field_blocks:
                lgmap, blocked = _block_lgmap(chosen.columns, parent, bs, comm)
                self._blocks.append(_Block(form, lgmap, blocked, fixed[parent], constant))
            self._lgmap = self.mat.getLGMap()[0]

    def keep_constant_blocks(self) -> None:
        """From the next assembly on, assemble the constant field blocks only once:
        the next assembly keeps a copy of their sum (a matrix), the later ones add
        it. For the iterates of one Newton solve; call again at the next (the copy
        is made anew). Not collective."""
        if self._kept is not None:
            self._kept.destroy()
            self._kept = None
        self._keep = any(block.constant for block in self._blocks)

    def _assemble_blocks(self, constant: bool) -> None:
        for form, lgmap, blocked, fixed, is_constant in self._blocks:
            if is_constant != constant:
                continue
            self.mat.setLGMap(lgmap, lgmap)  # in the field's own numbering
            constants = dolfinx.fem.pack_constants(form)
            coefficients = dolfinx.fem.pack_coefficients(form)
            dolfinx.cpp.fem.petsc.assemble_matrix(
                self.mat, form._cpp_object, constants, coefficients, fixed, fixed, not blocked
            )
        self.mat.setLGMap(self._lgmap, self._lgmap)

    def assemble(self) -> PETSc.Mat:
        """Assemble ``R^T A R`` (with the Dirichlet conditions) into :attr:`mat` and
        return it; the object keeps it. Collective."""
        if self.direct:
            self.mat.zeroEntries()
            _zeros_outside_the_pattern(self.mat, self.skip_zeros)
            if self._kept is not None:
                info = PETSc.Mat.InfoType.LOCAL
                sizes = (m.getInfo(info)["nz_allocated"] for m in (self._kept, self.mat))
                # new storage (a merge) on any rank: the copy no longer fits; decided
                # together, since keeping a new copy assembles (collectively)
                if self.mat.getComm().tompi4py().allreduce(len(set(sizes)) > 1, op=MPI.LOR):
                    self.keep_constant_blocks()
            if self._kept is not None:  # same structure: values added, rank by rank
                self.mat.axpy(1.0, self._kept, PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
            else:
                self._assemble_blocks(constant=True)
                if self._keep:
                    self.mat.assemble()
                    self._kept, self._keep = self.mat.duplicate(copy=True), False
            self._assemble_blocks(constant=False)
            _assemble_unrolled(self.mat, self.a, self.bcs)
            self.mat.assemble()
            return self.mat
        self._full.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(self._full, self.a, bcs=self.bcs)
        self._full.assemble()
        if self.mat is None:
            self.mat = self._full.PtAP(self.R)
        else:
            self._full.PtAP(self.R, result=self.mat)
        return self.mat

    @property
    def full(self) -> PETSc.Mat | None:
        """The full matrix ``A`` of the ``PtAP`` path at the last assembly, else None."""
        return self._full

    def full_matrix(self) -> PETSc.Mat:
        """The full matrix ``A`` (with the Dirichlet conditions) at the last assembly:
        :attr:`full` on the ``PtAP`` path, else assembled here (the caller destroys
        that one). Collective."""
        if self._full is not None:
            return self._full
        A = dolfinx.fem.petsc.assemble_matrix(self.a, bcs=self.bcs)
        A.assemble()
        return A

    def release(self) -> PETSc.Mat:
        """Hand :attr:`mat` over to the caller (who destroys it) and destroy the rest.
        Collective."""
        mat, self.mat = self.mat, None
        self.destroy()
        return mat

    def destroy(self) -> None:
        """Destroy the PETSc objects made here (not ``R``). Collective."""
        for mat in (self._full, self.mat):
            if mat is not None:
                mat.destroy()
        for _, lgmap, *_ in self._blocks:
            lgmap.destroy()
        self._blocks = []
        if self._kept is not None:
            self._kept.destroy()
            self._kept = None
