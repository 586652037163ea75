"""Compression of cut-cell rules: a subset of each rule's points, with new positive weights,
that keeps its moments of degree ``<= q`` (Tchakaloff / Caratheodory). Pure numpy.

A rule of ``n`` points with positive weights ``w`` and moments ``M w`` (``M`` the ``m x n``
values of a basis of ``P_q`` at the points, ``m = dim P_q``) has a subset of at most ``m``
points carrying the same moments with positive weights (Caratheodory's theorem on the cone of
the columns). The reduction here is recursive over groups of points: the points of a rule
are split into ``G = min(n, 2 m)`` groups of consecutive points, and a Caratheodory
elimination on the ``G`` group moments (``m``-vectors) finds scales ``s >= 0`` of the
groups, at most ``m`` of them nonzero, with ``sum_g s_g M_g = sum_g M_g``: the points of the
groups scaled by 0 are removed and the others' weights scaled. This halves a rule per round
until it has at most ``m`` points, in about ``log2(n / m)`` rounds of ``O(m^3)`` work per
rule plus ``O(n m)`` for the moments. The elimination uses the ``G - m`` null vectors of a
complete QR of the group moments (a batched LAPACK call over rules); each one moves the
scales until one of them vanishes, and the next ones are combined with it to vanish
there too. Every array of a rule has the same shape in any batch, so a rule's result does
not depend on the other rules compressed with it (the same on any partition of the cells).

The basis is the tensor Legendre polynomials of ``2 X - 1`` (well conditioned on the unit
box holding the reference triangle and tetrahedron), total degree ``<= q``. It spans the
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

_BATCH_VALUES = 1_000_000  # basis values (points x moments) per batch of rules


def num_moments(dim: int, degree: int) -> int:
    """``dim P_q`` in ``dim`` variables: ``binom(q + dim, dim)``."""
    return math.comb(degree + dim, dim)


def moment_basis(points: npt.ArrayLike, degree: int) -> npt.NDArray[np.float64]:
    """Tensor Legendre polynomials of ``2 X - 1`` of total degree ``<= degree`` at ``points``.

    Args:
        points: Reference points, shape ``(n, dim)``.
        degree: Total degree ``q >= 0``.

    Returns:
        Shape ``(num_moments(dim, q), n)``.
    """
    X = 2.0 * np.asarray(points, dtype=np.float64).T - 1.0  # (dim, n), rows contiguous
    P = [None, X]  # P[j][i]: Legendre P_j of coordinate i (P_0 = 1)
    for j in range(1, degree):
        P.append(((2 * j + 1) * X * P[j] - j * (P[j - 1] if j > 1 else 1.0)) / (j + 1))
    exponents = _exponents(X.shape[0], degree)
    values = np.ones((len(exponents), X.shape[1]))
    for k, exps in enumerate(exponents):
        for i, e in enumerate(exps):
            if e:
                values[k] *= P[e][i]
    return values


def _exponents(dim: int, degree: int) -> list[tuple[int, ...]]:
    if dim == 0:
        return [()]
    return [(a, *rest) for a in range(degree + 1) for rest in _exponents(dim - 1, degree - a)]


def compress_rules(rules: RuleSet, degree: int, keep: int | None = None) -> RuleSet:
    """Each rule of more than ``keep`` points replaced by at most ``num_moments(dim,
    degree)`` of its points with positive weights and the same moments of degree
    ``<= degree`` (to round-off); the others are kept as they are. A rule's result
    depends on that rule alone, not on the others in ``rules``, so it is the same on any
    partition of the cells.

    Args:
        rules: Rules with positive weights (side or interface rules; normals go along).
        degree: Polynomial degree ``q`` of the moments kept.
        keep: Rules of at most this many points are kept; default
            ``num_moments(dim, degree)``.

    Returns:
        A :class:`~xfem_contact.quadrature.rules.RuleSet` with the same rules (rows).
    """
    if degree < 0:
        raise ValueError(f"compression degree must be >= 0, got {degree}")
    m = num_moments(rules.points.shape[1], degree)
    if keep is None:
        keep = m
    if keep < m:
        raise ValueError(f"keep must be >= num_moments = {m} to compress, got {keep}")
    counts = np.diff(rules.offsets)
    big = np.flatnonzero(counts > keep)
    if big.size == 0:
        return rules
    weights = rules.weights.copy()
    kept = np.ones(weights.size, dtype=bool)
    ends = np.cumsum(counts[big])
    start = 0
    while start < big.size:  # batches of whole rules, of _BATCH_VALUES basis values
        stop = np.searchsorted(ends, ends[start] - counts[big[start]] + _BATCH_VALUES // m)
        stop = max(int(stop), start + 1)
        rows = big[start:stop]
        take = _ranges(rules.offsets[rows], counts[rows])
        basis = moment_basis(rules.points[take], degree) if m > 1 else None
        weights[take] = _reduce(basis, weights[take], counts[rows], m)
        kept[take] = weights[take] > 0
        start = stop
    return RuleSet(
        rules.points[kept],
        weights[kept],
        _offsets(np.bincount(rules.point_rows[kept], minlength=rules.num_rules)),
        None if rules.normals is None else rules.normals[kept],
    )


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The indices ``starts[k] + arange(counts[k])``, concatenated."""
    first = np.repeat(starts - np.cumsum(counts) + counts, counts)
    return first + np.arange(counts.sum())


def _reduce(basis: np.ndarray, w: np.ndarray, counts: np.ndarray, m: int) -> np.ndarray:
    """Recombination of rules stored back to back: basis values ``(m, N)`` at the points,
    weights ``w`` ``(N,)``, ``counts`` points per rule. Each round splits a rule of
    ``c > m`` points into ``G = min(c, 2 m)`` groups of consecutive points and scales the
    groups by ``s >= 0`` with ``sum_g s_g M_g = sum_g M_g`` (``M_g`` a group's moments)
    and at most ``m`` of them nonzero (:func:`_eliminate`): a rule of ``c > 2 m`` points
    loses about half of them, one of ``c <= 2 m`` ends with ``<= m``.

    Returns:
        The new weights ``(N,)``, zero at the points removed.
    """
    if m == 1:  # one moment (the sum of the weights): a rule's first point carries it
        first = np.cumsum(counts) - counts
        total = np.add.reduceat(w, first)
        w = np.zeros_like(w)
        w[first] = total
        return w
    w = w.copy()
    index = np.arange(w.size)  # the points still in, rule by rule
    size = counts.copy()  # their number per rule
    moments = w * basis  # (m, points still in)
    while True:
        active = size > m
        if not active.all():
            keep = np.repeat(active, size)
            index, moments, size = index[keep], moments[:, keep], size[active]
        if index.size == 0:
            return w
        first = np.cumsum(size) - size
        rank = np.arange(index.size) - np.repeat(first, size)
        G = np.minimum(size, 2 * m)
        # Every rule gets 2 m columns (zero ones past its G groups): a rule's arrays
        # have the same shape in any batch.
        slot = np.repeat(np.arange(size.size) * 2 * m, size) + (
            np.repeat(G, size) * rank // np.repeat(size, size)
        )
        starts = np.flatnonzero(np.r_[True, slot[1:] != slot[:-1]])
        grouped = np.zeros((m, size.size * 2 * m))
        grouped[:, slot[starts]] = np.add.reduceat(moments, starts, axis=1)
        grouped = grouped.reshape(m, size.size, 2 * m).transpose(1, 2, 0)
        scale = _eliminate(grouped).reshape(-1)[slot]
        w[index] *= scale
        kept = scale > 0
        size = np.bincount(np.repeat(np.arange(size.size), size)[kept], minlength=size.size)
        index, moments = index[kept], moments[:, kept] * scale[kept]


def _eliminate(M: np.ndarray) -> np.ndarray:
    """Caratheodory on columns: for ``M`` ``(r, G, m)`` (``G >= 2 m`` vectors of moments
    per rule), scales ``s >= 0`` ``(r, G)`` with ``s M = 1 M`` and at most ``m`` of them
    nonzero. The ``G - m`` null vectors of ``M^T`` (the last columns of a complete QR of
    ``M``) are used in turn: each moves ``s`` along itself until an entry vanishes, and
    the next ones are combined with it to vanish there too. A zero vector's scale is
    free (it carries no moment)."""
    r, G, m = M.shape
    rows = np.arange(r)
    null = np.linalg.qr(M, mode="complete")[0][:, :, m:].transpose(0, 2, 1).copy()  # (r, k, G)
    s = np.ones((r, G))
    ratio = np.empty((r, G))
    for j in range(G - m):
        v = null[:, j]
        v *= np.where(v.max(axis=1) >= -v.min(axis=1), 1.0, -1.0)[:, None]  # a positive entry
        positive = v > 0
        ratio.fill(np.inf)
        np.divide(s, v, out=ratio, where=positive)
        i = np.argmin(ratio, axis=1)
        alpha = ratio[rows, i]
        alpha[~np.isfinite(alpha)] = 0.0
        s -= alpha[:, None] * v
        np.maximum(s, 0.0, out=s)
        s[rows, i] = 0.0
        if j + 1 < G - m:
            rest = null[:, j + 1 :]
            pivot = v[rows, i]
            factor = rest[rows, :, i] / np.where(pivot > 0, pivot, 1.0)[:, None]
            rest -= factor[:, :, None] * v[:, None, :]
            rest[rows, :, i] = 0.0
    return s
