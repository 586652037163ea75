"""Linear solves on the reduced space ``y`` with ``x = R y`` (PETSc KSP).

The same prolongation as :class:`~xfem_contact.solvers.newton.ReducedNewton`:
``a`` and ``L`` are assembled with Dirichlet conditions and reduced with the operator
``R`` of :mod:`xfem_contact.fem.prolongation`, ``A_r = R^T A R`` (straight into the
reduced numbering, :mod:`xfem_contact.solvers.assembly`) and ``b_r = R^T b``; the
solution is ``x = R y``, or ``x = E g + R y`` where cell aggregation extends Dirichlet
values ``g`` (:func:`~xfem_contact.fem.prolongation.prescribed_extension`).
The solver factors the symmetrically scaled ``D A_r D`` (:mod:`xfem_contact.solvers.scaling`),
or, with a crack's tip enrichment, ``Z^T A_r Z`` with ``x = R Z y`` for the change of
unknowns ``Z`` of :mod:`xfem_contact.solvers.block_scaling`.
"""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
from petsc4py import PETSc

from xfem_contact._deprecation import renamed
from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.fem.prolongation import prescribed_offset, prolongation_matrix
from xfem_contact.solvers.assembly import ReducedMatrix
from xfem_contact.solvers.block_scaling import refined, scaled, tip_transform
from xfem_contact.solvers.callback_errors import raised_as_themselves
from xfem_contact.solvers.options import applied_options, checked_prefix, merged_options
from xfem_contact.solvers.report import LinearSolveFailure, SolveReport
from xfem_contact.solvers.scaling import saddle_point_scaling
from xfem_contact.solvers.symmetry import mark_symmetric


def assemble_reduced(
    a: dolfinx.fem.Form,
    L: dolfinx.fem.Form,
    bcs: list[dolfinx.fem.DirichletBC],
    R: PETSc.Mat,
    offset: PETSc.Vec | None = None,
) -> tuple[PETSc.Mat, PETSc.Vec]:
    """Assemble ``a`` and ``L`` with Dirichlet conditions and reduce them by ``R``
    (for ``x = offset + R y``: the right-hand side ``R^T (b - A offset)``).

    Collective.

    Args:
        a: Bilinear form on the full mixed space ``W`` (test and trial).
        L: Linear form on ``W``.
        bcs: Dirichlet conditions on ``W``, applied as
            :func:`dolfinx.fem.petsc.assemble_matrix` (unit diagonal) and
            :func:`dolfinx.fem.petsc.set_bc` do.
        R: Prolongation, global shape ``(dim W, n_reduced)``, see
            :func:`xfem_contact.fem.prolongation.prolongation_matrix`. Not modified.
        offset: The prescribed part of ``x`` off the Dirichlet dofs
            (:func:`~xfem_contact.fem.prolongation.prescribed_offset`), laid out as
            ``W``'s owned dofs, or None.

    Returns:
        The reduced matrix ``R^T A R``, global shape ``(n_reduced, n_reduced)``,
        and right-hand side ``R^T b``, global size ``n_reduced``, both laid out
        as the columns of ``R``. The caller destroys both.
    """
    reduced = ReducedMatrix(a, bcs, R)
    reduced.assemble()
    b = dolfinx.fem.petsc.assemble_vector(L)
    dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)
    if offset is not None:  # zero on the Dirichlet dofs, whose rows of A are the identity
        A = reduced.full_matrix()
        A.mult(offset, (Ax := offset.duplicate()))
        b.axpy(-1.0, Ax)
        Ax.destroy()
        if A is not reduced.full:
            A.destroy()
    A_r = reduced.release()
    b_r = R.createVecRight()
    R.multTranspose(b, b_r)
    b.destroy()
    return A_r, b_r


def solve_reduced(
    a: dolfinx.fem.Form,
    L: dolfinx.fem.Form,
    bcs: list[dolfinx.fem.DirichletBC],
    space: EnrichedSpace,
    petsc_options: dict | None = None,
    petsc_options_prefix: str | None = None,
    R: PETSc.Mat | None = None,
    residuals: list[float] | None = None,
    tip_scaling: bool = True,
    extension: PETSc.Mat | None = None,
) -> tuple[dolfinx.fem.Function, int]:
    """Solve ``a(u, v) = L(v)`` on the reduced space of ``R`` (one KSP solve).

    Collective.

    Args:
        a: Bilinear form on ``space.W``.
        L: Linear form on ``space.W``.
        bcs: Dirichlet conditions on ``space.W``.
        space: The enriched space; the solution lives on ``space.W``.
        petsc_options: PETSc options (without prefix) overriding the ``"linear"``
            defaults of :data:`xfem_contact.solvers.options.SOLVER_OPTIONS`.
        petsc_options_prefix: The KSP's options prefix; ``None``: a unique one. The
            options are in the PETSc database only during the solve.
        R: Prolongation, global shape ``(dim W, n_reduced)``; by default
            ``prolongation_matrix(space)`` (the active dofs), built and destroyed
            here. A given ``R`` is not destroyed.
        residuals: If given, the norms of the scaled reduced residual before and
            after the solve are appended to it (``|D b|``, ``|D b - D A D y_s|``).
        tip_scaling: With a crack's tip enrichment, factor ``Z^T A_r Z`` with ``x = R Z y``
            (:func:`~xfem_contact.solvers.block_scaling.tip_scaling`) instead of ``D A_r D``.
        extension: The prescribed part ``E`` of cell aggregation's extension
            (:func:`~xfem_contact.fem.prolongation.prescribed_extension`, for the same
            ``R``), or None: the solution is then ``x = E g + R y``, ``g`` the Dirichlet
            values. Not destroyed.

    Returns:
        The solution ``x = R y`` (``E g + R y``) on ``space.W`` (zero on inactive dofs, ghosts
        updated) and the KSP's converged reason (> 0).

    Raises:
        LinearSolveFailure: The KSP diverged (converged reason < 0); nothing made
            here outlives the call.
    """
    if (petsc_options or {}).get("pc_type") == "python":
        raise ValueError(
            "solver preset 'iterative' (the band multigrid) preconditions the Newton "
            "steps of contact problems; a linear problem (interfaces 'bonded' or 'free' "
            "only) takes 'direct'"
        )
    owned = []  # every PETSc object made here, destroyed on every path
    try:
        if R is None:
            R = prolongation_matrix(space)
            owned.append(R)
        offset = None
        if extension is not None:
            offset = prescribed_offset(extension, bcs, space.W)
            owned.append(offset)
        A, b = assemble_reduced(a, L, bcs, R, offset)
        owned += [A, b]
        transform = tip_transform(space, off=not tip_scaling)
        if transform is None:
            D = saddle_point_scaling(A)  # solve D A D y_s = D b, y = D y_s
            A.diagonalScale(D, D)
            b.pointwiseMult(b, D)
        else:  # solve Z^T A Z y_s = Z^T b, y = Z y_s (refined against A_r y = b_r)
            D = transform(R, A)
            (A_r, b_r), A = (A, b), scaled(A, D)
            b = A.createVecRight()
            owned += [A, b]
            D.multTranspose(b_r, b)
        owned.append(D)
        ksp = PETSc.KSP().create(A.getComm())
        owned.append(ksp)
        ksp.setOperators(A)
        prefix = checked_prefix(petsc_options_prefix, "xfem_linear_")
        ksp.setOptionsPrefix(prefix)
        options = merged_options("linear", petsc_options)
        if options.get("pc_type") == "cholesky":
            mark_symmetric(A)  # checked: an LDL^T reads one triangle only
        with applied_options(prefix, options):
            ksp.setFromOptions()
        y = R.createVecRight()
        owned.append(y)
        # the factorisation reads options too; a Python preconditioner's own exception
        # is raised as itself
        with applied_options(prefix, options), raised_as_themselves():
            ksp.solve(b, y)
        norms = [b.norm()]
        r = b.duplicate()
        owned.append(r)
        A.mult(y, r)
        r.axpy(-1.0, b)
        norms.append(r.norm())
        if residuals is not None:
            residuals += norms
        reason = ksp.getConvergedReason()
        if reason < 0:
            raise LinearSolveFailure(
                f"Linear solve failed: KSP converged reason {reason} "
                f"({ksp.getType()} with pc {ksp.getPC().getType()})",
                SolveReport(norms, reason=reason),
            )
        if transform is None:
            y.pointwiseMult(y, D)
        else:
            y = refined(ksp, D, A_r, b_r, y)
            owned.append(y)
        w = dolfinx.fem.Function(space.W)
        R.mult(y, w.x.petsc_vec)
        if offset is not None:
            w.x.petsc_vec.axpy(1.0, offset)
        w.x.scatter_forward()
        return w, reason
    finally:
        for obj in {id(o): o for o in owned}.values():
            obj.destroy()


#: Deprecated names of this module's functions: old name -> new name
_RENAMED = {"solve_restricted": "solve_reduced", "assemble_restricted": "assemble_reduced"}


__getattr__ = renamed(__name__, _RENAMED, globals())
