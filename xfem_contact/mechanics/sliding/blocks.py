"""Point blocks of the hybrid elements added to a PETSc Jacobian through a COO matrix.

A block is ``(rows (m, a), cols (m, b), values (m, a, b))``: per point, a dense
``a x b`` matrix on reduced row and column indices (-1: none, dropped by PETSc).
:class:`BlockMatrix` keeps one COO matrix whose pattern is rebuilt only when the
pairing (its key) changes, and adds it to the Jacobian, merging its pattern into the
Jacobian's when a pair of cells appears that the Jacobian has not held yet.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc


class BlockMatrix:
    """The COO matrix of the couplings' point blocks (collective methods)."""

    def __init__(self):
        self._coo: tuple | None = None
        self._merged: set = set()

    def reset(self) -> None:
        """Forget the pattern (new numbering): destroy the matrix. Collective."""
        self.destroy()
        self._merged.clear()

    def add_to(self, J: PETSc.Mat, key: bytes, blocks: list, pairs: set) -> None:
        """Add ``blocks`` to ``J``.

        Args:
            J: The Jacobian (reduced numbering).
            key: Identifies the blocks' pattern (same key: same row and column
                indices as the last call).
            blocks: The point blocks (see the module).
            pairs: Pairs of global cells the blocks couple; a pair not seen before
                (on any process) merges the pattern into ``J``'s.
        """
        if self._coo is None or self._coo[0] != key:
            self.destroy()
            Ic, Jc = [], []
            for rows, cols, _ in blocks:
                Ic.append(np.repeat(rows, cols.shape[1], axis=1).ravel())
                Jc.append(np.tile(cols, (1, rows.shape[1])).ravel())
            C = PETSc.Mat().create(comm=J.getComm())
            C.setSizes(J.getSizes())
            C.setType(PETSc.Mat.Type.AIJ)
            C.setPreallocationCOO(
                np.concatenate(Ic).astype(PETSc.IntType), np.concatenate(Jc).astype(PETSc.IntType)
            )
            self._coo = (key, C)
        C = self._coo[1]
        values = np.concatenate([v.ravel() for _, _, v in blocks])
        C.setValuesCOO(values, addv=PETSc.InsertMode.INSERT_VALUES)
        C.assemble()
        new = not pairs <= self._merged
        if J.getComm().tompi4py().allreduce(new, op=MPI.LOR):
            self._merged |= pairs
            J.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        else:
            J.axpy(1.0, C, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def destroy(self) -> None:
        """Destroy the COO matrix. Collective."""
        if self._coo is not None:
            self._coo[1].destroy()
            self._coo = None
