"""Input and output: meshes, gmsh files, VTX/VTK/JSON results, pictures and plots.

Owns what crosses the package boundary as files or images: structured meshes with
exact curved boundaries (:mod:`~xfem_contact.io.meshes`), gmsh ``.geo``/``.msh``
meshes with named parts (:mod:`~xfem_contact.io.gmsh`), VTX, ``.vtu`` and JSON
output (:mod:`~xfem_contact.io.output`), ``.pvtu`` pieces and ``.pvd`` time series
(:mod:`~xfem_contact.io.series`), the crack table of K
(:mod:`~xfem_contact.io.crack_report`), pyvista grids of the cut and the lips
(:mod:`~xfem_contact.io.vtk_grids`), off-screen PNGs
(:mod:`~xfem_contact.io.pictures`, drawing helpers in :mod:`~xfem_contact.io.render`)
and matplotlib plots (:mod:`~xfem_contact.io.plots`). Seventh step of the layout: it
may import :mod:`xfem_contact.codegen`, :mod:`xfem_contact.geometry`,
:mod:`xfem_contact.quadrature`, :mod:`xfem_contact.fem`, :mod:`xfem_contact.solvers`
and :mod:`xfem_contact.mechanics` only.
"""
