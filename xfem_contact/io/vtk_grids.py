"""VTK grids of cut meshes and results as pyvista objects (no rendering).

The grids of :mod:`xfem_contact.io.vtu` (its docstring describes their layout: local
to each process, unshared nodes, quadratic cells, cell data ``side``, ``cut``,
``cell``), wrapped for pyvista: what :mod:`xfem_contact.io.pictures` renders and
notebooks inspect. Writing ``.vtu`` files needs no pyvista (:func:`~xfem_contact.io.vtu.write_vtu`).
"""

from __future__ import annotations

from collections.abc import Sequence

import pyvista

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.vtu import (
    P2_TO_VTK,
    GridArrays,
    interface_arrays,
    lips_arrays,
    subcell_arrays,
)

__all__ = ["P2_TO_VTK", "deformed_lips_grid", "interface_grid", "merge_grids", "subcell_grid"]


def _grid(arrays: GridArrays) -> pyvista.UnstructuredGrid:
    """The pyvista grid of ``arrays``."""
    if arrays.types.size == 0:
        grid = pyvista.UnstructuredGrid()
    else:
        grid = pyvista.UnstructuredGrid(arrays.cells, arrays.types, arrays.points)
    for name, values in arrays.cell_data.items():
        grid.cell_data[name] = values
    for name, values in arrays.point_data.items():
        grid.point_data[name] = values
    return grid


def subcell_grid(cut: CutMesh) -> pyvista.UnstructuredGrid:
    """Uncut cells and curved sub-triangles of the cut cells (this process's cells).

    Returns:
        Quadratic cells (see the module docstring) with cell data ``side``
        (-1/+1), ``cut`` (1 on sub-triangles) and ``cell``. Their areas (m^2)
        add up to the area of the process's part of the mesh.
    """
    return _grid(subcell_arrays(cut))


def interface_grid(cut: CutMesh) -> pyvista.UnstructuredGrid:
    """The curved interface pieces as 3-node VTK quadratic edges (this process's cut cells).

    Nodes are ``cut.geometry.seg`` (end ``a``, end ``b``, mid-node) pushed
    through the parent cell map, in physical coordinates (m). Side -1 lies on
    the left of ``a -> b``. Cell data ``cell``: local index of the parent cell.
    """
    return _grid(interface_arrays(cut))


def deformed_lips_grid(cut: CutMesh, u_minus, u_plus) -> pyvista.UnstructuredGrid:
    """:func:`subcell_grid` with point data ``u`` (m, shape ``(npoints, 3)``): the
    displacement of each cell's own side, so the two lips carry their own values.

    Args:
        cut: The cut mesh.
        u_minus: Displacement Function of side -1 (Lagrange, vector; or a
            sub-function of a mixed Function, read in place).
        u_plus: Displacement Function of side +1.
    """
    return _grid(lips_arrays(cut, u_minus, u_plus))


def merge_grids(grids: Sequence[pyvista.DataSet]) -> pyvista.UnstructuredGrid:
    """One grid from several (e.g. the ``_r{rank}`` files of a parallel run), nodes kept apart."""
    grids = [g for g in grids if g.n_cells > 0]
    if not grids:
        raise ValueError("No cells in the given grids")
    if len(grids) == 1:
        return grids[0].cast_to_unstructured_grid()
    return pyvista.merge(grids, merge_points=False)
