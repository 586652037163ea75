"""Rules on surfaces in reference coordinates of 3D cells, mapped to the physical measure.

A surface rule point carries its reference position ``X``, its *area vector* ``a``
(the reference unit normal times the reference area element of the surface's
parametrisation, pointing from side -1 to side +1) and a weight ``w`` in that
parameter. With the parent Jacobian ``J = dx/dX`` at ``X`` (Nanson's formula) the
physical area element is ``|det J| |J^{-T} a| w``. Rules store weights in the parent
*reference* measure, as FFCx multiplies every weight by ``|det J|``: the stored weight
is ``w |J^{-T} a|`` and the physical unit normal ``J^{-T} a / |J^{-T} a|``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from xfem_contact.quadrature.rules import RuleSet

__all__ = ["surface_rules"]

Jacobian = Callable[[np.ndarray, np.ndarray], np.ndarray]
"""``(rows (m,), X (m, 3)) -> (m, 3, 3)``: the parent map's Jacobian ``dx/dX`` at reference
points of cells ``rows``."""


def surface_rules(
    X: npt.NDArray[np.float64],
    area: npt.NDArray[np.float64],
    w: npt.NDArray[np.float64],
    rows: npt.NDArray[np.int64],
    ncells: int,
    jacobian: Jacobian | None = None,
) -> RuleSet:
    """Per-cell surface rules with physical unit normals, in the parent reference measure.

    Args:
        X: Reference points, shape ``(N, 3)``, sorted by ``rows``.
        area: Reference area vectors there, shape ``(N, 3)``, pointing to side +1.
        w: Weights in the surface parameter, shape ``(N,)``.
        rows: Cell row of each point, shape ``(N,)``, sorted.
        ncells: Number of cells (rules).
        jacobian: The parent map's Jacobian (see :data:`Jacobian`); ``None``: the
            identity (the reference cell is the physical cell).

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` with weights ``w |J^{-T} a|``
        and unit normals ``(N, 3)``.
    """
    if jacobian is None:
        mapped = area
    else:
        J = np.asarray(jacobian(rows, X), dtype=np.float64)
        if J.shape != (rows.size, 3, 3):
            raise ValueError(f"jacobian must return shape ({rows.size}, 3, 3), got {J.shape}")
        mapped = np.linalg.solve(np.swapaxes(J, 1, 2), area[..., None])[..., 0]
    norm = np.linalg.norm(mapped, axis=1)
    normals = np.divide(mapped, norm[:, None], out=np.zeros_like(mapped), where=norm[:, None] > 0)
    offsets = np.searchsorted(rows, np.arange(ncells + 1)).astype(np.int64)
    return RuleSet(X, w * norm, offsets, normals)
