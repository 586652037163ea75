"""Solves on the reduced space: linear (PETSc KSP) and generalized Newton (PETSc SNES).

Owns the assembly and solution of systems reduced to the active dofs of an
enriched space, ``x = R y`` with ``R`` from
:func:`xfem_contact.fem.prolongation.prolongation_matrix`: one KSP solve of
``R^T A R y = R^T b`` (:mod:`~xfem_contact.solvers.linear`), generalized Newton on
``R^T F(R y) = 0`` with its report and failure (:mod:`~xfem_contact.solvers.newton`),
the assembly of ``R^T A R`` straight into the reduced numbering
(:mod:`~xfem_contact.solvers.assembly`), the saddle-point scaling
(:mod:`~xfem_contact.solvers.scaling`) and the one table of their default PETSc
options (:mod:`~xfem_contact.solvers.options`).
Solvers know forms and spaces, not materials or laws. Fifth step of the layout: it may
import :mod:`xfem_contact.codegen`, :mod:`xfem_contact.geometry`,
:mod:`xfem_contact.quadrature` and :mod:`xfem_contact.fem` only.
"""
