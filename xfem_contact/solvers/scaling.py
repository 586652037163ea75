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
    inverse = J.createVecRight()
    inverse.setArray(np.divide(1.0, d, out=np.zeros_like(d), where=d > 0))
    indptr, indices, values = J.getValuesCSR()
    squared = J.duplicate(copy=False)  # J's layout and sparsity, not its values
    squared.setValuesCSR(indptr, indices, values**2)
    squared.assemble()
    coupled = J.createVecLeft()
    squared.mult(inverse, coupled)  # sum_j J_ij^2 / |J_jj| over j with J_jj != 0
    s = coupled.getArray(readonly=True) - np.where(d > 0, d, 0.0)  # without j = i
    scale = np.maximum(d, s)
    D = J.createVecRight()
    D.setArray(np.divide(1.0, np.sqrt(scale), out=np.ones_like(scale), where=scale > 0))
    for obj in (diagonal, inverse, squared, coupled):
        obj.destroy()
    return D
