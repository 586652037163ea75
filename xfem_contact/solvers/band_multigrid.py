"""A preconditioner for the reduced contact Jacobians: p-multigrid plus an interface band.

One application to a residual ``r`` (a petsc4py Python PC, ``pc_type = python``):

1. ``x_u = MG(A_uu + B^T B) r_u``, zero elsewhere (``B = J_lu``, the multipliers' rows:
   the augmented-Lagrangian coupling of the two sides, which a law without
   augmentation, ``bonded``, does not put into ``A_uu``, leaving the inclusion floating
   there): the displacement block by one V-cycle of a two-level multigrid, degree 2
   on degree 1 (the interpolation ``P`` from each field's vertex values,
   :func:`xfem_contact.mechanics.fieldsplit_data.vertex_interpolation`). The fine level is
   ``A_uu`` read in place from ``J`` (a virtual sub-matrix: no copy), smoothed by
   Chebyshev-Jacobi; the coarse level ``P^T A_uu P + (B P)^T (B P)`` (augmented: it
   holds the floating bodies) by algebraic multigrid (GAMG with the rigid modes), so
   that memory and time grow linearly with the dofs: three Richardson iterations of its
   V-cycle (a fixed linear operator), or under a flexible Krylov method
   (:data:`~xfem_contact.solvers.options.FLEXIBLE_KRYLOV`, the outer ``ksp_type``)
   GMRES + GAMG to a relative tolerance, whose contraction does not degrade with the
   mesh size as the V-cycle's does. For degree 1, GAMG on the augmented block;
2. ``x_b += J_bb^-1 (r - J x)_b``: an exact (LU) solve on the band ``b``, the
   displacements of the cut cells and their facet neighbours (where the ghost penalty
   acts) and every multiplier.

Algebraic multigrid alone (GAMG on ``A_uu``, with the multipliers by a Schur
fieldsplit) does not suffice: the ghost-penalty rows make the degree-2 operator hard to
aggregate, and the multipliers couple only through the band. With the band solved
exactly and the bulk by the p-multigrid, the Krylov iteration count does not grow with
the mesh size nor with tiny cuts (measured by ``bench/iterative.py``). The band has
O(N) unknowns and the coarse level a quarter of the displacements'. The copies made
are the band's block ``J_bb`` (released once an LDL^T factorisation, which keeps its
own upper triangle, is made; ``(J x)_b`` is read from ``J`` itself), the multipliers'
rows ``B`` (during the set-up only) and the coarse level; everything but the
prolongations is released after each Krylov solve (the next set-up extracts it afresh).
A Jacobian stored by node blocks (BAIJ) gives its blocks through a transient AIJ copy.

Sub-solver options live under the PC's prefix plus ``bmg_u_`` (the PCMG, or GAMG for
degree 1) and ``bmg_band_`` (the band's LU); the rows ``band_u`` (or ``band_u_flexible``),
``band_u_degree1`` and ``band`` of :data:`~xfem_contact.solvers.options.PRESETS` are the
defaults, which options in the database override; a symmetric problem's band is factored
LDL^T (the row ``symmetric_band``), its matrix checked symmetric first, and a 3D
problem's is ordered by METIS (the row ``band_3d``).
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.solvers.assembly import aij
from xfem_contact.solvers.options import FLEXIBLE_KRYLOV, PRESETS
from xfem_contact.solvers.scaling import gather
from xfem_contact.solvers.symmetry import mark_symmetric


class BandMultigrid:
    """The Python context of the PC (see the module docstring).

    PETSc creates it from ``pc_python_type``; :meth:`configure` then gives it the
    index sets, the near null space and the interpolation, in the unknowns of the
    operator (the reduced, scaled numbering of
    :class:`~xfem_contact.solvers.newton.ReducedNewton`). Collective methods.
    """

    def __init__(self):
        self.u = self.band = self.J = None
        self._interpolation, self._degree2 = None, False
        self._prolongations: tuple | None = None  # (P, P in J's rows, coarse positions)
        self._modes: list[PETSc.Vec] = []  # owned: destroyed once restricted (degree 2)
        self._coarse_modes: list[PETSc.Vec] = []
        self._objects: list = []
        self._built = False

    def configure(self, u: PETSc.IS, band: PETSc.IS, modes: list[PETSc.Vec], interpolation):
        """Give the fieldsplits. Collective.

        Args:
            u: The displacement unknowns (owned, global indices of the operator).
            band: The band's unknowns (owned, global indices).
            modes: Near null space of ``A_uu`` (vectors laid out as ``u``); this object
                takes them over (and destroys them).
            interpolation: ``None`` (degree 1), or ``(rows, cols, weights)``: global
                unknowns of the operator, rows owned or not (sent to their owners), each
                a displacement unknown, cols the vertex unknowns it interpolates from
                (the coarse unknowns).
        """
        self._forget_prolongations()
        self._forget_modes()
        self.u, self.band, self._modes = u, band, list(modes)
        self._degree2 = interpolation is not None
        self._interpolation = interpolation  # released once the prolongations are built

    def _forget_prolongations(self) -> None:
        if self._prolongations is not None:
            for mat in self._prolongations[:2]:
                mat.destroy()
        self._prolongations = None
        for vector in self._coarse_modes:
            vector.destroy()
        self._coarse_modes = []

    def _forget_modes(self) -> None:
        for vector in self._modes:
            vector.destroy()
        self._modes = []

    # -- PETSc's callbacks ---------------------------------------------------------
    def setUp(self, pc: PETSc.PC) -> None:
        if self.u is None:
            raise RuntimeError("BandMultigrid: configure() was not called before the solve")
        J = pc.getOperators()[1]
        prefix = pc.getOptionsPrefix() or ""
        self.reset(pc)  # the blocks, the augmented block and its coarse level afresh
        self._build(J, prefix)
        for ksp, row in ((self.ksp_band, PRESETS["band"]), (self.ksp_u, self.u_preset)):
            with _defaults(ksp.getOptionsPrefix(), row.options):
                ksp.setFromOptions()
                if ksp.getPC().getType() == PETSc.PC.Type.CHOLESKY:
                    mark_symmetric(ksp.getOperators()[0])  # checked, then flagged
                ksp.setUp()
            if ksp is self.ksp_band:
                self._release_band_block()

    def _release_band_block(self) -> None:
        """With an LDL^T factorisation (which keeps the band's upper triangle itself),
        solve the band by the factors and release ``J_bb`` and its solver."""
        self._solve_band = self.ksp_band.solve
        if self.ksp_band.getPC().getType() != PETSc.PC.Type.CHOLESKY:
            return
        factor = self.ksp_band.getPC().getFactorMatrix()
        self._solve_band = factor.solve
        self._objects.append(factor)
        for obj in (self.ksp_band, self.J_bb):
            obj.destroy()
        self.ksp_band = self.J_bb = None

    def postSolve(self, pc: PETSc.PC, ksp: PETSc.KSP, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """Release the blocks and the factorisation after each Krylov solve: the next
        Newton step's set-up extracts them afresh anyway, and the residual assembled
        meanwhile does not add its memory to theirs."""
        self.reset(pc)

    def apply(self, pc: PETSc.PC, r: PETSc.Vec, x: PETSc.Vec) -> None:
        if not self._built:  # a solve with operators unchanged since the last one
            self.setUp(pc)
        x.set(0.0)
        r_u, x_u = r.getSubVector(self.u), x.getSubVector(self.u)
        self.ksp_u.solve(r_u, x_u)
        r.restoreSubVector(self.u, r_u)
        x.restoreSubVector(self.u, x_u)
        self.J.mult(x, self.Jx)  # (r - J x)_b from J itself: no copy of the band's rows
        self.Jx.aypx(-1.0, r)
        self.Jx.getSubVector(self.band, self.r_b)
        self._solve_band(self.r_b, self.x_b)
        self.Jx.restoreSubVector(self.band, self.r_b)
        x_b = x.getSubVector(self.band)
        x_b.axpy(1.0, self.x_b)
        x.restoreSubVector(self.band, x_b)

    def view(self, pc: PETSc.PC, viewer: PETSc.Viewer | None = None) -> None:
        if viewer is not None and self.u is not None:
            levels = "degree 2 on degree 1, coarse GAMG" if self._degree2 else "GAMG"
            viewer.printfASCII(
                f"  band multigrid: {self.band.getSize()} band unknowns (LU), "
                f"{self.u.getSize()} displacements ({levels})\n"
            )

    def reset(self, pc: PETSc.PC | None = None) -> None:
        """Forget the operators' blocks. Every set-up extracts them afresh (a
        large-sliding coupling may have grown the operator's pattern since), and PETSc
        calls it when the pattern changed."""
        for obj in self._objects:
            obj.destroy()
        self._objects = []
        self.J = None
        self._built = False

    def destroy(self, pc: PETSc.PC | None = None) -> None:
        self.reset(pc)
        self._forget_prolongations()
        self._forget_modes()

    # -- construction --------------------------------------------------------------
    def _build(self, J_given: PETSc.Mat, prefix: str) -> None:
        J, copied = aij(J_given)  # the blocks are taken from AIJ storage
        try:
            self._build_from(J, J_given, prefix)
        finally:
            if copied:
                J.destroy()

    def _build_from(self, J: PETSc.Mat, J_given: PETSc.Mat, prefix: str) -> None:
        """The blocks from ``J`` (AIJ), the fine level reading ``J_given`` in place."""
        comm = J.getComm()
        first, last = J.getOwnershipRange()
        self.all_columns = PETSc.IS().createStride(last - first, first, 1, comm=comm)
        others = np.setdiff1d(np.arange(first, last), self.u.getIndices())
        multipliers = PETSc.IS().createGeneral(others.astype(PETSc.IntType), comm=comm)
        # the multipliers' rows: on u for degree 1, on all columns for degree 2 (``B P``
        # as ``B_all P_full``: P_full's rows outside u are zero)
        self.B = J.createSubMatrix(multipliers, self.all_columns if self._degree2 else self.u)
        self.J = J_given  # multiplied by in place (the residual on the band)
        self.J_bb = J.createSubMatrix(self.band, self.band)  # to factor
        self.Jx, self.x_b = J_given.createVecLeft(), self.J_bb.createVecRight()
        self.r_b = PETSc.Vec()  # a view of Jx's band part during each application
        self.ksp_band = PETSc.KSP().create(comm)
        self.ksp_band.setOptionsPrefix(prefix + PRESETS["band"].prefix)
        self.ksp_band.setOperators(self.J_bb)
        self.ksp_u = PETSc.KSP().create(comm)
        self.ksp_u.setOptionsPrefix(prefix + PRESETS["band_u"].prefix)
        space = PETSc.NullSpace().create(vectors=self._modes, comm=comm)
        self.P = self.A_c = None
        self._objects = [self.all_columns, multipliers, self.J_bb, self.Jx, self.x_b]
        self._objects += [self.ksp_band, self.ksp_u]
        if not self._degree2:  # degree 1: GAMG on the augmented block
            self.u_preset = PRESETS["band_u_degree1"]
            self.A = J.createSubMatrix(self.u, self.u)
            BtB = _gram(self.B)
            self.A.axpy(1.0, BtB, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            self.A.setBlockSize(self.u.getBlockSize())
            space = PETSc.NullSpace().create(vectors=self._modes, comm=comm)
            self.A.setNearNullSpace(space)
            self.ksp_u.setOperators(self.A)
            self._objects += [self.A, space]
            BtB.destroy()
        else:  # degree 2: J's block itself (no copy) smoothed, the coarse level augmented
            self.u_preset = PRESETS["band_u_flexible" if _flexible(prefix) else "band_u"]
            if self._prolongations is None:  # the pattern of J does not change them
                self._prolongations = _prolongation(J, self.u, *self._interpolation)
                self._interpolation = None
                # the near null space on the coarse unknowns only, the modes released
                coarse = self._prolongations[2]
                self._coarse_modes = _orthonormal([_restricted(m, coarse) for m in self._modes])
                self._forget_modes()
            self.P, self.P_full, coarse = self._prolongations  # P: P_full's rows u (a view)
            #: Local positions in ``u`` of the owned coarse (vertex) unknowns
            self.coarse_positions = coarse
            self.A = PETSc.Mat().createSubMatrixVirtual(J_given, self.u, self.u)
            product = J.PtAP(self.P_full)  # which keeps J (maybe a copy) alive: copied
            self.A_c = product.duplicate(copy=True)
            product.destroy()
            BP = self.B.matMult(self.P_full)
            BtB = _gram(BP)
            self.A_c.axpy(1.0, BtB, PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
            self.A_c.setBlockSize(self.u.getBlockSize())
            coarse_space = PETSc.NullSpace().create(vectors=self._coarse_modes, comm=comm)
            self.A_c.setNearNullSpace(coarse_space)
            self.ksp_u.setOperators(self.A)
            mg = self.ksp_u.getPC()
            mg.setType(PETSc.PC.Type.MG)
            mg.setMGLevels(2)
            mg.setMGInterpolation(1, self.P)
            mg.getMGCoarseSolve().setOperators(self.A_c, self.A_c)
            mg.getMGSmoother(1).setOperators(self.A, self.A)
            self._objects += [self.A, self.A_c, coarse_space]
            for obj in (BP, BtB):
                obj.destroy()
        self.B.destroy()  # the multipliers' rows serve the set-up only
        self.B = None
        self._built = True


def _gram(B: PETSc.Mat) -> PETSc.Mat:
    """``B^T B`` (a new matrix; the caller destroys it). Collective."""
    Bt = B.transpose(PETSc.Mat())  # (PETSc 3.25: B.transposeMatMult(B) failed on a process
    BtB = Bt.matMult(B)  # without multiplier rows)
    Bt.destroy()
    return BtB


def _prolongation(
    J: PETSc.Mat, u: PETSc.IS, rows, cols, weights
) -> tuple[PETSc.Mat, PETSc.Mat, np.ndarray]:
    """``P_full`` from the coarse unknowns (the distinct ``cols`` of every process, each
    numbered by its owner, process by process in the order of their global index) into
    all of ``J``'s unknowns (zero rows outside ``u``: ``P_full^T J P_full`` is the coarse
    ``P^T J_uu P`` without extracting ``J_uu``); ``P``, its rows ``u`` (a virtual
    sub-matrix: no copy); and the positions in ``u``'s local part of the owned coarse
    unknowns. Collective; raises on every process if the interpolation does not fit."""
    comm = u.getComm()
    owned_u = u.getIndices()
    first, last = J.getOwnershipRange()
    rows, cols, weights = _to_owners(J, rows, cols, weights)
    # the owned columns that some process interpolates from: a vertex's owner need not
    # hold a cell on which the field is active around it (its rows then do not name it)
    referenced = J.createVecRight()
    wanted = np.unique(cols).astype(PETSc.IntType)
    referenced.setValues(wanted, np.ones(wanted.size), addv=PETSc.InsertMode.ADD_VALUES)
    referenced.assemble()
    coarse = np.flatnonzero(referenced.getArray(readonly=True) > 0.0) + first  # by index
    referenced.destroy()
    offset = comm.tompi4py().exscan(coarse.size) or 0
    # the coarse number of every column, from its owner
    number = J.createVecRight()
    values = np.full(last - first, -1.0)
    values[coarse - first] = offset + np.arange(coarse.size)  # exact below 2^53
    number.setArray(values)
    coarse_cols = np.rint(gather(number, cols)).astype(PETSc.IntType)
    number.destroy()
    fits = not np.any(coarse_cols < 0) and np.all(np.isin(rows, owned_u))
    if not comm.tompi4py().allreduce(bool(fits and np.all(np.isin(coarse, owned_u))), MPI.LAND):
        raise RuntimeError("BandMultigrid: the interpolation does not fit the fieldsplits")
    order = np.lexsort((coarse_cols, rows))
    rows, coarse_cols, weights = rows[order], coarse_cols[order], weights[order]
    indptr = np.searchsorted(rows, np.arange(first, last + 1)).astype(PETSc.IntType)
    P_full = PETSc.Mat().createAIJ(
        ((last - first, PETSc.DETERMINE), (coarse.size, PETSc.DETERMINE)), comm=comm
    )
    P_full.setPreallocationCSR((indptr, coarse_cols, weights))
    P_full.assemble()
    columns = PETSc.IS().createStride(coarse.size, offset, 1, comm=comm)
    P = PETSc.Mat().createSubMatrixVirtual(P_full, u, columns)
    columns.destroy()
    by_index = np.argsort(owned_u)  # u need not be sorted (side -1's nodes, then +1's)
    positions = by_index[np.searchsorted(owned_u, coarse, sorter=by_index)]
    return P, P_full, positions


def _to_owners(J: PETSc.Mat, rows, cols, weights) -> tuple[np.ndarray, ...]:
    """The interpolation's entries ``(row, col, weight)`` on the processes that own their
    rows (from every process that has them), each ``(row, col)`` once. Collective."""
    comm = J.getComm().tompi4py()
    ranges = J.getOwnershipRanges()
    owner = np.searchsorted(ranges, rows, side="right") - 1
    sent = [(rows[owner == p], cols[owner == p], weights[owner == p]) for p in range(comm.size)]
    received = comm.alltoall(sent)
    rows, cols, weights = (np.concatenate([r[k] for r in received]) for k in range(3))
    _, once = np.unique(np.stack([rows, cols]), axis=1, return_index=True)
    return rows[once], cols[once], weights[once]


def _restricted(mode: PETSc.Vec, positions: np.ndarray) -> PETSc.Vec:
    """The entries of ``mode`` (laid out as ``u``) at the owned coarse unknowns."""
    values = mode.getArray(readonly=True)[positions].copy()
    return PETSc.Vec().createWithArray(values, comm=mode.getComm())


def _orthonormal(vectors: list[PETSc.Vec]) -> list[PETSc.Vec]:
    """Gram-Schmidt; vectors that vanish are dropped."""
    kept = []
    for v in vectors:
        for q in kept:
            v.axpy(-v.dot(q), q)
        norm = v.norm()
        if norm > 1e-12:
            v.scale(1.0 / norm)
            kept.append(v)
        else:
            v.destroy()
    return kept


def _flexible(prefix: str) -> bool:
    """Whether the Krylov method of the PC's options ``prefix`` (its ``ksp_type`` in the
    options database, which the package's solvers fill during each solve) is one of
    :data:`~xfem_contact.solvers.options.FLEXIBLE_KRYLOV`. Not collective."""
    return PETSc.Options().getString(prefix + "ksp_type", "") in FLEXIBLE_KRYLOV


class _defaults:
    """Write default options under a prefix for a ``setFromOptions`` unless the
    database has them already; remove what was written afterwards."""

    def __init__(self, prefix: str, options: dict):
        self.prefix, self.options, self.written = prefix, options, []

    def __enter__(self):
        database = PETSc.Options()
        for key, value in self.options.items():
            name = self.prefix + key
            if not database.hasName(name):
                database[name] = value
                self.written.append(name)

    def __exit__(self, *exc):
        database = PETSc.Options()
        for name in self.written:
            database.delValue(name)
        return False
