"""The length of a crack's tips, and the default tip enrichment radius in units of it.

Each tip of a crack owns a share of its crack's length: the length of the crack (its
lips' arc length on the current cut) divided by its number of tips, ``a`` for a crack of
length ``2a`` inside the body, the whole length for an edge crack. The defaults of the
tip enrichment (:data:`TIP_RADIUS`) and of the rings of K are fractions of it, so that
they do not shrink with the mesh: the enriched zone and the integration domain stay the
same set of points as ``h -> 0``, which is what makes K converge monotonically.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np
import numpy.typing as npt
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.geometry.crack import TIP

__all__ = ["TIP_RADIUS", "default_tip_radius", "tip_cells_size", "tip_lengths"]

#: The default tip enrichment radius, in units of the shortest :func:`tip_lengths`
TIP_RADIUS = 0.5


def tip_lengths(cut: CutMesh) -> npt.NDArray[np.float64]:
    """Per tip of ``cut.crack`` (in its order): the length (m) of the tip's crack divided
    by that crack's number of tips, ``(ntips,)``. Collective.

    Raises:
        ValueError: the cut has no crack.
    """
    crack = cut.crack
    if crack is None:
        raise ValueError("tip_lengths: the cut has no crack (CutMesh(..., tangent=psi))")
    names = crack.tip_names or (cut.interface_names[0],) * len(crack.tips)
    one = dolfinx.fem.Constant(cut.mesh, 1.0)
    lengths = {}
    for name in dict.fromkeys(names):
        local = dolfinx.fem.assemble_scalar(form(one * cut.interface_measure(name)))
        lengths[name] = cut.mesh.comm.allreduce(local, op=MPI.SUM) / names.count(name)
    return np.array([lengths[name] for name in names])


def tip_cells_size(cut: CutMesh) -> float:
    """The largest diameter (m) of the tip cells of ``cut.crack``. Collective."""
    mesh, crack = cut.mesh, cut.crack
    cells = crack.cells(TIP, cut.cut_cells).astype(np.int32)
    local = float(mesh.h(mesh.topology.dim, cells).max()) if cells.size else 0.0
    return mesh.comm.allreduce(local, op=MPI.MAX)


def default_tip_radius(cut: CutMesh) -> float:
    """The default tip enrichment radius (m): :data:`TIP_RADIUS` times the shortest of
    :func:`tip_lengths`, with several cracks (or interfaces) at most their zone less one
    cell (:meth:`~xfem_contact.geometry.crack_union.CrackUnion.check_tip_radius`), and at
    least the tip cells' size (on a mesh too coarse to hold that zone the tip cells'
    patch is the zone). Collective."""
    radius = TIP_RADIUS * float(tip_lengths(cut).min())
    union = cut.crack.union
    if union is not None and len(union.names) > 1:
        radius = min(radius, union.zone - union.h)
    return max(radius, tip_cells_size(cut))
