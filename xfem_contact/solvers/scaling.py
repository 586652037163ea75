"""Symmetric diagonal scaling of the reduced systems (saddle points included).

The contact and bonded systems couple displacements (rows of size ``E``, Pa) with
multipliers whose block is ``h^2 / E`` or zero (a closed contact point without
stabilisation is a pure Lagrange multiplier): unscaled, the 2-norm condition number
of a small case-2 Jacobian was 2.6e19 and the direct solver's round-off differed
from machine to machine at 1e-8. Both solves therefore work with ``R_s = R D`` (the
unknowns ``y = D^-1 y_r``) and factor ``D R^T J R D``, with

    d_i = max(|J_ii|, sum_{j != i, J_jj != 0} J_ij^2 / |J_jj|),    D_ii = d_i^-1/2

on the reduced Jacobian ``J`` of the first assembly: Jacobi where the diagonal
dominates, and for a multiplier row the diagonal of the Schur complement
``B A^-1 B^T`` it couples into (the scale a zero-diagonal row needs). ``D`` is kept
for the whole solve (any fixed positive ``D`` gives the same solution in exact
arithmetic); a row with ``d_i = 0`` keeps ``D_ii = 1``.
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc


def saddle_point_scaling(J: PETSc.Mat) -> PETSc.Vec:
    """The scaling ``D`` (diagonal, as a vector laid out as ``J``'s columns). Collective.

    Args:
        J: A square assembled AIJ matrix (the reduced Jacobian ``R^T J R``).

    Returns:
        ``D`` with ``D_i = d_i^-1/2`` (see the module docstring); the caller destroys it.
    """
    diagonal = J.getDiagonal()
    d = np.abs(diagonal.getArray(readonly=True))
    diagonal.destroy()
    inverse = np.divide(1.0, d, out=np.zeros_like(d), where=d > 0)
    indptr, columns, values = J.getValuesCSR()  # owned rows, global columns
    lookup = _column_values(J, inverse, columns)
    # s_i = sum_j J_ij^2 / |J_jj| row by row, a block of rows at a time (no temporary
    # of the matrix's size: at 830 k rows J has 29 M entries)
    s = np.zeros_like(d)
    lengths = np.diff(indptr)
    for begin in range(0, d.size, _ROWS_PER_BLOCK):
        end = min(d.size, begin + _ROWS_PER_BLOCK)
        a, b = indptr[begin], indptr[end]
        weighted = values[a:b] ** 2 * lookup(columns[a:b])
        rows = np.flatnonzero(lengths[begin:end] > 0)
        s[begin + rows] = np.add.reduceat(weighted, indptr[begin + rows] - a)
    s -= np.where(d > 0, d, 0.0)  # without j = i (J_ii^2 / |J_ii|)
    scale = np.maximum(d, s)
    D = J.createVecRight()
    D.setArray(np.divide(1.0, np.sqrt(scale), out=np.ones_like(scale), where=scale > 0))
    return D


#: Rows per block of the row sums in :func:`saddle_point_scaling`
_ROWS_PER_BLOCK = 1 << 15


def _column_values(J: PETSc.Mat, owned: np.ndarray, columns: np.ndarray):
    """A function mapping global column indices of ``J`` (owned or not) to the values
    ``owned`` holds on their owning processes (one per owned column). Collective: the
    values of the other processes' columns that ``columns`` names are gathered here."""
    first, last = J.getOwnershipRangeColumn()
    remote = np.unique(columns[(columns < first) | (columns >= last)])
    source = J.createVecRight()
    source.setArray(owned)
    gathered = PETSc.Vec().createSeq(remote.size, comm=PETSc.COMM_SELF)
    index = PETSc.IS().createGeneral(remote.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
    scatter = PETSc.Scatter().create(source, index, gathered, None)
    scatter.scatter(source, gathered, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
    remote_values = gathered.getArray(readonly=True).copy()
    for obj in (source, gathered, index, scatter):
        obj.destroy()

    def lookup(cols: np.ndarray) -> np.ndarray:
        local = (cols >= first) & (cols < last)
        out = np.empty(cols.size)
        out[local] = owned[cols[local] - first]
        elsewhere = ~local
        out[elsewhere] = remote_values[np.searchsorted(remote, cols[elsewhere])]
        return out

    return lookup
