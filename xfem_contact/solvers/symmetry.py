"""The symmetric factorisation (MUMPS LDL^T) of symmetric Jacobians, and its guard.

Sticking and frictionless contact (augmented Lagrangian, generalized Newton), bonded
interfaces and the bulk give symmetric (indefinite) Jacobians: an LDL^T factorisation
(``pc_type = "cholesky"``: MUMPS with ``SYM = 2``, 2 x 2 pivots) takes about half
the factor entries and flops of an LU. Coulomb friction (slip) and
large sliding give unsymmetric ones and keep the LU.

Which laws are symmetric is a property of each law
(:attr:`~xfem_contact.mechanics.laws.base.InterfaceLaw.symmetric`); every matrix
handed to the symmetric factorisation is checked first (:func:`mark_symmetric`), so a
wrong declaration or a user's ``pc_type = "cholesky"`` on an unsymmetric problem is an
error, never an LDL^T of a matrix it does not represent. The option itself is the row
``"symmetric"`` of :data:`~xfem_contact.solvers.options.PRESETS`.
"""

from __future__ import annotations

import numpy as np
from petsc4py import PETSc

#: ``|y.Ax - x.Ay|`` allowed, relative to ``|y| |Ax| + |x| |Ay|`` (round-off is ~1e-16;
#: an unsymmetric interface block is detected well above 1e-8)
TOLERANCE = 1e-12


def symmetry_gap(A: PETSc.Mat) -> tuple[float, float]:
    """``(|y.Ax - x.Ay|, |y| |Ax| + |x| |Ay|)`` for two random vectors ``x``, ``y`` (the
    same on every run): ``A`` is symmetric to ``tol`` when the first is at most ``tol``
    times the second. Two matrix-vector products. Collective."""
    x, y = A.createVecs()
    rank = A.getComm().getRank()
    for k, v in enumerate((x, y)):
        v.setArray(np.random.default_rng([k, rank]).standard_normal(v.getLocalSize()))
    Ax, Ay = x.duplicate(), y.duplicate()
    A.mult(x, Ax)
    A.mult(y, Ay)
    gap = abs(y.dot(Ax) - x.dot(Ay))
    scale = y.norm() * Ax.norm() + x.norm() * Ay.norm()
    for v in (x, y, Ax, Ay):
        v.destroy()
    return gap, scale


def mark_symmetric(A: PETSc.Mat) -> None:
    """Check that ``A`` is symmetric (:func:`symmetry_gap`, to :data:`TOLERANCE`) and
    flag it so for PETSc's symmetric factorisations. Collective.

    Raises:
        ValueError: ``A`` is not symmetric.
    """
    gap, scale = symmetry_gap(A)
    if not gap <= TOLERANCE * scale:
        raise ValueError(
            f"The matrix for the symmetric factorisation (pc_type = 'cholesky') is not "
            f"symmetric: |y.Ax - x.Ay| = {gap:.2e} for |y| |Ax| + |x| |Ay| = {scale:.2e}; "
            "use pc_type = 'lu'"
        )
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
