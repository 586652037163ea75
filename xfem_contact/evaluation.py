"""Point values of finite element functions at the quadrature points of cut cells."""

from __future__ import annotations

import basix
import dolfinx.fem
import numpy as np
import numpy.typing as npt

from xfem_contact.cutmesh import CutMesh
from xfem_contact.quadrature import RuleSet


def evaluate_at_rules(
    u: dolfinx.fem.Function, cut: CutMesh, rules: RuleSet
) -> npt.NDArray[np.float64]:
    """Values of a (sub-)function at every point of per-cut-cell rules (local, no communication).

    Args:
        u: A Lagrange function, or a sub-function ``w.sub(i)`` of a mixed one.
        cut: The cut mesh the rules belong to (rule ``k`` lives in ``cut.cut_cells[k]``).
        rules: The rules (reference points).

    Returns:
        Values of shape ``(npoints, value_size)``.
    """
    if u.function_space.component():  # a view into a mixed function
        u = u.collapse()
    V = u.function_space
    element = V.ufl_element()
    scalar = basix.create_element(
        basix.ElementFamily.P,
        cut.mesh.basix_cell(),
        element.embedded_superdegree,
        basix.LagrangeVariant.gll_warped,
    )
    rows = np.repeat(np.arange(rules.offsets.size - 1), np.diff(rules.offsets))
    basis = scalar.tabulate(0, rules.points)[0, :, :, 0]  # (npoints, ndofs)
    bs = V.dofmap.bs
    dofs = V.dofmap.list[cut.cut_cells[rows]]  # (npoints, ndofs)
    values = u.x.array[(dofs[:, :, None] * bs + np.arange(bs)).reshape(dofs.shape[0], -1)]
    return np.einsum("pi,pic->pc", basis, values.reshape(dofs.shape[0], dofs.shape[1], bs))


def interface_points(cut: CutMesh) -> npt.NDArray[np.float64]:
    """Physical coordinates of the interface quadrature points, shape ``(npoints, gdim)``."""
    rules = cut.rules[3]
    rows = np.repeat(np.arange(rules.offsets.size - 1), np.diff(rules.offsets))
    return cut.maps.push_forward(cut.cut_cells[rows], rules.points)
