"""Solvers on the reduced space of the restriction operator ``R`` (``x = R y``).

- :mod:`~xfem_contact.solvers.linear`: one KSP solve of ``R^T A R y = R^T b``;
- :mod:`~xfem_contact.solvers.newton`: generalized Newton (SNES) on ``R^T F(R y) = 0``;
- :mod:`~xfem_contact.solvers.options`: the default PETSc options of both.

``R`` is built by :func:`xfem_contact.fem.restriction.restriction_matrix`.
"""
