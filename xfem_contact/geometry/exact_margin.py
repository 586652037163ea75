"""How far a level set given as a function may stray from its P2 interpolant on a
tetrahedron: a bound of ``|phi - phi_h|`` per cell, so that a box certified on one side
by the interpolant's Bernstein coefficients is certified for ``phi`` too (pure numpy and
Basix).

The interpolant ``phi_h`` agrees with ``phi`` at the ten P2 nodes; between them they differ
by the interpolation error ``e = phi - phi_h``, of order ``h^3 |D^3 phi|``. Where the zero
set of ``phi`` bulges out of a cell by less than ``e`` (a thin lens or cap next to a face
or an edge), every nodal value, and every Bernstein coefficient of ``phi_h`` on a box,
may have one sign while ``phi`` changes sign in the box. :func:`exact_margin` samples
``e`` at the 20 points of the cubic lattice of the reference tetrahedron, where it is
the cubic interpolant of ``e``, and bounds that cubic over the tetrahedron by its
Bernstein coefficients (the convex-hull property). The bound is exact for the cubic part of
``e``; :data:`SAFETY` covers its quartic and higher terms. A box whose interpolant's
Bernstein coefficients are all below ``-margin`` (all ``>= margin``) lies on side -1
(+1) for ``phi``.
"""

from __future__ import annotations

import functools

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.exact_lines import ExactLevelSet
from xfem_contact.geometry.simplex_bernstein import lattice_indices, lattice_to_bernstein

__all__ = ["SAFETY", "exact_margin"]

SAFETY = 2.0
"""Factor on the cubic bound of ``|phi - phi_h|`` in :func:`exact_margin` (the terms of
degree four and higher of the interpolation error, smaller by a factor of order ``h``)."""


@functools.cache
def _lattice() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cubic lattice of the reference tetrahedron ``(20, 3)``, the P2 basis at it
    ``(20, 10)`` (Basix ``gll_warped`` order) and the matrix ``(20, 20)`` taking values
    at the lattice to the Bernstein coefficients of the cubic that interpolates them."""
    alphas = lattice_indices(3)
    X = np.array([a[1:] for a in alphas], dtype=np.float64) / 3.0
    p2 = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    return X, p2.tabulate(0, X)[0, :, :, 0], lattice_to_bernstein(3)


def exact_margin(phi: npt.ArrayLike, exact: ExactLevelSet) -> npt.NDArray[np.float64]:
    """Bound of ``|exact - phi_h|`` over each tetrahedron, ``SAFETY`` times the largest
    Bernstein coefficient of the cubic interpolant of the difference (see the module).

    Args:
        phi: P2 nodal values of the interpolant, shape ``(ncells, 10)`` (Basix order).
        exact: ``(rows, X) -> (m,)``: the level set at reference points ``X`` ``(m, 3)`` of
            cells ``rows`` (rows of ``phi``).

    Returns:
        Shape ``(ncells,)``, in the level set's units, ``>= 0``.
    """
    phi = np.asarray(phi, dtype=np.float64)
    n = phi.shape[0]
    X, P2, to_bernstein = _lattice()
    rows = np.repeat(np.arange(n), X.shape[0])
    values = np.asarray(exact(rows, np.tile(X, (n, 1))), dtype=np.float64).reshape(n, len(X))
    # einsum, not BLAS: a cell's margin must not depend on the batch it is in
    error = values - np.einsum("nk,jk->nj", phi, P2)
    return SAFETY * np.abs(np.einsum("nj,bj->nb", error, to_bernstein)).max(axis=1, initial=0.0)
