"""Point values of finite element functions at reference points of given cells."""

from __future__ import annotations

import basix
import dolfinx.fem
import numpy as np
import numpy.typing as npt

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.quadrature.rules import RuleSet


def lagrange_element(V: dolfinx.fem.FunctionSpace) -> basix.finite_element.FiniteElement:
    """The scalar Lagrange element of ``V`` (or of a sub-space ``W.sub(i)``), whose
    ``tabulate(k, X)`` gives the basis and its reference derivatives up to order ``k``
    at reference points ``X`` in the node order of :func:`cell_dofs`."""
    return basix.create_element(
        basix.ElementFamily.P,
        V.mesh.basix_cell(),
        V.ufl_element().embedded_superdegree,
        basix.LagrangeVariant.gll_warped,
    )


def _basis(V: dolfinx.fem.FunctionSpace, X: npt.NDArray[np.float64]) -> np.ndarray:
    """The Lagrange basis of ``V``'s element at reference points ``X``, ``(n, nnodes)``."""
    return lagrange_element(V).tabulate(0, X)[0, :, :, 0]


def cell_dofs(V: dolfinx.fem.FunctionSpace, cells: npt.NDArray[np.int32]) -> np.ndarray:
    """Indices into the array of a Function on ``V`` (or on its parent, for a view
    ``W.sub(i)``: unblocked dofs of ``W``, node by node) of the dofs of each cell,
    shape ``(len(cells), nnodes, value_size)``."""
    if V.component():
        bs = V.ufl_element().reference_value_size
        dofs = V.dofmap.list[cells]  # explicit shape: a process may have no cells here
        return dofs.reshape(len(cells), dofs.shape[1] // bs, bs)
    bs = V.dofmap.bs
    return V.dofmap.list[cells][:, :, None] * bs + np.arange(bs)


def evaluate_reference(
    u: dolfinx.fem.Function, cells: npt.NDArray[np.int32], X: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """Values of a Lagrange function at reference points, one point per cell entry (local).

    Args:
        u: A Lagrange function, or a sub-function ``w.sub(i)`` of a mixed one (read in
            place, not collapsed).
        cells: Local cell of each point, shape ``(m,)``.
        X: Reference coordinates, shape ``(m, tdim)``.

    Returns:
        Values of shape ``(m, value_size)``.
    """
    V = u.function_space
    values = u.x.array[cell_dofs(V, cells)]  # (m, nnodes, value_size)
    basis = _basis(V, X)  # (m, nnodes)
    return np.einsum("pi,pic->pc", basis, values)


def evaluate_lattice(
    u: dolfinx.fem.Function, cells: npt.NDArray[np.int32], X: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """Values of a Lagrange function at the same reference points ``X`` (k, tdim) in
    every one of ``cells`` (the basis tabulated once), shape ``(len(cells) * k,
    value_size)``, cell by cell. ``u`` as for :func:`evaluate_reference`. Local."""
    V = u.function_space
    basis, dofs = _basis(V, X), cell_dofs(V, cells)  # (k, nnodes), (n, nnodes, bs)
    values = np.einsum("ki,cis->cks", basis, u.x.array[dofs])
    return values.reshape(-1, values.shape[-1])


class FieldSampler:
    """Values of the fields of functions on one mixed space at fixed points.

    For a Newton status line or a state evaluated at every iterate: the basis of
    each field at the points and the dofs of ``W`` it reads are computed once (per
    field, on first use), after which a sample is one gather and one contraction.
    Not collective; local to a process.

    Args:
        W: The mixed function space.
        cells: Local cell of each point, shape ``(m,)``.
        X: Reference coordinates, shape ``(m, tdim)``.
    """

    def __init__(
        self,
        W: dolfinx.fem.FunctionSpace,
        cells: npt.NDArray[np.int32],
        X: npt.NDArray[np.float64],
    ):
        self.W, self.cells, self.X = W, cells, X
        self._fields: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def __call__(self, w: dolfinx.fem.Function, field: int) -> npt.NDArray[np.float64]:
        """Values of field ``field`` of ``w`` (a Function on ``W``), ``(m, value_size)``."""
        if field not in self._fields:
            V = self.W.sub(field)
            basis, dofs = _basis(V, self.X), cell_dofs(V, self.cells)
            self._fields[field] = (basis, dofs)
        basis, dofs = self._fields[field]
        return np.einsum("pi,pic->pc", basis, w.x.array[dofs])


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
