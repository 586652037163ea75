"""What a field-split preconditioner needs to know of a problem's mixed space.

:func:`field_splits` names the dofs of the displacements (``"u"``: both sides) and of
the multipliers (``"lambda"``: every multiplier field); :func:`rigid_modes` gives the
translations and the rotation of each side, the near null space of the displacement
block for algebraic multigrid (GAMG). Used by
:class:`~xfem_contact.mechanics.problem.Problem` for the ``"iterative"`` preset of
:data:`~xfem_contact.solvers.options.LINEAR_PRESETS`.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np

from xfem_contact.fem.enrichment import EnrichedSpace

SIDE_FIELDS = (0, 1)


def field_splits(space: EnrichedSpace) -> dict[str, np.ndarray]:
    """``{"u": nodes, "lambda": dofs}``: local dofs of ``space.W`` (owned and ghost) of
    the displacement fields, one row ``(x, y)`` per node and side, and of the multiplier
    fields (no ``"lambda"`` without a multiplier). Not collective."""
    W = space.W

    def dofs(fields):
        return np.unique(np.concatenate([W.sub(f).dofmap.list.ravel() for f in fields]))

    nodes = []
    for field in SIDE_FIELDS:
        parts = [W.sub(field).sub(c).dofmap.list.ravel() for c in range(W.mesh.geometry.dim)]
        nodes.append(np.unique(np.stack(parts, axis=1), axis=0))
    splits = {"u": np.concatenate(nodes)}
    multipliers = [field for field, _, _ in space.multiplier_fields]
    if multipliers:
        splits["lambda"] = dofs(multipliers)
    return splits


def rigid_modes(space: EnrichedSpace) -> list[dolfinx.fem.Function]:
    """The rigid motions of each side separately (2D: two translations and the
    rotation about the origin, per side field), as Functions on ``space.W`` (m).
    Collective."""
    modes = []
    motions = (
        lambda x: np.vstack([np.ones_like(x[0]), np.zeros_like(x[0])]),
        lambda x: np.vstack([np.zeros_like(x[0]), np.ones_like(x[0])]),
        lambda x: np.vstack([-x[1], x[0]]),
    )
    for field in SIDE_FIELDS:
        for motion in motions:
            mode = dolfinx.fem.Function(space.W)
            mode.sub(field).interpolate(motion)
            mode.x.scatter_forward()
            modes.append(mode)
    return modes
