"""Finite elements on a cut mesh: CutMesh and its measures, form(), enriched spaces.

Owns :class:`~xfem_contact.fem.cutmesh.CutMesh` (a mesh cut by a level set, with
the UFL measures of each side and of the interface), :func:`~xfem_contact.fem.forms.form`
(UFL forms with cut measures to DOLFINx forms compiled through the runtime back end),
the Heaviside-enriched spaces and their active dofs (:mod:`~xfem_contact.fem.enrichment`),
sub-spaces as spaces of their own (:mod:`~xfem_contact.fem.subspaces`), point values of
functions at rule points (:mod:`~xfem_contact.fem.evaluation`) and the
prolongation ``R`` from the reduced to the full space
(:mod:`~xfem_contact.fem.prolongation`). Physics does not live here. Fourth step of the
layout: it may import :mod:`xfem_contact.codegen`, :mod:`xfem_contact.geometry` and
:mod:`xfem_contact.quadrature` only.
"""
