"""Interface pieces of the cut cells: which of several named interfaces cuts each
cell, and the removal of round-off slivers (both used by
:class:`~xfem_contact.fem.cutmesh.CutMesh` after each cut; local to a process)."""

from __future__ import annotations

import dolfinx.mesh
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.levelset import CellMaps, LevelSetCallable
from xfem_contact.quadrature import rules as quadrature


def cell_interfaces(
    maps: CellMaps,
    cut_cells: npt.NDArray[np.int32],
    rules: quadrature.RuleSet,
    components: dict[str, LevelSetCallable] | None,
) -> npt.NDArray[np.int32]:
    """Which interface cuts each cut cell: the one whose level set is nearest zero
    on average over the cell's interface points and its reference centre (the
    interfaces cut no common cell, so the nearest is the one that cuts it)."""
    ncut = cut_cells.size
    if components is None or len(components) == 1:
        return np.zeros(ncut, dtype=np.int32)
    rows = np.r_[rules.point_rows, np.arange(ncut)]
    centre = np.full((ncut, rules.points.shape[1]), 1.0 / 3.0)
    if maps.mesh.topology.cell_name() == "quadrilateral":
        centre[:] = 0.5
    x = maps.push_forward(cut_cells[rows], np.r_[rules.points, centre])
    x3 = np.zeros((3, x.shape[0]))
    x3[: x.shape[1]] = x.T
    distance = np.abs([np.asarray(phi(x3), dtype=np.float64) for phi in components.values()])
    npts = np.bincount(rows, minlength=ncut)[:, None]
    totals = np.stack([np.bincount(rows, weights=d, minlength=ncut) for d in distance], axis=1)
    return np.argmin(totals / np.maximum(npts, 1), axis=1).astype(np.int32)


#: Interface pieces shorter than this fraction of their cell's size are round-off
SLIVER_TOLERANCE = 64 * np.finfo(np.float64).eps


def without_slivers(
    mesh: dolfinx.mesh.Mesh,
    cut_cells: npt.NDArray[np.int32],
    rules: quadrature.RuleSet,
    maps: CellMaps,
) -> quadrature.RuleSet:
    """The interface rules without the cells whose interface length is round-off
    (below ``SLIVER_TOLERANCE`` times the cell size): a cell touched by the interface
    at a node got a piece of length 3e-17 or none depending on the order of the
    cell's vertices, i.e. on the number of processes, and with it multiplier dofs."""
    if rules.weights.size == 0:
        return rules
    J = maps.jacobian(cut_cells[rules.point_rows], rules.points)
    length = np.bincount(
        rules.point_rows, rules.weights * np.abs(np.linalg.det(J)), minlength=cut_cells.size
    )
    h = mesh.h(mesh.topology.dim, cut_cells)
    return rules.select(length > SLIVER_TOLERANCE * h)
