"""Interface pieces of the cut cells: which of several named interfaces cuts each
cell, and the removal of round-off slivers (both used by
:class:`~xfem_contact.fem.cutmesh.CutMesh` after each cut; local to a process)."""

from __future__ import annotations

import basix
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
    vertices = basix.geometry(maps.mesh.basix_cell())
    centre = np.broadcast_to(vertices.sum(axis=0) / len(vertices), (ncut, vertices.shape[1]))
    x = maps.push_forward(cut_cells[rows], np.r_[rules.points, centre])
    x3 = np.zeros((3, x.shape[0]))
    x3[: x.shape[1]] = x.T
    distance = np.abs([np.asarray(phi(x3), dtype=np.float64) for phi in components.values()])
    npts = np.bincount(rows, minlength=ncut)[:, None]
    totals = np.stack([np.bincount(rows, weights=d, minlength=ncut) for d in distance], axis=1)
    return np.argmin(totals / np.maximum(npts, 1), axis=1).astype(np.int32)


#: Interface pieces shorter than this fraction of their cell's size (in 3D: of smaller area
#: than this fraction of its size squared) are round-off
SLIVER_TOLERANCE = 64 * np.finfo(np.float64).eps


def without_slivers(
    mesh: dolfinx.mesh.Mesh,
    cut_cells: npt.NDArray[np.int32],
    rules: quadrature.RuleSet,
    maps: CellMaps,
) -> quadrature.RuleSet:
    """The interface rules without the cells whose interface length (area) is round-off
    (below ``SLIVER_TOLERANCE`` times the cell size ``h`` (``h^2``)): a cell touched by
    the interface at a node can get a round-off piece or none depending on the order of the cell's
    vertices, i.e. on the number of processes, and with it multiplier dofs."""
    if rules.weights.size == 0:
        return rules
    J = maps.jacobian(cut_cells[rules.point_rows], rules.points)
    size = np.bincount(
        rules.point_rows, rules.weights * np.abs(np.linalg.det(J)), minlength=cut_cells.size
    )
    tdim = mesh.topology.dim
    h = mesh.h(tdim, cut_cells)
    return rules.select(size > SLIVER_TOLERANCE * h ** (tdim - 1))


#: A singular value of a cell's trace matrix below this fraction of the largest is zero
TRACE_RANK_TOLERANCE = 1e-8


def trace_nullity(
    cell_name: str, rules: quadrature.RuleSet, jacobian_det: npt.NDArray[np.float64]
) -> npt.NDArray[np.int32]:
    """Per cut cell: how many combinations of the cell's P1/Q1 vertex functions vanish
    on its interface piece (the nullity of the weighted trace matrix).

    A straight piece in a triangle or a quadrilateral leaves 1 (a linear function on a
    segment has 2 values, a bilinear one 3). A piece along a line of the cell's
    reference coordinates (a circle in a polar mesh, a line along a cell row) leaves 2
    in a quadrilateral: those combinations, joined over the cells, are multiplier
    modes no interface term sees.

    Args:
        cell_name: ``"triangle"`` or ``"quadrilateral"``.
        rules: The interface rules (per cut cell).
        jacobian_det: ``|det J|`` at every rule point, shape ``(npoints,)``.

    Returns:
        Shape ``(num_rules,)``; cells without points get 0.
    """
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType[cell_name], 1, basix.LagrangeVariant.gll_warped
    )
    nv = element.dim
    counts = np.diff(rules.offsets)
    nullity = np.zeros(rules.num_rules, dtype=np.int32)
    if rules.weights.size == 0:
        return nullity
    basis = element.tabulate(0, rules.points)[0, :, :, 0]  # (npoints, nv)
    basis *= np.sqrt(np.abs(rules.weights * jacobian_det))[:, None]
    rank_of_point = np.arange(rules.weights.size) - rules.offsets[rules.point_rows]
    padded = np.zeros((rules.num_rules, max(int(counts.max()), nv), nv))
    padded[rules.point_rows, rank_of_point] = basis
    sigma = np.linalg.svd(padded, compute_uv=False)  # (num_rules, nv), descending
    has_points = counts > 0
    ranks = np.sum(sigma > TRACE_RANK_TOLERANCE * sigma[:, :1], axis=1)
    nullity[has_points] = nv - ranks[has_points]
    return nullity
