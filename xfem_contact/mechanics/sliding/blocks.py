"""Point blocks of the hybrid elements added to a PETSc Jacobian.

A block is ``(rows (m, a), cols (m, b), values (m, a, b))``: per point, a dense
``a x b`` matrix on reduced row and column indices (-1: none, dropped by PETSc).
:class:`BlockMatrix` sums the blocks of the points that share their indices (a slave
cell and a master piece: the Gauss points of one sub-segment) and, while the pairs of
cells they couple lie in the Jacobian's pattern, adds them block by block
(``MatSetValues``, looped over in C); when a pair appears that the Jacobian has not
held yet, it makes a COO matrix of the blocks and merges its pattern into the
Jacobian's (``MatAXPY``, different pattern: new storage, then a new symbolic
factorisation if the pattern grew).
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc


def role(cells: np.ndarray, master: bool) -> np.ndarray:
    """Global cells as slave (``2 c``: slave displacement and multiplier dofs) or
    master (``2 c + 1``: master displacement dofs) cells; negative cells stay -1."""
    cells = np.asarray(cells, dtype=np.int64)
    return np.where(cells >= 0, 2 * cells + int(master), -1)


def cell_pairs(num_cells: int, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Distinct codes ``row * 2 num_cells + col`` of (row, column) pairs of cells in
    their roles (:func:`role`; ``num_cells`` global), pairs with a negative cell left
    out."""
    n = np.int64(2 * num_cells)
    keep = (rows >= 0) & (cols >= 0)
    return np.unique(rows[keep] * n + cols[keep])


def _summed(rows: np.ndarray, cols: np.ndarray, values: np.ndarray) -> tuple:
    """The blocks of the points that share their row and column indices (a slave
    cell and a master piece) summed: one block per distinct index set, in PETSc's
    types."""
    index = np.ascontiguousarray(np.concatenate([rows, cols], axis=1), dtype=PETSc.IntType)
    if index.shape[0] == 0:
        return index[:, : rows.shape[1]], index[:, rows.shape[1] :], values
    keys = index.view(np.dtype((np.void, index.dtype.itemsize * index.shape[1])))[:, 0]
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    order = np.argsort(inverse, kind="stable")
    starts = np.searchsorted(inverse[order], np.arange(first.size))
    summed = np.add.reduceat(values[order], starts, axis=0)
    index = index[first]
    a = rows.shape[1]
    return (
        np.ascontiguousarray(index[:, :a]),
        np.ascontiguousarray(index[:, a:]),
        np.ascontiguousarray(summed, dtype=PETSc.ScalarType),
    )


class BlockMatrix:
    """Adds the couplings' point blocks to the Jacobian (collective methods)."""

    def __init__(self):
        self._merged = np.zeros(0, dtype=np.int64)

    def reset(self) -> None:
        """Forget the pattern (new numbering). Collective."""
        self._merged = np.zeros(0, dtype=np.int64)

    def add_to(self, J: PETSc.Mat, blocks: list, pairs: np.ndarray) -> None:
        """Add ``blocks`` to ``J``.

        Args:
            J: The Jacobian (reduced numbering).
            blocks: The point blocks (see the module).
            pairs: The (row, column) pairs of global cells the blocks couple, as
                distinct integer codes; a pair not seen before (on any process)
                merges the pattern into ``J``'s.
        """
        blocks = [_summed(*block) for block in blocks]
        new = bool(np.isin(pairs, self._merged, assume_unique=True, invert=True).any())
        if not J.getComm().tompi4py().allreduce(new, op=MPI.LOR):
            # within the pattern: block by block into J (no COO pattern to sort, no merge)
            for rows, cols, values in blocks:
                J.setValuesRCV(rows, cols, values, addv=PETSc.InsertMode.ADD_VALUES)
            J.assemble()
            return
        Ic, Jc = [], []
        for rows, cols, _ in blocks:
            Ic.append(np.repeat(rows, cols.shape[1], axis=1).ravel())
            Jc.append(np.tile(cols, (1, rows.shape[1])).ravel())
        C = PETSc.Mat().create(comm=J.getComm())
        C.setSizes(J.getSizes())
        C.setType(PETSc.Mat.Type.AIJ)
        C.setPreallocationCOO(np.concatenate(Ic), np.concatenate(Jc))
        values = np.concatenate([v.ravel() for _, _, v in blocks])
        C.setValuesCOO(values, addv=PETSc.InsertMode.INSERT_VALUES)
        C.assemble()
        self._merged = np.union1d(self._merged, pairs)
        J.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        C.destroy()

    def destroy(self) -> None:
        """Nothing is kept between calls (kept for the couplings' interface)."""
