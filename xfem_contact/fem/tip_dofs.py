"""A crack's branch dofs: their support around the tips, the ramp, and gathering.

The branch dofs of :class:`~xfem_contact.fem.enrichment.EnrichedSpace` are active on the
cells where its ramp ``R`` is not 0: with a tip radius ``r_e``, the P1 function 1 on
the vertices within ``r_e`` of a tip (``tip_dofs="nodal"``), or the smooth cut-off
below (``"gathered"``); without one, on the tip cells.

With ``tip_dofs="gathered"`` the branch dofs of every vertex near one tip take one
value per branch function ``F_k`` and component (the dof gathering of Laborde, Pommier,
Renard and Salaün, IJNME 64, 2005): the vertices' hats sum to 1 on the cells where the
ramp is not 0, so the enrichment is ``R(x) sum_k F_k a_k`` with constant ``a_k``, the
cut-off method of Chahine, Laborde and Renard (2008). The ramp ``R`` is then the
Lagrange interpolant (P1; with cell aggregation, of the displacement degree:
:func:`ramp_degree`) of a smooth cut-off of the distance ``d`` to the nearest tip,
``1 - 10 s^3 + 15 s^4 - 6 s^5`` with ``s = d / r_e`` (1 at the tip, 0 from ``r_e`` on,
its first and second derivatives 0 at both ends). Its slopes are fixed by ``r_e``, not by
``h``, so ``(1 - R) u`` is as smooth as ``u`` off the tip and the standard functions
approximate it at their full order (a cut-off with a jump of its second derivative
lowers the rate of degree 2). The few gathered unknowns, each shifted by its
interpolant on the standard nodes (:mod:`xfem_contact.solvers.block_scaling`), add no
near-dependence that grows as ``h -> 0``, whatever the number of vertices in the zone.

Cell aggregation (:mod:`~xfem_contact.fem.aggregation`) gives a badly cut cell's
standard dofs its root's polynomial: the standard part ``(1 - R) u`` must then be one
polynomial on the root and the badly cut cell to the order of the element. The P1
interpolant's slopes jump across every edge of the zone by ``h`` times the cut-off's
second derivative; the interpolant of degree 2 jumps by ``h^2`` times the third.
"""

from __future__ import annotations

import logging
import typing

import dolfinx.la
import numpy as np
import numpy.typing as npt
from mpi4py import MPI

from xfem_contact.fem.branch import null_pins
from xfem_contact.geometry.crack import TIP

if typing.TYPE_CHECKING:
    from xfem_contact.fem.enrichment import EnrichedSpace

__all__ = [
    "TIP_DOFS",
    "branch_groups",
    "branch_support",
    "checked_tip_dofs",
    "cutoff",
    "ramp_degree",
]

_logger = logging.getLogger(__name__)
#: Relative tolerance of the tip radius: the mesh generator rounds a node's coordinates
#: differently on 1 and 2 processes (1 ulp)
_RADIUS_TOLERANCE = 1e-10

#: The ways a crack's branch dofs are unknowns
TIP_DOFS = ("nodal", "gathered")


def checked_tip_dofs(tip_dofs: str, tip_radius) -> str:
    """``tip_dofs`` (one of :data:`TIP_DOFS`), refused in one line if unknown or if
    ``"gathered"`` comes without a tip radius (the topological zone's hats do not sum
    to 1 on its cells)."""
    if tip_dofs not in TIP_DOFS:
        raise ValueError(f"tip_dofs must be one of {TIP_DOFS}, got {tip_dofs!r}")
    if tip_dofs == "gathered" and tip_radius is None:
        raise ValueError(
            "tip_dofs='gathered' needs a tip radius (tip_radius a length or 'auto', not None)"
        )
    return tip_dofs


def ramp_degree(tip_dofs: str, degree: int, aggregated: bool) -> int:
    """The Lagrange degree of the ramp ``R``: 1, or the displacement ``degree`` for
    gathered dofs with cell aggregation (``aggregated``). The cut-off's interpolant of
    degree 1 has slopes that jump across cell edges by ``h`` times the cut-off's second
    derivative, which the standard functions follow at no cost; an aggregated dof
    extends its root's polynomial across an edge and cannot (module docstring). Nodal
    dofs keep their ramp of vertex values 0 and 1."""
    return degree if tip_dofs == "gathered" and aggregated else 1


def cutoff(distance: npt.NDArray[np.float64], radius: float) -> npt.NDArray[np.float64]:
    """The smooth cut-off of the module docstring at distances ``distance`` (m) from a
    tip, for the tip radius ``radius`` (m); same shape as ``distance``."""
    s = np.clip(np.asarray(distance) / radius, 0.0, 1.0)
    return 1.0 - s**3 * (10.0 - 15.0 * s + 6.0 * s**2)


def branch_support(space: EnrichedSpace) -> npt.NDArray[np.bool_]:
    """Per local dof of ``space.W``: a branch dof of a cell where the ramp is not 0 (the
    ramp ``space.ramp`` is set here), or of a tip cell without a tip radius. With nodal
    dofs ``F_1``, ``F_2`` are dropped at one node per tip
    (:func:`~xfem_contact.fem.branch.null_pins`). Collective."""
    crack, field = space.cut.crack, space.branch_field
    if space.tip_radius is None:
        return space._mark(field, crack.cells(TIP, space.cut.cut_cells)) > 0
    mesh = space.cut.mesh
    tip_cells = crack.cells(TIP, space.cut.cut_cells).astype(np.int32)
    local = float(mesh.h(2, tip_cells).max()) if tip_cells.size else 0.0
    h = mesh.comm.allreduce(local, op=MPI.MAX)
    R = space.ramp
    if space.tip_radius < h:
        _logger.warning(
            "tip_radius = %.6g m is smaller than the tip cells (diameter %.6g m): the "
            "branch functions enrich the tip cells' nodes",
            space.tip_radius,
            h,
        )
        R.x.array[:] = 0.0
        R.x.array[R.function_space.dofmap.list[tip_cells].ravel()] = 1.0
        R.x.scatter_reverse(dolfinx.la.InsertMode.add)
        R.x.array[:] = R.x.array > 0
    else:
        x = R.function_space.tabulate_dof_coordinates()[:, : crack.tips.shape[1]]
        distance = np.linalg.norm(x[:, None, :] - crack.tips[None], axis=2).min(axis=1)
        if space.tip_dofs == "gathered":
            R.x.array[:] = cutoff(distance, space.tip_radius)
        else:  # a node at the radius is in, whatever rounding its coordinates carry
            R.x.array[:] = distance <= space.tip_radius * (1.0 + _RADIUS_TOLERANCE)
    R.x.scatter_forward()
    ramp_cells = R.function_space.dofmap.list[: space.cut.cell_sides.size]
    flags = space._mark(field, np.flatnonzero(R.x.array[ramp_cells].max(axis=1) > 0)) > 0
    if space.tip_dofs == "gathered":  # constant coefficients: no null vectors
        return flags
    V, parent = space.field_space(field)  # F_1, F_2 dropped at one node: no null vectors
    gdim, bs, xb = crack.tips.shape[1], V.dofmap.index_map_bs, V.tabulate_dof_coordinates()
    pins = null_pins(xb[:, :gdim], crack.tips, crack.directions, 0.5 * h, mesh.comm)
    flags[parent[(np.flatnonzero(pins)[:, None] * bs + np.arange(2 * gdim)).ravel()]] = False
    return flags


def branch_groups(space: EnrichedSpace) -> npt.NDArray[np.int64] | None:
    """With ``tip_dofs="gathered"``: per owned dof of ``space.W``, the group of the
    branch dofs that share one unknown, ``tip * 4 gdim + j`` for component ``j`` of the
    branch field at a node nearest to tip ``tip``, -1 off the branch field; else None.
    Not collective."""
    if space.tip_dofs != "gathered" or space.branch_field is None:
        return None
    V, parent = space.field_space(space.branch_field)
    tips, bs = space.cut.crack.tips, V.dofmap.index_map_bs
    x = V.tabulate_dof_coordinates()[:, : tips.shape[1]]
    nearest = np.linalg.norm(x[:, None, :] - tips[None], axis=2).argmin(axis=1)
    n_owned = space.W.dofmap.index_map.size_local * space.W.dofmap.index_map_bs
    groups = np.full(n_owned, -1, dtype=np.int64)
    owned = parent < n_owned
    groups[parent[owned]] = (nearest[:, None] * bs + np.arange(bs)[None, :]).ravel()[owned]
    return groups
