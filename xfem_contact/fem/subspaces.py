"""Sub-spaces of mixed spaces as spaces of their own, built cell by cell.

DOLFINx's ``FunctionSpace.collapse`` of a blocked (vector) sub-space of a mixed
space on quadrilaterals is slow (DOLFINx 0.11; see the docs' performance notes).
:func:`collapse` creates the space afresh and reads the map to
the parent's dofs off the two cell dofmaps, which list a cell's dofs in the same
order (node by node, components inside a node).
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np
import numpy.typing as npt


def collapse(sub: dolfinx.fem.FunctionSpace) -> tuple[dolfinx.fem.FunctionSpace, npt.NDArray]:
    """A sub-space ``W.sub(i)`` (or ``W.sub(i).sub(j)``) as a space of its own.

    Equivalent to ``sub.collapse()`` (a space of the same element on the same mesh
    and, for each of its local dofs, the local dof of the parent space holding the
    same value), but the space's dofs are numbered as a freshly created space's.
    Collective (creates a function space).

    Args:
        sub: A sub-space view of a mixed function space.

    Returns:
        ``(V, parent)``: the space and the parent dof (local index into the mixed
        space's dof array) of each local dof of ``V`` (owned and ghost),
        shape ``(V.dofmap.index_map.size_local + num_ghosts) * V.dofmap.bs``.
    """
    if not sub.component():
        raise ValueError("collapse() takes a sub-space W.sub(i) of a mixed space")
    V = dolfinx.fem.functionspace(sub.mesh, sub.ufl_element())
    bs = V.dofmap.bs
    imap = V.dofmap.index_map
    child_cells = V.dofmap.list  # (num_cells, num_nodes): blocks of bs dofs
    parent_cells = sub.dofmap.list  # (num_cells, num_nodes * bs): unblocked
    if parent_cells.shape[1] != child_cells.shape[1] * bs:
        raise RuntimeError("collapse(): the dofmaps of the sub-space and its copy differ")
    parent = np.full((imap.size_local + imap.num_ghosts) * bs, -1, dtype=np.int32)
    child = child_cells[:, :, None] * bs + np.arange(bs, dtype=np.int32)
    parent[child.ravel()] = parent_cells.ravel()
    if parent.size and parent.min() < 0:
        raise RuntimeError("collapse(): a dof of the copy lies on no local cell")
    return V, parent
