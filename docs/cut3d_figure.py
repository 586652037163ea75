"""Draw a 3D cut: ``docs/figures/cut3d_sphere_tetrahedra.png`` and ``..._hexahedra.png``.

The sphere of radius 0.3 centred in the unit cube, as a degree-2 level set on 8 x 8 x 8
cubes (six P2 tetrahedra each, or Q2 hexahedra), drawn by
:func:`xfem_contact.io.cut3d_pictures.plot_cut_3d`.

Run: ``python docs/cut3d_figure.py`` (one process).
"""

import pathlib

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.cut3d_pictures import plot_cut_3d
from xfem_contact.io.render import quiet_vtk

FIGURES = pathlib.Path(__file__).parent / "figures"


def main() -> None:
    quiet_vtk()
    for cell, name in (("tetrahedron", "tetrahedra"), ("hexahedron", "hexahedra")):
        mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, 8, 8, 8, dolfinx.mesh.CellType[cell])
        cut = CutMesh(mesh, lambda x: np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - 0.3, degree=2)
        print(plot_cut_3d(cut, FIGURES / f"cut3d_sphere_{name}.png"))


if __name__ == "__main__":
    main()
