"""Generalized Newton (PETSc SNES) on the reduced space ``y`` with ``x = R y``.

Residual and Jacobian are assembled with Dirichlet conditions (as
:class:`dolfinx.fem.petsc.NonlinearProblem` does) and reduced: ``F_r = R^T F(R y)``,
``J_r = R^T J R`` (straight into the reduced numbering,
:mod:`xfem_contact.solvers.assembly`), the same prolongation as the linear solves of
:mod:`xfem_contact.solvers.linear`. Every iterate is logged (INFO on this module's
logger: residual norm and, through a callback, e.g. the contact status); failure raises
with the whole history. Default options: :mod:`xfem_contact.solvers.options`.
"""

from __future__ import annotations

import logging
import weakref
from collections.abc import Callable

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact._deprecation import renamed, renamed_keyword
from xfem_contact._timers import phase, seconds
from xfem_contact.fem.forms import form_parts
from xfem_contact.fem.prolongation import prescribed_offset
from xfem_contact.solvers.assembly import ReducedMatrix, selection
from xfem_contact.solvers.block_scaling import TipFactor
from xfem_contact.solvers.callback_errors import raised_as_themselves
from xfem_contact.solvers.fieldsplit_sets import fieldsplit_sets
from xfem_contact.solvers.jacobian import JacobianForms
from xfem_contact.solvers.options import (
    REFACTOR_AFTER,
    applied_options,
    checked_prefix,
    merged_options,
    uses_band_multigrid,
)
from xfem_contact.solvers.report import NewtonFailure, NewtonReport
from xfem_contact.solvers.scaling import saddle_point_scaling
from xfem_contact.solvers.symmetry import mark_symmetric

logger = logging.getLogger(__name__)

#: Stagnation test of :class:`ReducedNewton`: a solve stops (``reason`` :data:`STALLED`)
#: when none of the last ``STALL_WINDOW`` iterates has a residual norm below
#: ``STALL_FACTOR`` times the least of those before them (Newton cycling among a few
#: active sets or stuck where the residual has no root nearby, not converging slowly or
#: descending again, see :func:`stalled`)
STALL_WINDOW, STALL_FACTOR = 4, 0.9
#: The reason of a stalled solve: PETSc's ``SNES_DIVERGED_LOCAL_MIN``
STALLED = int(PETSc.SNES.ConvergedReason.DIVERGED_LOCAL_MIN)


class ReducedNewton:
    """Solve ``F(w; v) = 0`` for ``w = R y`` on the reduced space of ``R``.

    Construction is collective (it compiles the forms, builds the sparsity of
    ``R^T J R`` (:class:`~xfem_contact.solvers.assembly.ReducedMatrix`), assembles the
    Jacobian once for the scaling ``D`` of :mod:`xfem_contact.solvers.scaling` (the
    first iterate reuses it when it sits at the same state), and creates the SNES
    under its options prefix, removing its options from the PETSc database
    afterwards). SNES iterates on the scaled unknowns ``y`` with ``w = R D y``, so the
    residual norms it reports are those of ``D R^T F``. Each :meth:`solve` starts from
    the current ``w`` (projected on the range of ``R D``), stops early when the residual
    norms stall (:func:`stalled`) and checks the final residual against the tolerances.
    With ``pc_type = "cholesky"`` every Jacobian is checked to be symmetric first
    (:func:`~xfem_contact.solvers.symmetry.mark_symmetric`). A Krylov method over a
    factorisation (``pc_type`` lu or cholesky, e.g. the preset ``reused_lu`` of
    :data:`~xfem_contact.solvers.options.PRESETS`) keeps the factorisation of an earlier
    iterate of the same solve: it refactors at the first iterate, when the pattern grows,
    and after a linear solve that failed or took more than
    :data:`~xfem_contact.solvers.options.REFACTOR_AFTER` iterations; such a failed linear
    solve does not end the Newton solve (its step is taken as it is, the final residual
    check stands).

    Args:
        residual: UFL residual form, linear in the test function, on the full
            mixed space ``W`` of ``w``.
        w: The unknown on ``W``; set to ``R y`` at every iterate and after the solve.
        bcs: Dirichlet conditions on ``W``.
        R: Prolongation, global shape ``(dim W, n_reduced)``, see
            :func:`xfem_contact.fem.prolongation.prolongation_matrix`. Not modified:
            the solver keeps its own scaled copy ``R D`` (:attr:`R`).
        petsc_options: PETSc options (without prefix) overriding the ``"newton"``
            defaults of :data:`xfem_contact.solvers.options.SOLVER_OPTIONS`.
        petsc_options_prefix: Options prefix of the SNES (and its KSP and PC); ``None``:
            a unique one.
        status: Called with ``w`` at every iterate, on every process; returns a
            dict shown in the log.
        fieldsplit_dofs: For a ``fieldsplit`` preconditioner, or the band multigrid of
            the ``"iterative"`` preset of :data:`~xfem_contact.solvers.options.PRESETS`
            (which reads ``"u"`` and ``"band"``): fieldsplit name to the
            local dofs of ``W`` it holds: shape ``(n,)``, the reduced unknowns touching
            them; or ``(n, bs)``, blocks of dofs that are reduced unknowns themselves
            (a node's components), kept together as blocks of size ``bs`` (what
            algebraic multigrid needs for elasticity). Ignored by other preconditioners.
        near_nullspace: Functions on ``W`` (e.g. rigid modes) given, reduced and
            orthonormalised, as the near null space of the fieldsplit named ``"u"``.
        couplings: Terms assembled outside UFL (e.g. the large-sliding hybrid
            elements of :class:`~xfem_contact.mechanics.sliding.coupling.SlidingCoupling`):
            objects with ``bind(columns, bcs)``, ``begin_step(w)``,
            ``add_residual(w, b)`` (into the residual of ``W``, global numbering) and
            ``add_jacobian(w, J)`` (into the unscaled reduced Jacobian). They need a
            selecting ``R`` (no multiplier prolongation).
        interpolation: For the band multigrid (the ``"iterative"`` preset): ``(rows,
            cols, weights)`` on local dofs of ``W``
            (:func:`xfem_contact.mechanics.fieldsplit_data.vertex_interpolation`), or ``None``.
        field_space: ``field_space(i)``: field ``i``'s own space and the parent dofs
            (:meth:`EnrichedSpace.field_space
            <xfem_contact.fem.enrichment.EnrichedSpace.field_space>`). With a selecting
            ``R`` the Jacobian's uncut cells and ghost penalty are then assembled field
            by field on those spaces (:func:`xfem_contact.fem.field_blocks.uncut_field_blocks`).
        transform: ``transform(R, J_r)``: a change of unknowns ``Z`` made from the first
            unscaled reduced Jacobian (a crack's tip enrichment,
            :func:`~xfem_contact.solvers.block_scaling.tip_scaling`): each Newton step
            then factors ``Z^T J_r Z`` (:class:`~xfem_contact.solvers.block_scaling.TipFactor`);
            SNES's unknowns and residual norms stay ``D``-scaled. Not with couplings or a
            fieldsplit preconditioner.
        extension: The prescribed part ``E`` of cell aggregation's extension
            (:func:`~xfem_contact.fem.prolongation.prescribed_extension`, for the same
            ``R``), or None: the iterates are then ``w = E g + R y``, ``g`` the Dirichlet
            values when a solve starts. Not destroyed.
        splits: Deprecated name of ``fieldsplit_dofs``.
    """

    def __init__(
        self,
        residual: ufl.Form,
        w: dolfinx.fem.Function,
        bcs: list,
        R: PETSc.Mat,
        petsc_options: dict | None = None,
        petsc_options_prefix: str | None = None,
        status: Callable[[dolfinx.fem.Function], dict] | None = None,
        fieldsplit_dofs: dict[str, np.ndarray] | None = None,
        near_nullspace: list[dolfinx.fem.Function] | None = None,
        couplings: list | None = None,
        interpolation=None,
        field_space: Callable | None = None,
        transform: Callable[[PETSc.Mat, PETSc.Mat], PETSc.Mat] | None = None,
        extension: PETSc.Mat | None = None,
        *,
        splits: dict[str, np.ndarray] | None = None,
    ):
        fieldsplit_dofs = renamed_keyword(
            "ReducedNewton", "splits", "fieldsplit_dofs", splits, fieldsplit_dofs
        )
        self.w, self.bcs, self.R = w, bcs, R
        self.extension = extension
        #: ``E g`` of the current solve (None without an extension)
        self.offset: PETSc.Vec | None = None
        self.couplings = list(couplings or [])
        timer = phase("Newton set-up: selection")
        chosen = selection(R, w.function_space)
        selecting = seconds(timer)
        timer = phase("Newton set-up: forms")
        self.F = form_parts(residual)  # the residual: standard and runtime integrals apart
        #: The Jacobian's forms (the uncut cells' field blocks apart when possible)
        self.jacobian_forms = JacobianForms(residual, w, None if chosen is None else field_space)
        self.J = self.jacobian_forms.rest
        #: Wall time (s) of the set-up steps: forms (JIT included on a cold cache),
        #: sparsity, first Jacobian, scaling
        self.timings = {"forms": seconds(timer)}
        self.b = dolfinx.fem.petsc.create_vector(self.F[0].function_spaces[0])
        self.y = R.createVecRight()
        self.F_r = R.createVecRight()
        self.status = status
        #: The PETSc options (without prefix) of this solver's SNES, KSP and PC
        self.options = merged_options("newton", petsc_options)
        timer = phase("Newton set-up: sparsity")
        self.jacobian = ReducedMatrix(
            self.J,
            bcs,
            R,
            blocks=not self.couplings,
            field_blocks=self.jacobian_forms.blocks,
            chosen=chosen,
            # the band multigrid extracts its blocks from a copy (assembly.aij)
            node_storage=uses_band_multigrid(self.options) and transform is None,
        )
        self.timings["sparsity"] = seconds(timer) + selecting
        if self.couplings and not self.jacobian.direct:
            raise ValueError(
                "Couplings assembled outside UFL (large sliding) need a prolongation that "
                "selects dofs: no multiplier prolongation (lbb = 'restriction')"
            )
        for coupling in self.couplings:
            coupling.bind(self.jacobian.selection.columns, bcs)
        # Solve for y_s with x = R D y_s, D the scaling of the first Jacobian (well
        # scaled saddle points: see xfem_contact.solvers.scaling); J_r = D R^T J R D
        timer = phase("Newton set-up: first Jacobian")
        self.J_r = self.jacobian.assemble()
        self.timings["jacobian"] = seconds(timer)
        timer = phase("Newton set-up: scaling")
        self.D = saddle_point_scaling(self.J_r)
        Z = None if transform is None else transform(R, self.J_r)
        self.J_r.diagonalScale(self.D, self.D)
        self.timings["scaling"] = seconds(timer)
        self._symmetric = self.options.get("pc_type") == "cholesky"
        #: Whether factorisations are reused across iterates (see the class docstring)
        self.reuses_factor = transform is None and self.options.get("ksp_type") != "preonly"
        self.reuses_factor &= self.options.get("pc_type") in ("lu", "cholesky")
        if self._symmetric:
            mark_symmetric(self.J_r)
        self.R = R.copy()
        self.R.diagonalScale(None, self.D)
        # The first Newton iterate usually sits where this Jacobian was assembled
        self._assembled_at = None if self.couplings else w.x.array.copy()
        self.snes = PETSc.SNES().create(R.getComm())
        # Options live in the PETSc database only while PETSc may read them (here and
        # during each solve, when the factorisation reads e.g. mat_mumps_* options)
        self._prefix = checked_prefix(petsc_options_prefix, "xfem_newton_")
        self.snes.setOptionsPrefix(self._prefix)
        with applied_options(self._prefix, self.options):
            self.snes.setFromOptions()
            if self.reuses_factor:  # a reused factor's GMRES may fail: the next refactors
                self.snes.setMaxLinearSolveFailures(self.snes.getTolerances()[3])
            #: The factorisation through the tip enrichment's change of unknowns, or None
            self.tip = None if Z is None else TipFactor(self.snes, Z, self.D, self._symmetric)
        self._fieldsplit_objects = fieldsplit_sets(
            self.snes.getKSP().getPC(),
            self.R,
            self.D,
            self.w,
            self.jacobian.selection,
            fieldsplit_dofs or {},
            near_nullspace or [],
            interpolation,
        )
        # PETSc keeps its callbacks alive, and the garbage collector cannot see through
        # PETSc objects: callbacks hold this object weakly, or it would never be freed.
        this = weakref.ref(self)
        self.snes.setFunction(lambda snes, y, F: this()._residual(snes, y, F), self.F_r)
        #: The preconditioner's matrix: a copy of an earlier iterate's Jacobian when
        #: factorisations are reused, else the Jacobian itself
        self.P = self.J_r.duplicate(copy=True) if self.reuses_factor else self.J_r
        if self.reuses_factor:
            self.P.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
        self.snes.setJacobian(
            lambda snes, y, J, P: this()._jacobian(snes, y, J, P), self.J_r, self.P
        )
        self.snes.setMonitor(lambda snes, it, norm: this()._monitor(snes, it, norm))
        self.report = NewtonReport()

    def _update(self, y: PETSc.Vec) -> None:
        x = self.w.x.petsc_vec
        self.R.mult(y, x)
        if self.offset is not None:
            x.axpy(1.0, self.offset)
        self.w.x.scatter_forward()

    def _residual(self, snes, y, F_r):
        timer = phase("Newton assembly")
        self._update(y)
        x = self.w.x.petsc_vec
        with self.b.localForm() as local:
            local.set(0.0)
        for part in self.F:
            dolfinx.fem.petsc.assemble_vector(self.b, part)
        self.jacobian_forms.lift(self.b, self.bcs, x)
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        for coupling in self.couplings:
            coupling.add_residual(self.w, self.b)
        dolfinx.fem.petsc.set_bc(self.b, self.bcs, x, -1.0)
        self.R.multTranspose(self.b, F_r)
        self.report.assembly_time += seconds(timer)

    def _jacobian(self, snes, y, J_r, P_r):
        timer = phase("Newton assembly")
        self._update(y)
        x, at, self._assembled_at = self.w.x.array, self._assembled_at, None
        if at is None or not _same_state(x, at, self.R.getComm().tompi4py()):
            self.jacobian.assemble()  # into J_r, the same matrix
            if self.couplings:
                self._add_couplings(J_r)
            J_r.diagonalScale(self.D, self.D)
            if self._symmetric:
                mark_symmetric(J_r)
        # the preconditioner's own copy, taken anew only when needed (the callback's J_r
        # and P_r are new Python objects even when they wrap one matrix)
        if self.P is not self.J_r:
            grown = J_r.getInfo(_GLOBAL)["nz_allocated"] != P_r.getInfo(_GLOBAL)["nz_allocated"]
            if grown or self._refactor(snes):
                J_r.copy(P_r, _DIFFERENT if grown else _SAME)
                if self._symmetric:
                    mark_symmetric(P_r)
        self.report.assembly_time += seconds(timer)

    def _refactor(self, snes) -> bool:
        """Whether the preconditioner takes the Jacobian of this iterate: at the first
        iterate of a solve, or after a linear solve that failed or took more than
        ``REFACTOR_AFTER`` Krylov iterations. Otherwise its matrix, hence its
        factorisation, stays that of an earlier iterate (PETSc refactors only a
        preconditioning matrix that changed)."""
        ksp = snes.getKSP()
        stale = ksp.getConvergedReason() <= 0 or ksp.getIterationNumber() > REFACTOR_AFTER
        return snes.getIterationNumber() == 0 or stale

    def _add_couplings(self, J_r) -> None:
        """Add the couplings' Jacobians. A coupling that grows the pattern replaces
        the matrix's storage (PETSc's merge), which the preconditioner does not see as
        a new pattern: its factorisation is then reset. Collective."""
        size = J_r.getInfo(_GLOBAL)["nz_allocated"]
        for coupling in self.couplings:
            coupling.add_jacobian(self.w, J_r)
        if J_r.getInfo(_GLOBAL)["nz_allocated"] != size:
            self.snes.getKSP().getPC().reset()

    def _monitor(self, snes, it, norm):
        timer = phase("Newton interface status")
        if it > 0:
            self.report.linear_iterations.append(snes.getKSP().getIterationNumber())
        self.report.residuals.append(float(norm))
        status = self.status(self.w) if self.status else {}
        self.report.status.append(status)
        self.report.status_time += seconds(timer)
        self._log(snes, it, norm, status)
        # SNES monitors after its convergence test and stops on the reason it then holds
        if snes.getConvergedReason() == 0 and stalled(self.report.residuals):
            snes.setConvergedReason(STALLED)

    def _log(self, snes, it: int, norm: float, status: dict) -> None:
        if logger.isEnabledFor(logging.INFO):
            krylov = ""
            if it > 0 and snes.getKSP().getType() != PETSc.KSP.Type.PREONLY:
                krylov = f"  ({self.report.linear_iterations[-1]} Krylov iterations)"
            logger.info(
                f"  Newton {it:2d}: |F| = {norm:.3e}  "
                + "  ".join(f"{k} {v}" for k, v in status.items())
                + krylov
            )

    def _start_from_w(self) -> None:
        """``y`` from the current ``w``: the least-squares ``(R^T R)^-1 R^T (w - E g)``
        (exact when ``w`` lies in the range, e.g. after a previous solve), by CG on
        ``R^T R``, with the offset ``E g`` taken anew from the Dirichlet values; the
        matrix and its solver are destroyed afterwards (they would stay allocated
        through the Newton solve, whose peak memory they would add to)."""
        if self.extension is not None:
            if self.offset is not None:
                self.offset.destroy()
            self.offset = prescribed_offset(self.extension, self.bcs, self.w.function_space)
        RtR = self.R.transposeMatMult(self.R)
        projection = PETSc.KSP().create(self.R.getComm())
        projection.setOperators(RtR)
        projection.setType("cg")
        projection.getPC().setType("jacobi")
        projection.setTolerances(rtol=1e-14, atol=0.0, max_it=1000)
        rhs = self.R.createVecRight()
        shifted = self.w.x.petsc_vec.copy()
        if self.offset is not None:
            shifted.axpy(-1.0, self.offset)
        self.R.multTranspose(shifted, rhs)
        shifted.destroy()
        projection.solve(rhs, self.y)
        for obj in (projection, RtR, rhs):
            obj.destroy()

    def final_residual(self) -> float:
        """``|D R^T F(w)|`` at the current iterate (collective)."""
        self._residual(None, self.y, self.F_r)
        return self.F_r.norm()

    def residual_of_w(self) -> float:
        """``|D R^T F(R D y)|`` with ``y`` the projection of the current ``w`` on the
        range of ``R D`` (as a solve starts from it); ``w`` becomes ``R D y`` and the
        current iterate ``y``. Collective."""
        self._start_from_w()
        return self.final_residual()

    def solve(self) -> NewtonReport:
        """Run SNES from the current reduced iterate. Collective.

        Returns:
            The history of this solve; ``w`` holds the solution ``R y``.

        Raises:
            NewtonFailure: SNES did not converge (reason <= 0), or stalled (reason
                :data:`STALLED`, see :func:`stalled`); it holds the history.
            BaseException: what a callback (residual, Jacobian, ``status``) raised, as
                itself (:mod:`~xfem_contact.solvers.callback_errors`): a
                ``KeyboardInterrupt`` stays one.
        """
        self.report = NewtonReport()
        timer = phase("Newton solve")
        self._start_from_w()
        self.jacobian.keep_constant_blocks()  # the uncut cells' linear bulk: once a solve
        for coupling in self.couplings:
            coupling.begin_step(self.w)
        try:
            # a callback's own exception (e.g. the ValueError of an unsymmetric Jacobian
            # for LDL^T, a KeyboardInterrupt) as itself, not as PETSc's "error code 101"
            with applied_options(self._prefix, self.options), raised_as_themselves():
                self.snes.solve(None, self.y)
        except BaseException:
            # SNES leaves its solution vector read-locked when a callback raises (the
            # monitor's at the first iterate): a later solve would fail on it (PETSc's
            # error 73), so the next solve gets a new one
            locked, self.y = self.y, self.y.duplicate()
            locked.destroy()
            raise
        self.report.total_time = seconds(timer)
        self._update(self.y)
        self.report.reason = self.snes.getConvergedReason()
        if self.report.reason == STALLED:
            raise NewtonFailure(
                f"Newton stalled (reason {STALLED}): no residual of the last {STALL_WINDOW} "
                f"iterates below {STALL_FACTOR:g} times the least before them",
                self.report,
            )
        if self.report.reason <= 0:
            raise NewtonFailure(
                f"Newton failed to converge (SNES reason {self.report.reason})", self.report
            )
        # Success is what the tolerances say, whatever SNES reports (e.g. ksponly)
        rtol, atol, _, _ = self.snes.getTolerances()
        if self.snes.getType() in _EVALUATES_LAST and self.report.iterations == self.snes.its:
            final = self.report.residuals[-1]  # SNES evaluated F at the last iterate
        else:  # e.g. ksponly: the norm after the step was never computed
            final = self.final_residual()
        bound = max(atol, rtol * self.report.residuals[0]) if self.report.residuals else atol
        self.report.final_residual = final
        if not final <= bound * (1.0 + 1e-8):
            raise NewtonFailure(
                f"SNES reported convergence (reason {self.report.reason}) but the final "
                f"residual {final:.3e} exceeds max(atol, rtol |F_0|) = {bound:.3e}",
                self.report,
            )
        return self.report

    def destroy(self):
        """Destroy the PETSc objects made here (the scaled copy of ``R`` included, not
        the ``R`` given). Collective."""
        self.jacobian.destroy()  # J_r included
        if self.P is not self.J_r:
            self.P.destroy()
        for coupling in self.couplings:
            coupling.destroy()
        for obj in (self.snes, self.b, self.y, self.F_r, self.R, self.D, *self._fieldsplit_objects):
            obj.destroy()
        if self.offset is not None:
            self.offset.destroy()
        if self.tip is not None:
            self.tip.destroy()
        self.jacobian_forms.destroy()


_GLOBAL, _SAME = PETSc.Mat.InfoType.GLOBAL_SUM, PETSc.Mat.Structure.SAME_NONZERO_PATTERN
_DIFFERENT = PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN

#: SNES types that evaluate the residual at the iterate they stop at (and monitor it)
_EVALUATES_LAST = ("newtonls", "newtontr")


def stalled(residuals: list[float]) -> bool:
    """Whether a Newton history of residual norms (the initial one first) stalls: none of
    its last :data:`STALL_WINDOW` norms is below :data:`STALL_FACTOR` times the least
    norm before them, and at least ``STALL_WINDOW`` iterates came after the initial one
    before those, unless each of the last norms is below the one before it (Newton
    descending again after a jump of its active set is not cycling). Not collective (the
    norms are global)."""
    if len(residuals) < 2 * STALL_WINDOW + 1:
        return False
    last = residuals[-STALL_WINDOW:]
    if all(b < a for a, b in zip(last[:-1], last[1:], strict=True)):
        return False
    return min(residuals[-STALL_WINDOW:]) >= STALL_FACTOR * min(residuals[:-STALL_WINDOW])


def _same_state(x: np.ndarray, x0: np.ndarray, comm: MPI.Comm) -> bool:
    """Whether two dof arrays agree to round-off on every process (the start of a
    solve, projected on the range of ``R D``, and the state it was taken from).
    Collective."""
    bound = 1e-14 * comm.allreduce(np.abs(x0).max(initial=0.0), op=MPI.MAX)
    close = x.shape == x0.shape and bool(np.all(np.abs(x - x0) <= bound))
    return comm.allreduce(close, op=MPI.LAND)


def weak_method(method: Callable) -> Callable:
    """``method`` called through a weak reference to its object: the Newton solver a
    problem owns must not keep the problem alive (a reference cycle holds the meshes'
    MPI communicators until the cyclic collector runs; MPICH runs out of them after
    about 120 problems on 2 ranks)."""
    ref = weakref.WeakMethod(method)
    return lambda *args: ref()(*args)


__getattr__ = renamed(__name__, {"RestrictedNewton": "ReducedNewton"}, globals())
