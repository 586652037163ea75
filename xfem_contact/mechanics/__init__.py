"""Mechanics on cut meshes: materials, loading, problems, interface laws, LBB treatments.

Owns the physics written in UFL: linear elastic materials
(:mod:`~xfem_contact.mechanics.materials`), the loads of a problem (parts, magnitudes,
load paths: :mod:`~xfem_contact.mechanics.loads`), the problems (enriched elasticity
with free or bonded interfaces, augmented-Lagrangian contact, plain uncut
elasticity), the interface laws they compose, and the inf-sup (LBB) treatments of the
contact multiplier (:mod:`~xfem_contact.mechanics.lbb`). Sixth step of the layout: it
may import :mod:`xfem_contact.codegen`, :mod:`xfem_contact.geometry`,
:mod:`xfem_contact.quadrature`, :mod:`xfem_contact.fem` and :mod:`xfem_contact.solvers`
only.
"""
