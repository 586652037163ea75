"""Moment fitting: an independent oracle for cut-cell integration.

Per cut cell, weights at *fixed* points (a standard rule of the parent cell)
are fitted so that the rule integrates a polynomial basis exactly over one side
of the cut (moments from the sub-triangulation). The weights reach FFCx through
a quadrature-element Function multiplying the integrand, the standard FFCx path
with no runtime kernel. Exact for integrands in the fitted space on affine
cells; weights may be negative. A test oracle and fallback, not the main path.
"""

from __future__ import annotations

import basix
import basix.ufl
import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.quadrature.rules import RuleSet


def fitted_weights(
    cell: str, rules: RuleSet, degree: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit weights at the points of basix's default rule of ``2 * degree``.

    Args:
        cell: ``"triangle"`` or ``"quadrilateral"``.
        rules: Per-cell rules (reference coordinates) giving the moments.
        degree: Polynomial degree ``k`` of the fitted space (P_k on
            triangles, Q_k on quadrilaterals).

    Returns:
        Fixed points ``(nq, tdim)``, their standard weights ``(nq,)`` and the
        fitted weights ``(ncells, nq)`` in the reference measure.
    """
    cell_type = basix.CellType[cell]
    points, std_weights = basix.make_quadrature(cell_type, 2 * degree)
    basis_at_points = basix.tabulate_polynomials(
        basix.PolynomialType.legendre, cell_type, degree, points
    )  # (nbasis, nq)
    basis_at_rules = basix.tabulate_polynomials(
        basix.PolynomialType.legendre, cell_type, degree, rules.points
    )  # (nbasis, N)
    ncells = rules.offsets.size - 1
    owner = rules.point_rows
    moments = np.zeros((ncells, basis_at_rules.shape[0]))
    np.add.at(moments, owner, (basis_at_rules * rules.weights).T)
    fitted = np.linalg.lstsq(basis_at_points, moments.T, rcond=None)[0].T
    return points, std_weights, fitted


def measure_and_weight(
    mesh: dolfinx.mesh.Mesh, cells: np.ndarray, rules: RuleSet, degree: int
) -> tuple[dolfinx.fem.Function, ufl.Measure]:
    """A weight Function and a measure such that ``expr * weight * measure``
    integrates ``expr`` over the rules' region by moment fitting.

    Args:
        mesh: The mesh.
        cells: Owned cells the rules belong to, shape ``(ncells,)``.
        rules: Per-cell rules giving the exact moments.
        degree: Degree of the fitted polynomial space.
    """
    cell = mesh.topology.cell_name()
    points, std_weights, fitted = fitted_weights(cell, rules, degree)
    element = basix.ufl.quadrature_element(
        mesh.basix_cell(), value_shape=(), points=points, weights=std_weights
    )
    weight = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, element), name="mf_weight")
    dofs = weight.function_space.dofmap.list[cells]
    weight.x.array[dofs] = fitted / std_weights
    measure = ufl.Measure(
        "dx", domain=mesh, subdomain_data=[(1, np.asarray(cells, np.int32))], subdomain_id=1
    )
    return weight, measure
