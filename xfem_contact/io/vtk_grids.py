"""VTK grids of cut meshes and results (pyvista objects, no rendering).

Every grid is local to its process (each rank builds its own owned cells) and
has no shared points: each cell carries its own nodes, so fields may jump
between cells (the two lips of the interface). Coordinates are physical (the
mesh's units, m in the paper's cases), padded with ``z = 0``.

- Uncut cells are quadratic VTK cells (6-node triangles, 9-node biquadratic
  quadrilaterals) whose nodes are the parent cell's P2/Q2 reference lattice
  pushed through the cell map: exact for affine and Q2 geometry.
- Sub-triangles of cut cells are 6-node VTK triangles: the nodes of
  ``cut.geometry.tri_minus`` / ``tri_plus`` (parent reference coordinates)
  pushed through the cell map. On affine parents this is the exact curved
  sub-triangle used by the quadrature; on curved parents its P2 interpolant.
- Interface pieces are 3-node VTK quadratic edges (``cut.geometry.seg``).

Cell data: ``side`` (-1 for ``phi < 0``, +1), ``cut`` (1 on sub-triangles, 0 on
uncut cells), ``cell`` (local index of the parent cell).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
import numpy.typing as npt
import pyvista

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import evaluate_lattice, evaluate_reference

# Reference nodes of the uncut cells' quadratic lattice, in VTK node order
_LATTICE = {
    "triangle": (
        np.array([[0, 0], [1, 0], [0, 1], [0.5, 0], [0.5, 0.5], [0, 0.5]], dtype=np.float64),
        pyvista.CellType.QUADRATIC_TRIANGLE,
    ),
    "quadrilateral": (
        np.array(
            [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0], [1, 0.5], [0.5, 1], [0, 0.5], [0.5, 0.5]],
            dtype=np.float64,
        ),
        pyvista.CellType.BIQUADRATIC_QUAD,
    ),
}
# Basix P2 triangle (vertices, then mid-nodes of edges (1,2), (0,2), (0,1)) -> VTK
# (vertices, then mid-nodes of edges (0,1), (1,2), (2,0))
P2_TO_VTK = np.array([0, 1, 2, 5, 3, 4])


class _Block(NamedTuple):
    """Cells of one kind: parent cells ``(n,)``, reference nodes ``(n, k, tdim)`` in VTK order."""

    side: int
    cut: int
    cells: npt.NDArray[np.int32]
    X: npt.NDArray[np.float64]
    vtk_type: int


def _blocks(cut: CutMesh) -> list[_Block]:
    """Uncut cells and sub-triangles of both sides (owned cells of this process)."""
    lattice, vtk_type = _LATTICE[cut.mesh.topology.cell_name()]
    g = cut.geometry
    blocks = []
    for side, tri, rows in ((-1, g.tri_minus, g.tri_minus_cell), (1, g.tri_plus, g.tri_plus_cell)):
        cells = np.flatnonzero(cut.cell_sides == side).astype(np.int32)
        X = np.broadcast_to(lattice, (cells.size, *lattice.shape))
        blocks.append(_Block(side, 0, cells, X, vtk_type))
        blocks.append(
            _Block(
                side,
                1,
                cut.cut_cells[rows].astype(np.int32),
                tri[:, P2_TO_VTK],
                pyvista.CellType.QUADRATIC_TRIANGLE,
            )
        )
    return blocks


def _pad3(a: np.ndarray) -> np.ndarray:
    """``(m, d)`` -> ``(m, 3)`` with zero columns."""
    return np.c_[a, np.zeros((a.shape[0], 3 - a.shape[1]))]


def _grid(
    cut: CutMesh, blocks: list[_Block], fields: dict | None = None
) -> pyvista.UnstructuredGrid:
    """Grid of ``blocks`` with unshared nodes; ``fields[side]``: Function evaluated as ``u``."""
    tdim = cut.mesh.topology.dim
    points, connectivity, types, data = [], [], [], {"side": [], "cut": [], "cell": []}
    values = []
    start = 0
    for b in blocks:
        n, k = b.X.shape[:2]
        if n == 0:
            continue
        if b.X.strides[0] == 0:  # the same lattice in every cell: tabulate it once
            lattice = np.ascontiguousarray(b.X[0])
            points.append(_pad3(cut.maps.push_forward_lattice(b.cells, lattice)))
            if fields is not None:
                values.append(_pad3(evaluate_lattice(fields[b.side], b.cells, lattice)))
        else:
            cells = np.repeat(b.cells, k)
            X = np.ascontiguousarray(b.X.reshape(-1, tdim))
            points.append(_pad3(cut.maps.push_forward(cells, X)))
            if fields is not None:
                values.append(_pad3(evaluate_reference(fields[b.side], cells, X)))
        ids = start + np.arange(n * k).reshape(n, k)
        connectivity.append(np.c_[np.full(n, k), ids].ravel())
        types.append(np.full(n, b.vtk_type, dtype=np.uint8))
        data["side"].append(np.full(n, b.side, dtype=np.int8))
        data["cut"].append(np.full(n, b.cut, dtype=np.int8))
        data["cell"].append(b.cells.astype(np.int32))
        start += n * k
    if not points:
        grid = pyvista.UnstructuredGrid()
        for name, dtype in (("side", np.int8), ("cut", np.int8), ("cell", np.int32)):
            grid.cell_data[name] = np.zeros(0, dtype=dtype)
        return grid
    grid = pyvista.UnstructuredGrid(
        np.concatenate(connectivity), np.concatenate(types), np.concatenate(points)
    )
    for name, parts in data.items():
        grid.cell_data[name] = np.concatenate(parts)
    if fields is not None:
        grid.point_data["u"] = np.concatenate(values)
    return grid


def subcell_grid(cut: CutMesh) -> pyvista.UnstructuredGrid:
    """Uncut cells and curved sub-triangles of the cut cells (this process's cells).

    Returns:
        Quadratic cells (see the module docstring) with cell data ``side``
        (-1/+1), ``cut`` (1 on sub-triangles) and ``cell``. Their areas (m^2)
        add up to the area of the process's part of the mesh.
    """
    return _grid(cut, _blocks(cut))


def interface_grid(cut: CutMesh) -> pyvista.UnstructuredGrid:
    """The curved interface pieces as 3-node VTK quadratic edges (this process's cut cells).

    Nodes are ``cut.geometry.seg`` (end ``a``, end ``b``, mid-node) pushed
    through the parent cell map, in physical coordinates (m). Side -1 lies on
    the left of ``a -> b``. Cell data ``cell``: local index of the parent cell.
    """
    g = cut.geometry
    cells = cut.cut_cells[g.seg_cell].astype(np.int32)
    grid = _grid(cut, [_Block(0, 1, cells, g.seg, pyvista.CellType.QUADRATIC_EDGE)])
    for name in ("side", "cut"):
        grid.cell_data.pop(name, None)
    return grid


def deformed_lips_grid(cut: CutMesh, u_minus, u_plus) -> pyvista.UnstructuredGrid:
    """:func:`subcell_grid` with point data ``u`` (m, shape ``(npoints, 3)``): the
    displacement of each cell's own side, so the two lips carry their own values.

    Args:
        cut: The cut mesh.
        u_minus: Displacement Function of side -1 (Lagrange, vector; or a
            sub-function of a mixed Function, read in place).
        u_plus: Displacement Function of side +1.
    """
    return _grid(cut, _blocks(cut), {-1: u_minus, 1: u_plus})


def merge_grids(grids: Sequence[pyvista.DataSet]) -> pyvista.UnstructuredGrid:
    """One grid from several (e.g. the ``_r{rank}`` files of a parallel run), nodes kept apart."""
    grids = [g for g in grids if g.n_cells > 0]
    if not grids:
        raise ValueError("No cells in the given grids")
    if len(grids) == 1:
        return grids[0].cast_to_unstructured_grid()
    return pyvista.merge(grids, merge_points=False)
