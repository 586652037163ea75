"""Geometry of the cut: level sets, root finding and curved sub-triangulation of cut cells.

Owns the level sets on a mesh (interpolation, per-cell nodal values, reference to
physical maps; :mod:`~xfem_contact.geometry.levelset`), vectorised root finding
(:mod:`~xfem_contact.geometry.roots`) and the cutting of cells into curved P2
sub-triangles and SEG3 interface segments in reference coordinates
(:mod:`~xfem_contact.geometry.cut`, with its steps in the ``cut_*`` modules). It is
numpy and Basix plus DOLFINx mesh data (coordinates, dofmaps): no forms, no function
spaces. Second step of the layout: it may import :mod:`xfem_contact.codegen` only.
"""
