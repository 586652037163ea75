"""Compression of cut-cell rules: a subset of each rule's points, with new positive weights,
that keeps its moments of degree ``<= q`` (Tchakaloff / Caratheodory). Pure numpy.

A rule of ``n`` points with positive weights ``w`` and moments ``M w`` (``M`` the ``m x n``
values of a basis of ``P_q`` at the points, ``m = dim P_q``) has a subset of at most ``m``
points carrying the same moments with positive weights (Caratheodory's theorem on the cone of
the columns). The reduction here removes points by null vectors of ``M``: for ``v`` with
``M v = 0``, ``w - alpha v`` keeps the moments, and the largest ``alpha`` that keeps every
weight ``>= 0`` zeroes one of them. Points enter one at a time next to the ``m`` kept,
and the null vector of those ``m + 1`` (the last column of a batched complete QR) removes
one. Vectorised over rules; the loop runs over the points to remove, so the cost grows as
``n m^3`` per rule.

The basis is the tensor Legendre polynomials of ``2 X - 1`` (well conditioned on the unit
box holding the reference tetrahedron and hexahedron), total degree ``<= q``. It spans the
monomials ``x^a y^b z^c``, ``a + b + c <= q``, so their moments are kept too. For an
interface rule the moments are those of the surface weights (polynomials restricted to the
surface); the normals of the kept points go with them.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from xfem_contact.quadrature.rules import RuleSet, _offsets

__all__ = ["compress_rules", "moment_basis", "num_moments"]


def num_moments(dim: int, degree: int) -> int:
    """``dim P_q`` in ``dim`` variables: ``binom(q + dim, dim)``."""
    return math.comb(degree + dim, dim)


def moment_basis(points: npt.ArrayLike, degree: int) -> npt.NDArray[np.float64]:
    """Tensor Legendre polynomials of ``2 X - 1`` of total degree ``<= degree`` at ``points``.

    Args:
        points: Reference points, shape ``(..., dim)``.
        degree: Total degree ``q >= 0``.

    Returns:
        Shape ``(..., num_moments(dim, q))``.
    """
    X = 2.0 * np.asarray(points, dtype=np.float64) - 1.0
    dim = X.shape[-1]
    P = [np.ones_like(X), X]  # P[j][..., i]: Legendre P_j of coordinate i
    for j in range(1, degree):
        P.append(((2 * j + 1) * X * P[j] - j * P[j - 1]) / (j + 1))
    columns = [
        np.prod([P[e][..., i] for i, e in enumerate(exps)], axis=0)
        for exps in _exponents(dim, degree)
    ]
    return np.stack(columns, axis=-1)


def _exponents(dim: int, degree: int) -> list[tuple[int, ...]]:
    if dim == 0:
        return [()]
    return [(a, *rest) for a in range(degree + 1) for rest in _exponents(dim - 1, degree - a)]


def compress_rules(rules: RuleSet, degree: int) -> RuleSet:
    """Each rule replaced by at most ``num_moments(dim, degree)`` of its points with positive
    weights and the same moments of degree ``<= degree`` (to round-off). Rules with no more
    points are kept as they are.

    Args:
        rules: Rules with positive weights (side or interface rules; normals go along).
        degree: Polynomial degree ``q`` of the moments kept.

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` with the same rules (rows).
    """
    if degree < 0:
        raise ValueError(f"compression degree must be >= 0, got {degree}")
    dim = rules.points.shape[1]
    m = num_moments(dim, degree)
    counts = np.diff(rules.offsets)
    big = np.flatnonzero(counts > m)
    if big.size == 0:
        return rules
    n = int(counts[big].max())
    # Padded per-rule slots: index into rules' points; a padding slot repeats the rule's
    # first point with weight 0 (a real point, so a null vector may give it weight).
    slot = np.arange(n)
    real = slot < counts[big, None]
    index = rules.offsets[big, None] + np.where(real, slot, 0)
    w = np.where(real, rules.weights[index], 0.0)
    index, w = _reduce(moment_basis(rules.points[index], degree), index, w, m)
    kept = w > 0
    new_counts = counts.copy()
    new_counts[big] = kept.sum(axis=1)
    small = np.ones(rules.weights.size, dtype=bool)
    small[np.repeat(np.isin(np.arange(rules.num_rules), big), counts)] = False
    take = np.concatenate([np.flatnonzero(small), index[kept]])
    weights = np.concatenate([rules.weights[small], w[kept]])
    row = np.concatenate([rules.point_rows[small], np.repeat(big, new_counts[big])])
    sort = np.argsort(row, kind="stable")
    take = take[sort]
    return RuleSet(
        rules.points[take],
        weights[sort],
        _offsets(new_counts),
        None if rules.normals is None else rules.normals[take],
    )


def _reduce(basis, index, w, m):
    """Caratheodory reduction of the rules of slots ``index`` ``(r, n)``, weights ``w`` and
    basis values ``basis`` ``(r, n, m)`` to ``m`` slots: each step adds one slot to the
    ``m`` kept and removes one along a null vector of the ``m x (m + 1)`` moment matrix.

    Returns:
        ``(index, weights)`` of shape ``(r, m)`` (weight 0: an empty slot).
    """
    rows = np.arange(index.shape[0])
    idx, A, cur = index[:, :m], basis[:, :m], w[:, :m]
    for j in range(m, index.shape[1]):
        idx = np.concatenate([idx, index[:, j : j + 1]], axis=1)
        A = np.concatenate([A, basis[:, j : j + 1]], axis=1)
        cur = np.concatenate([cur, w[:, j : j + 1]], axis=1)
        v = np.linalg.qr(A, mode="complete")[0][:, :, -1]  # orthogonal to A's columns
        v = np.where((v.max(axis=1) > -v.min(axis=1))[:, None], v, -v)  # a positive entry
        ratio = np.where(v > 0, cur / np.where(v > 0, v, 1.0), np.inf)
        i = np.argmin(ratio, axis=1)
        cur = np.maximum(cur - ratio[rows, i][:, None] * v, 0.0)
        cur[rows, i] = 0.0
        keep = np.argsort(np.arange(m + 1) == i[:, None], axis=1, kind="stable")[:, :m]
        idx = np.take_along_axis(idx, keep, axis=1)
        A = np.take_along_axis(A, keep[..., None], axis=1)
        cur = np.take_along_axis(cur, keep, axis=1)
    return idx, cur
