"""The q-functions of domain integrals: rings ``R_inf .. R_sup`` around a crack tip.

A ring's q is 1 within ``R_inf`` of the tip, 0 beyond ``R_sup`` and a ramp of the
distance between (linear, or the C1 cubic ``1 - 3 s^2 + 2 s^3`` of ``s = (r - R_inf) /
(R_sup - R_inf)``), interpolated into a Lagrange space of the mesh: so it is a polynomial
in every cell and the domain integrals need no quadrature across the ring's circles.
Radii are in metres; :func:`scaled_rings` gives them in units of a length (the cell size
at the tip, :func:`tip_cell_size`, or the crack length).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable

import dolfinx.fem
import dolfinx.geometry
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.mechanics.fracture.williams import TipFrame, local_coordinates

SHAPES = ("linear", "smooth")


@dataclasses.dataclass(frozen=True)
class Ring:
    """Radii ``0 <= r_inf < r_sup`` (m) of a q-function and the shape of its ramp."""

    r_inf: float
    r_sup: float
    shape: str = "linear"

    def __post_init__(self):
        if not (math.isfinite(self.r_inf) and math.isfinite(self.r_sup)):
            raise ValueError(f"ring radii must be finite, got ({self.r_inf}, {self.r_sup})")
        if not 0.0 <= self.r_inf < self.r_sup:
            raise ValueError(
                f"ring radii must satisfy 0 <= r_inf < r_sup (m), got ({self.r_inf}, {self.r_sup})"
            )
        if self.shape not in SHAPES:
            raise ValueError(f"ring shape must be one of {SHAPES}, got {self.shape!r}")

    def q(self, r: np.ndarray) -> np.ndarray:
        """The ramp at distances ``r`` (m) from the tip, any shape."""
        s = np.clip((np.asarray(r) - self.r_inf) / (self.r_sup - self.r_inf), 0.0, 1.0)
        return 1.0 - s if self.shape == "linear" else 1.0 - s * s * (3.0 - 2.0 * s)


def scaled_rings(factors: Iterable[tuple[float, float]], unit: float, shape: str = "linear"):
    """Rings ``(a unit, b unit)`` for each pair ``(a, b)`` of ``factors``, e.g. ``unit`` the
    cell size at the tip (:func:`tip_cell_size`) or the crack length (m)."""
    if not (math.isfinite(unit) and unit > 0.0):
        raise ValueError(f"unit must be a positive length (m), got {unit!r}")
    return [Ring(a * unit, b * unit, shape) for a, b in factors]


def cells_at(mesh: dolfinx.mesh.Mesh, point: np.ndarray) -> np.ndarray:
    """Local cells (owned and ghost) whose closure holds ``point`` (2,)."""
    tdim = mesh.topology.dim
    tree = dolfinx.geometry.bb_tree(mesh, tdim)
    x = np.array([[point[0], point[1], 0.0]])
    candidates = dolfinx.geometry.compute_collisions_points(tree, x)
    return dolfinx.geometry.compute_colliding_cells(mesh, candidates, x).links(0)


def tip_cell_size(mesh: dolfinx.mesh.Mesh, tip) -> float:
    """The largest diameter (m) of the cells holding the point ``tip``. Collective.

    Raises:
        ValueError: if no cell of the mesh holds ``tip``.
    """
    cells = cells_at(mesh, np.asarray(tip, dtype=np.float64))
    local = float(mesh.h(mesh.topology.dim, cells.astype(np.int32)).max()) if len(cells) else 0.0
    h = mesh.comm.allreduce(local, op=MPI.MAX)
    if h == 0.0:
        raise ValueError(f"tip {tuple(np.asarray(tip).tolist())} lies in no cell of the mesh")
    return h


def interpolate_ring(q: dolfinx.fem.Function, frame: TipFrame, ring: Ring) -> None:
    """Fill ``q`` (a scalar Lagrange Function) with ``ring``'s q around the tip ``frame``
    (numbers). Collective: checks that q is 1 on every cell holding the tip and 0 on the
    mesh boundary (except on the crack line behind the tip, where a body-fitted mesh
    with duplicated nodes has its lips).

    Raises:
        ValueError: a tip in no cell, ``r_inf`` smaller than the tip's cells, or
            ``r_sup`` reaching the boundary of the mesh.
    """
    V = q.function_space
    mesh = V.mesh
    x = V.tabulate_dof_coordinates().T
    x1, x2 = local_coordinates(x, frame)
    q.x.array[:] = ring.q(np.hypot(x1, x2))

    cells = cells_at(mesh, np.asarray(frame.origin, dtype=np.float64))
    if mesh.comm.allreduce(len(cells), op=MPI.SUM) == 0:
        raise ValueError(
            f"tip {tuple(np.asarray(frame.origin).tolist())} lies in no cell of the mesh"
        )
    dofs = V.dofmap.list[cells].ravel() if len(cells) else np.zeros(0, np.int32)
    low = mesh.comm.allreduce(float(q.x.array[dofs].min()) if len(dofs) else 1.0, op=MPI.MIN)
    if low < 1.0:
        h = tip_cell_size(mesh, frame.origin)
        raise ValueError(
            f"ring r_inf = {ring.r_inf:.6g} m does not cover the cells at the tip (size "
            f"{h:.6g} m): take r_inf of at least the tip cells' size"
        )

    fdim = mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, mesh.topology.dim)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    boundary = dolfinx.fem.locate_dofs_topological(V, fdim, facets)
    on_lips = (np.abs(x2[boundary]) <= 1e-9 * ring.r_sup) & (x1[boundary] <= 0.0)
    reached = boundary[(q.x.array[boundary] > 0.0) & ~on_lips]
    where = x[:2, reached[0]].tolist() if len(reached) else None
    where = [w for w in mesh.comm.allgather(where) if w is not None]
    if where:
        raise ValueError(
            f"ring r_sup = {ring.r_sup:.6g} m reaches the mesh boundary (at {where[0]}): "
            "take a smaller r_sup"
        )
