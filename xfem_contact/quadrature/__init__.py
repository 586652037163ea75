"""Quadrature on cut cells: per-cell rules, the memory their kernels read, facet rules.

Owns the per-cell rules on the sub-triangles and interface segments of a
:class:`~xfem_contact.geometry.cut.CutGeometry` (:class:`~xfem_contact.quadrature.rules.RuleSet`),
:class:`~xfem_contact.quadrature.cell_rules.CellRules` (those rules plus the runtime
memory the generated kernels read), the rules on boundary-facet pieces cut by the
interface (:mod:`~xfem_contact.quadrature.boundary`) and moment fitting, an
independent oracle for cut-cell integration (:mod:`~xfem_contact.quadrature.moment_fitting`).
Third step of the layout: it may import :mod:`xfem_contact.codegen` and
:mod:`xfem_contact.geometry` only.
"""
