"""A level set given as a function (not a polynomial) on lines of reference cells: its
roots on a line, found where its interpolant has them, and its gradient by central
differences (pure numpy), for rules that follow the exact zero set of a level set whose
interpolant chose their lines and boxes (:mod:`xfem_contact.quadrature.saye`).

Tolerance policy, as for the interpolant's lines
(:func:`~xfem_contact.geometry.tensor_levelset.line_roots`): ``phi < 0`` is side -1,
``phi >= 0`` side +1; a monotone piece of a line has a root where the signs at its ends
differ (an end where ``phi`` vanishes is that root); a root within ``16 eps`` of an end
(relative to the piece) is that end.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.roots import illinois

__all__ = ["STEP", "ExactLevelSet", "central_gradient", "line_roots"]

ExactLevelSet = Callable[[npt.NDArray[np.int64], npt.NDArray[np.float64]], npt.NDArray[np.float64]]
"""``exact(rows (m,), X (m, tdim)) -> (m,)``: the exact level set at reference points ``X``
of the cut cells ``rows`` (row numbers of their nodal values)."""

STEP = 2.0**-12
"""Step of :func:`central_gradient` in reference coordinates (a power of two: ``X +- STEP``
is exact): the truncation error ``STEP^2 / 6 |phi'''|`` and the round-off
``eps |phi| / STEP`` are both below ``1e-9`` of the gradient on cells of the size of the
level set's features or smaller."""


def line_roots(
    phi: Callable[[np.ndarray, np.ndarray], np.ndarray],
    X: npt.NDArray[np.float64],
    axis: int,
    lo: npt.NDArray[np.float64],
    hi: npt.NDArray[np.float64],
    c: npt.NDArray[np.float64],
) -> npt.NDArray[np.float64]:
    """The roots of ``phi`` on the lines ``X + t e_axis``, ``t`` in ``[lo, hi]``, near those
    of its interpolant there: each line is split at the critical point of the interpolant's
    restriction ``c`` (degree <= 2, so into at most two pieces on which it is monotone),
    and each piece has the root of ``phi`` where its signs at the piece's ends differ.

    Args:
        phi: ``(lines (k,), Y (k, 3)) -> (k,)``: ``phi`` at points ``Y`` of lines ``lines``.
        X: A point of each line, shape ``(m, 3)`` (its ``axis`` coordinate is ignored).
        axis: The lines' direction, 0, 1 or 2.
        lo, hi: The ends of each line, shape ``(m,)``.
        c: The interpolant's restrictions to the lines, coefficients in ``t`` lowest
            first, shape ``(m, 1..3)``
            (:func:`~xfem_contact.geometry.tensor_levelset.line_coefficients`).

    Returns:
        Shape ``(m, 2)`` (as :func:`~xfem_contact.geometry.tensor_levelset.line_roots`):
        the roots in ascending order, NaN where there is none.
    """
    m = X.shape[0]
    split = np.array(hi, dtype=np.float64)
    if c.shape[1] == 3:
        with np.errstate(divide="ignore", invalid="ignore"):
            critical = -c[:, 1] / (2.0 * c[:, 2])
        inside = (c[:, 2] != 0) & (critical > lo) & (critical < hi)
        split[inside] = critical[inside]
    roots = np.full((m, 2), np.nan)
    roots[:, 0] = _root(phi, X, axis, lo, split)
    second = np.flatnonzero(split < hi)
    if second.size:
        root = _root(lambda i, Y: phi(second[i], Y), X[second], axis, split[second], hi[second])
        roots[second, 1] = np.where(root == roots[second, 0], np.nan, root)  # not twice
    return roots


def _root(phi, X, axis, lo, hi) -> np.ndarray:
    """The root of ``phi`` on each line ``X + t e_axis``, ``t`` in ``[lo, hi]``, where its
    signs at the ends differ (an end where it vanishes: that end), else NaN."""
    m = X.shape[0]
    lines = np.arange(m)
    ends = []
    for t in (lo, hi):
        Y = X.copy()
        Y[:, axis] = t
        ends.append(phi(lines, Y))
    f_lo, f_hi = ends
    root = np.full(m, np.nan)
    root[f_lo == 0] = lo[f_lo == 0]
    at_hi = (f_hi == 0) & (f_lo < 0)
    root[at_hi] = hi[at_hi]
    inner = np.flatnonzero((f_lo != 0) & (f_hi != 0) & ((f_lo < 0) != (f_hi < 0)))
    if inner.size == 0:
        return root
    sign = np.where(f_lo[inner] < 0, 1.0, -1.0)  # sign * phi goes from < 0 to > 0

    def oriented(i: np.ndarray, t: np.ndarray) -> np.ndarray:
        Y = X[inner[i]].copy()
        Y[:, axis] = t
        return sign[i] * phi(inner[i], Y)

    a, b = lo[inner], hi[inner]
    tol = 4.0 * np.finfo(np.float64).eps * np.maximum(1.0, np.maximum(np.abs(a), np.abs(b)))
    t = illinois(oriented, a, b, sign * f_lo[inner], sign * f_hi[inner], tol)
    close = 16.0 * np.finfo(np.float64).eps * (b - a)
    root[inner] = np.where(t - a <= close, a, np.where(b - t <= close, b, t))
    return root


def central_gradient(
    phi: Callable[[np.ndarray], np.ndarray], X: npt.NDArray[np.float64], step: float = STEP
) -> npt.NDArray[np.float64]:
    """The gradient of ``phi`` at points ``X`` ``(m, 3)`` by central differences of
    ``step``, shape ``(m, 3)``; ``phi`` maps points ``(m, 3)`` to ``(m,)``."""
    grad = np.empty_like(X)
    for d in range(3):
        up, down = X.copy(), X.copy()
        up[:, d] += step
        down[:, d] -= step
        grad[:, d] = (phi(up) - phi(down)) / (2.0 * step)
    return grad
