"""Linear solves restricted to the active dofs of an enriched space (PETSc KSP)."""

from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
from petsc4py import PETSc

from xfem_contact.fem.enrichment import EnrichedSpace

DEFAULT_PETSC_OPTIONS = {
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


def assemble_restricted(
    a: dolfinx.fem.Form,
    L: dolfinx.fem.Form,
    bcs: list[dolfinx.fem.DirichletBC],
    space: EnrichedSpace,
) -> tuple[PETSc.Mat, PETSc.Vec, PETSc.IS]:
    """Assemble ``a``, ``L`` with Dirichlet conditions, keep the active dofs. Collective.

    Returns:
        The restricted matrix and right-hand side, and the index set of the
        active dofs in the full space (caller destroys all three).
    """
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    b = dolfinx.fem.petsc.assemble_vector(L)
    dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)
    index_set = space.index_set()
    A_r = A.createSubMatrix(index_set, index_set)
    sub = b.getSubVector(index_set)
    b_r = sub.copy()
    b.restoreSubVector(index_set, sub)
    A.destroy()
    b.destroy()
    return A_r, b_r, index_set


def solve_restricted(
    a: dolfinx.fem.Form,
    L: dolfinx.fem.Form,
    bcs: list[dolfinx.fem.DirichletBC],
    space: EnrichedSpace,
    petsc_options: dict | None = None,
    petsc_options_prefix: str = "xfem_linear_",
) -> tuple[dolfinx.fem.Function, int]:
    """Solve ``a(u, v) = L(v)`` on the active dofs (one KSP solve). Collective.

    Returns:
        The solution in the full mixed space (inactive dofs zero) and the
        KSP's converged reason.
    """
    A, b, index_set = assemble_restricted(a, L, bcs, space)
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    ksp.setOptionsPrefix(petsc_options_prefix)
    opts = PETSc.Options()
    for key, value in {**DEFAULT_PETSC_OPTIONS, **(petsc_options or {})}.items():
        opts[f"{petsc_options_prefix}{key}"] = value
    ksp.setFromOptions()
    w = dolfinx.fem.Function(space.W)
    x = w.x.petsc_vec
    x_r = x.getSubVector(index_set)
    ksp.solve(b, x_r)
    x.restoreSubVector(index_set, x_r)
    w.x.scatter_forward()
    reason = ksp.getConvergedReason()
    if reason < 0:
        raise RuntimeError(f"Linear solve failed: KSP converged reason {reason}")
    for obj in (ksp, A, b, index_set):
        obj.destroy()
    return w, reason
