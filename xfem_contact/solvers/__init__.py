"""Solves on the reduced space: linear (PETSc KSP) and generalized Newton (PETSc SNES).

Owns the assembly and solution of systems restricted to the active dofs of an
enriched space, ``x = R y`` with ``R`` from :mod:`xfem_contact.fem.restriction`
(:mod:`~xfem_contact.solvers.linear`), and the Newton iteration on ``y`` with its
report and failure (:mod:`~xfem_contact.solvers.newton`). Solvers know forms and
spaces, not materials or laws. Fifth step of the layout: it may import
:mod:`xfem_contact.codegen`, :mod:`xfem_contact.geometry`,
:mod:`xfem_contact.quadrature` and :mod:`xfem_contact.fem` only.
"""
