"""Validation cases with exact solutions, shared by the tests, demos, benchmarks and notebooks.

Owns the paper's cases (:mod:`~xfem_contact.cases.paper`): the straight interface,
the inclusion in contact and the annulus, each as a problem builder with its exact
solution and error measures. Eighth step of the layout: it may import
:mod:`xfem_contact.codegen`, :mod:`xfem_contact.geometry`, :mod:`xfem_contact.quadrature`,
:mod:`xfem_contact.fem`, :mod:`xfem_contact.solvers`, :mod:`xfem_contact.mechanics` and
:mod:`xfem_contact.io` only.
"""
