"""The numerical inf-sup test of a problem's displacement / multiplier pair (Chapelle and
Bathe, Computers & Structures 47, 1993).

For the reduced unknowns of a linear problem (its prolongation ``R``: the active dofs
and a restricted multiplier space), with the displacement norm ``A`` (the bulk matrix
with its ghost penalty over the largest Young's modulus ``E``, plus ``1 / D^2`` times
both sides' L2 mass, ``D`` the mesh's extent: a broken H1 norm that no free body's
rigid motion escapes), the coupling ``B`` (``int_Gamma mu . [v] ds``) and the
stabilisation ``C`` of the multiplier block (times ``E``: multipliers in units of ``E``),

    beta^2 = min over mu of  mu^T (B A^-1 B^T + C) mu / mu^T M mu,

with ``M`` the mesh-dependent multiplier norm ``||mu||^2 = int_Gamma h |mu|^2 ds`` (``h``
the cell diameter). That norm is the discrete form of ``H^-1/2(Gamma)``, the dual of the
displacement's trace space: for multipliers on a quasi-uniform mesh of the interface,
``c h^1/2 ||mu||_0 <= ||mu||_-1/2 <= C ||mu||_0``, and ``beta`` in it is bounded below
independently of ``h`` exactly when the pair is stable in ``H^1 x H^-1/2``. An unstable
pair (multipliers the displacements cannot see) shows ``beta`` falling as ``h -> 0``, to
zero for a spurious mode.
"""

from __future__ import annotations

import typing

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.fem.forms import form
from xfem_contact.solvers.assembly import ReducedMatrix

if typing.TYPE_CHECKING:
    from xfem_contact.mechanics.problem import Problem

#: Share of the largest eigenvalue of the multiplier norm below which a direction of the
#: multiplier space counts as without trace on the interface (left out of the test)
TRACE_TOLERANCE = 1e-12
#: Multiplier columns solved for at once (a dense block of the bulk's size times this)
BLOCK = 128


class InfSup(typing.NamedTuple):
    """Result of :func:`inf_sup_constant`."""

    beta: float  #: discrete inf-sup constant (dimensionless; 0 when ``beta_squared <= 0``)
    beta_squared: float  #: the least eigenvalue (negative: the pair's matrix is indefinite)
    multipliers: int  #: reduced multiplier unknowns tested
    without_trace: int  #: of them, directions with no trace on the interface
    #: negative eigenvalues of the displacement block (its bulk energy minus the
    #: Barbosa-Hughes term's share): 0 for a stable pair; else ``beta_squared`` < 0
    negative_displacement_modes: int = 0


def inf_sup_constant(problem: Problem, name: str | None = None) -> InfSup:
    """The discrete inf-sup constant of ``problem``'s pair on interface ``name`` (the
    only one for None). Collective; dense in the multiplier unknowns (a diagnostic for
    meshes of up to some thousand interface vertices).

    The problem's law must be linear (``"bonded"``: the pair's stability is that of its
    spaces and LBB treatment, not of the law's contact conditions).
    """
    name = problem._name(name)
    law, ctx = problem.law(name), problem.contexts[name]
    if not law.linear or ctx.field is None:
        raise ValueError(
            f"inf_sup_constant needs a linear law with a multiplier on {name!r} (e.g. "
            f"'bonded' with the LBB treatment to test), got {law.name!r}"
        )
    space, mesh, cut = problem.space, problem.mesh, problem.cut
    R = problem.prolongation()
    u, v = space.trial(), space.test()
    lam, mu = u[ctx.field], v[ctx.field]
    x = mesh.geometry.x
    size = mesh.comm.allreduce(np.ptp(x, axis=0).max() if x.size else 0.0, op=MPI.MAX)
    forms = (
        problem.bilinear_form(),
        sum(ufl.inner(u[f], v[f]) * cut.dx(side) for f, side in ((0, -1), (1, 1))),
        problem.cell_size * ufl.inner(lam, mu) * ctx.measure,
    )
    K, mass, M_full = (_reduced(form(a), R) for a in forms)
    multiplier_columns = _columns_of(R, space.W, ctx.field)
    lo, hi = K.getOwnershipRange()
    is_l = PETSc.IS().createGeneral(multiplier_columns.astype(PETSc.IntType), comm=mesh.comm)
    others = np.setdiff1d(np.arange(lo, hi), multiplier_columns).astype(PETSc.IntType)
    is_u = PETSc.IS().createGeneral(others, comm=mesh.comm)
    stiffness = max(float(m.E) for m in ctx.materials.values())
    A, Bt = K.createSubMatrix(is_u, is_u), K.createSubMatrix(is_u, is_l)
    C, M = K.createSubMatrix(is_l, is_l), M_full.createSubMatrix(is_l, is_l)
    A_mass = mass.createSubMatrix(is_u, is_u)
    A.scale(1.0 / stiffness)
    A.axpy(1.0 / size**2, A_mass)
    C.scale(stiffness)
    try:
        S, Md, negative = _schur_and_norm(A, Bt, C, M, mesh.comm)
    finally:
        for obj in (K, mass, M_full, A, A_mass, Bt, C, M, R, is_l, is_u):
            obj.destroy()
    # beta^2: the least eigenvalue of S in the M-orthonormal basis of M's range
    d, Q = np.linalg.eigh(Md)
    keep = d > TRACE_TOLERANCE * d.max()
    T = Q[:, keep] / np.sqrt(d[keep])
    beta2 = float(np.linalg.eigvalsh(T.T @ S @ T)[0]) if keep.any() else 0.0
    return InfSup(np.sqrt(max(beta2, 0.0)), beta2, int(S.shape[0]), int((~keep).sum()), negative)


def _reduced(a: dolfinx.fem.Form, R: PETSc.Mat) -> PETSc.Mat:
    """``R^T A R`` of the bilinear form ``a`` (collective; the caller destroys it)."""
    matrix = ReducedMatrix(a, [], R)
    matrix.assemble()
    return matrix.release()


def _columns_of(R: PETSc.Mat, W, field: int) -> np.ndarray:
    """Global reduced columns (owned by this process) that prolongate into ``field``."""
    _, dofs = W.sub(field).collapse()
    n_owned = W.dofmap.index_map.size_local * W.dofmap.index_map_bs
    indicator = R.createVecLeft()
    indicator.array[np.asarray(dofs)[np.asarray(dofs) < n_owned]] = 1.0
    columns = R.createVecRight()
    R.multTranspose(indicator, columns)
    lo, _ = columns.getOwnershipRange()
    found = np.flatnonzero(columns.array != 0.0) + lo
    indicator.destroy()
    columns.destroy()
    return found


def _schur_and_norm(A, Bt, C, M, comm) -> tuple[np.ndarray, np.ndarray, int]:
    """``B A^-1 B^T - C_block`` and ``M`` as dense arrays on every process (``C_block``
    the multiplier block of the problem's matrix, minus the stabilisation), and the
    number of negative eigenvalues of ``A`` (the negative pivots of its symmetric
    indefinite LDL^T, by Sylvester's law of inertia). One factorisation of ``A``,
    solved for :data:`BLOCK` multiplier columns at a time. Collective."""
    ksp = PETSc.KSP().create(comm)
    # symmetric, not SPD: with the Barbosa-Hughes term subtracted A may be indefinite
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setUp()
    factor = ksp.getPC().getFactorMatrix()
    negative = int(factor.getMumpsInfog(12))  # INFOG(12): negative pivots, all ranks
    n = M.getSize()[0]
    S, Md = np.empty((n, n)), np.empty((n, n))
    try:
        for start in range(0, n, BLOCK):
            stop = min(start + BLOCK, n)
            E = _unit_columns(M, start, stop)
            rhs = Bt.matMult(E)
            x = rhs.duplicate()
            factor.matSolve(rhs, x)
            blocks = (Bt.transposeMatMult(x), C.matMult(E), M.matMult(E))
            s, c, m = (np.concatenate(comm.allgather(b.getDenseArray().copy())) for b in blocks)
            S[:, start:stop], Md[:, start:stop] = s - c, m
            for obj in (E, rhs, x, *blocks):
                obj.destroy()
    finally:
        ksp.destroy()
    return 0.5 * (S + S.T), 0.5 * (Md + Md.T), negative


def _unit_columns(M: PETSc.Mat, start: int, stop: int) -> PETSc.Mat:
    """The dense matrix of the unit vectors ``e_start .. e_(stop-1)`` in ``M``'s row
    layout (collective)."""
    lo, hi = M.getOwnershipRange()
    E = PETSc.Mat().createDense(((hi - lo, M.getSize()[0]), (None, stop - start)), comm=M.getComm())
    E.setUp()
    E.zeroEntries()
    for j in range(max(start, lo), min(stop, hi)):
        E.setValue(j, j - start, 1.0)
    E.assemble()
    return E
