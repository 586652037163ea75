"""Symmetric diagonal scaling of the reduced systems (saddle points included).

The contact and bonded systems couple displacements (rows of size ``E``, Pa) with
multipliers whose block is ``h^2 / E`` or zero (a closed contact point without
stabilisation is a pure Lagrange multiplier): unscaled, their condition numbers are
astronomical and a direct solver's round-off differs from machine to machine. Both
solves therefore work with ``R_s = R D`` (the
unknowns ``y = D^-1 y_r``) and factor ``D R^T J R D``, with ``D_ii = d_i^-1/2`` and

    d_i = |J_ii|                                              (Jacobi), or
    d_i = max(|J_ii|, sum_{j != i, J_jj != 0} J_ij^2 / |J_jj|)  on the rows whose
          diagonal is small: |J_ii| <= 1e-8 max_j |J_jj|

on the reduced Jacobian ``J`` of the first assembly. A multiplier row (zero diagonal,
or ``h^2 / E`` against ``E`` in SI units) gets the diagonal of the Schur complement
``B A^-1 B^T`` it couples into, the scale a zero-diagonal row needs; only those rows
are read entry by entry (reading every row would be slow on large meshes).
Where a multiplier block is not small against the displacements' (units in which
``E ~ 1``), Jacobi scales its coupling ``B_ij / (C_ii A_jj)^1/2`` to order one too.
``D`` is kept for the whole solve (any fixed positive ``D`` gives the same solution in
exact arithmetic); a row with ``d_i = 0`` keeps ``D_ii = 1``.
``tests/test_conditioning.py`` bounds the scaled condition numbers.
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.solvers.assembly import aij

#: A diagonal at most this fraction of the largest is small (see the module docstring)
SMALL_DIAGONAL = 1e-8


def saddle_point_scaling(J: PETSc.Mat) -> PETSc.Vec:
    """The scaling ``D`` (diagonal, as a vector laid out as ``J``'s columns). Collective.

    Args:
        J: A square assembled AIJ (or BAIJ) matrix (the reduced Jacobian ``R^T J R``).

    Returns:
        ``D`` with ``D_i = d_i^-1/2`` (see the module docstring); the caller destroys it.
    """
    diagonal = J.getDiagonal()
    d = np.abs(diagonal.getArray(readonly=True))
    diagonal.destroy()
    comm = J.getComm()
    largest = comm.tompi4py().allreduce(float(d.max(initial=0.0)), op=MPI.MAX)
    small = np.flatnonzero(d <= SMALL_DIAGONAL * largest)
    first = J.getOwnershipRange()[0]
    rows = PETSc.IS().createGeneral((first + small).astype(PETSc.IntType), comm=comm)
    first_column = J.getOwnershipRangeColumn()[0]
    columns = PETSc.IS().createStride(J.getLocalSize()[1], first_column, 1, comm=comm)
    stored, copied = aij(J)
    part = stored.createSubMatrix(rows, columns)  # the small rows, all columns as in J
    indptr, cols, values = part.getValuesCSR()
    for obj in (rows, columns, part) + ((stored,) if copied else ()):
        obj.destroy()
    inverse = J.createVecRight()
    inverse.setArray(np.divide(1.0, d, out=np.zeros_like(d), where=d > 0))
    weighted = values**2 * gather(inverse, cols)  # 1 / |J_jj| at each entry's column
    inverse.destroy()
    s = np.zeros(small.size)
    nonempty = np.flatnonzero(np.diff(indptr) > 0)
    s[nonempty] = np.add.reduceat(weighted, indptr[nonempty])
    s -= np.where(d[small] > 0, d[small], 0.0)  # without j = i (J_ii^2 / |J_ii|)
    scale = d.copy()
    scale[small] = np.maximum(d[small], s)
    D = J.createVecRight()
    D.setArray(np.divide(1.0, np.sqrt(scale), out=np.ones_like(scale), where=scale > 0))
    return D


def gather(vector: PETSc.Vec, indices: np.ndarray) -> np.ndarray:
    """The entries of a distributed vector at global ``indices`` (owned here or not).
    Collective."""
    wanted = np.unique(indices)
    gathered = PETSc.Vec().createSeq(wanted.size, comm=PETSc.COMM_SELF)
    index = PETSc.IS().createGeneral(wanted.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
    scatter = PETSc.Scatter().create(vector, index, gathered, None)
    scatter.scatter(vector, gathered, PETSc.InsertMode.INSERT, PETSc.ScatterMode.FORWARD)
    values = gathered.getArray(readonly=True)[np.searchsorted(wanted, indices)].copy()
    for obj in (gathered, index, scatter):
        obj.destroy()
    return values
