"""Rigid motions: the translations and rotations of a body, in 2D and 3D (the motions
without strain, the null space of elasticity without supports)."""

from __future__ import annotations

import dataclasses

import numpy as np

#: The coordinate planes ``(i, j)`` of the rotations of :func:`rigid_motions`: in 3D
#: about x, y, z in turn
ROTATION_PLANES = {2: ((0, 1),), 3: ((1, 2), (2, 0), (0, 1))}


def rigid_motions(x: np.ndarray) -> np.ndarray:
    """The rigid motions at points ``x`` ``(n, gdim)`` (m): shape ``(n, gdim, m)``,
    ``m = gdim (gdim + 1) / 2`` (3 in 2D, 6 in 3D): the translations along the axes,
    then the rotations about the origin, ``v_i = -x_j``, ``v_j = x_i`` in each plane
    ``(i, j)`` of :data:`ROTATION_PLANES` (in 3D about x, y, z: ``e_k x x``)."""
    n, gdim = x.shape
    planes = ROTATION_PLANES[gdim]
    z = np.zeros((n, gdim, gdim + len(planes)))
    for c in range(gdim):
        z[:, c, c] = 1.0
    for k, (i, j) in enumerate(planes):
        z[:, i, gdim + k] = -x[:, j]
        z[:, j, gdim + k] = x[:, i]
    return z


@dataclasses.dataclass
class Body:
    """A connected part of the sides' fields: its owned active dofs per component."""

    name: str
    dofs: list[np.ndarray]  # per component: owned local dofs of W
    coords: list[np.ndarray]  # their coordinates, (n, gdim)
    alone: list[np.ndarray]  # per component: whether no other side's field is active there
    centre: np.ndarray
    radius: float  # radius of gyration of its area (volume in 3D) (m)

    def modes(self, x: np.ndarray, component: int) -> np.ndarray:
        """Component ``component`` of the scaled modes at points ``x``, shape (n, m)
        (:func:`rigid_motions` about the centre, lengths over the radius)."""
        return rigid_motions((x - self.centre) / self.radius)[:, component, :]


def modes_per_body(gdim: int) -> int:
    """``m = gdim (gdim + 1) / 2``: the rigid modes of a body, 3 in 2D, 6 in 3D."""
    return gdim * (gdim + 1) // 2
