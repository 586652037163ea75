"""Point values of finite element functions at reference points of given cells."""

from __future__ import annotations

import basix
import dolfinx.fem
import numpy as np
import numpy.typing as npt

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.quadrature.rules import RuleSet


def evaluate_reference(
    u: dolfinx.fem.Function, cells: npt.NDArray[np.int32], X: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """Values of a Lagrange function at reference points, one point per cell entry (local).

    Args:
        u: A Lagrange function, or a sub-function ``w.sub(i)`` of a mixed one.
        cells: Local cell of each point, shape ``(m,)``.
        X: Reference coordinates, shape ``(m, tdim)``.

    Returns:
        Values of shape ``(m, value_size)``.
    """
    if u.function_space.component():  # a view into a mixed function
        u = u.collapse()
    V = u.function_space
    element = basix.create_element(
        basix.ElementFamily.P,
        V.mesh.basix_cell(),
        V.ufl_element().embedded_superdegree,
        basix.LagrangeVariant.gll_warped,
    )
    basis = element.tabulate(0, X)[0, :, :, 0]  # (m, ndofs)
    bs = V.dofmap.bs
    dofs = V.dofmap.list[cells]  # (m, ndofs)
    values = u.x.array[dofs[:, :, None] * bs + np.arange(bs)]  # (m, ndofs, bs)
    return np.einsum("pi,pic->pc", basis, values)


def rule_cells(cut: CutMesh, rules: RuleSet) -> npt.NDArray[np.int32]:
    """Local cell of every point of per-cut-cell ``rules``, shape ``(npoints,)``."""
    return cut.cut_cells[rules.point_rows]


def evaluate_at_rules(
    u: dolfinx.fem.Function, cut: CutMesh, rules: RuleSet
) -> npt.NDArray[np.float64]:
    """Values of ``u`` at every point of per-cut-cell ``rules``, shape ``(npoints, value_size)``."""
    return evaluate_reference(u, rule_cells(cut, rules), rules.points)


def interface_points(cut: CutMesh, rules: RuleSet | None = None) -> npt.NDArray[np.float64]:
    """Physical coordinates of the interface quadrature points (of ``rules``, default
    all interfaces'), shape ``(npoints, gdim)`` (local)."""
    rules = cut.interface_rules if rules is None else rules
    return cut.maps.push_forward(rule_cells(cut, rules), rules.points)
