"""Closest points on the deformed master lip: bounding boxes, then Newton per piece.

For a slave point ``x`` and a master piece ``x_m(s)``
(:class:`~xfem_contact.mechanics.sliding.lips.MasterLip`),
the closest point solves ``f(s) = (x - x_m(s)) . x_m'(s) = 0`` (Newton, ``f'(s) =
-|x_m'|^2 + (x - x_m) . x_m''``). Candidates are the pieces whose deformed bounding
box, grown by the search radius, holds the point, nearest first; the pair kept is the
closest one whose foot lies on its piece, else the nearest piece end. Points farther
than the search radius from every piece are unpaired. Vectorised over all points;
local (each process pairs its own slave points against the whole lip). SI units (m).
"""

from __future__ import annotations

import typing

import numpy as np
import numpy.typing as npt

#: Parameters at which each deformed piece is sampled for its bounding box
_SAMPLES = np.linspace(0.0, 1.0, 5)
#: A foot at ``s`` in ``[-_ON_PIECE, 1 + _ON_PIECE]`` lies on its piece
_ON_PIECE = 1e-9


class Pairing(typing.NamedTuple):
    """Master piece and parameter of each slave point (``piece`` -1: unpaired).

    Attributes:
        piece: Index into the lip's pieces, ``(m,)``, -1 where unpaired.
        s: Piece parameter of the foot, ``(m,)`` (0 where unpaired).
        distance: Distance to the foot (m), ``(m,)``; where unpaired, to the nearest
            sample of the lip (a lower bound is all that is known: beyond the radius).
    """

    piece: npt.NDArray[np.int64]
    s: npt.NDArray[np.float64]
    distance: npt.NDArray[np.float64]

    @property
    def paired(self) -> npt.NDArray[np.bool_]:
        return self.piece >= 0


def _polynomials(lip) -> np.ndarray | None:
    """Each deformed piece as a polynomial in ``tau = 2 s - 1``: monomial coefficients
    ``(P, d + 1, 2)``, interpolated at ``d + 1`` Chebyshev points (exact: the cell
    map and the displacement are polynomials of degree ``<= tdim k`` in the
    reference coordinates, ``k`` their Lagrange degree, and those are quadratic in
    ``s``: ``d = 4 k``). Cached on the lip until its next ``refresh``; None for a lip
    without elements."""
    cache = getattr(lip, "cache", None)
    if cache is not None and "polynomials" in cache:
        return cache["polynomials"]
    elements = [getattr(lip, name, None) for name in ("element", "coordinate_element")]
    if any(e is None for e in elements):
        return None
    d = 4 * max(e.embedded_superdegree for e in elements)
    tau = np.cos(np.pi * (np.arange(d + 1) + 0.5) / (d + 1))
    P = lip.size
    x = lip.curve(np.repeat(np.arange(P), d + 1), np.tile(0.5 * (tau + 1.0), P)).x
    V = tau[:, None] ** np.arange(d + 1)[None, :]
    values = x.reshape(P, d + 1, 2).transpose(1, 0, 2).reshape(d + 1, 2 * P)
    coefficients = np.linalg.solve(V, values).reshape(d + 1, P, 2).transpose(1, 0, 2)
    if cache is not None:
        cache["polynomials"] = coefficients
    return coefficients


def _horner(coefficients: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(x, dx/ds, d^2x/ds^2)`` of polynomials ``(m, d + 1, 2)`` (in ``tau = 2 s - 1``)
    at ``s`` ``(m,)``, each ``(m, 2)``."""
    tau = (2.0 * s - 1.0)[:, None]
    p = coefficients[:, -1].copy()
    dp = np.zeros_like(p)
    ddp = np.zeros_like(p)
    for k in range(coefficients.shape[1] - 2, -1, -1):
        ddp = ddp * tau + 2.0 * dp
        dp = dp * tau + p
        p = p * tau + coefficients[:, k]
    return p, 2.0 * dp, 4.0 * ddp


def _newton(lip, x: np.ndarray, pieces: np.ndarray, s: np.ndarray, iterations: int = 30):
    """:func:`_exact_newton` started from the feet on the pieces' polynomials
    (:func:`_polynomials`, no element tabulated), which the exact curve then
    polishes in one or two iterations."""
    coefficients = _polynomials(lip)
    if coefficients is not None and pieces.size:
        s = _exact_newton(None, x, pieces, s, iterations, coefficients[pieces])
    return _exact_newton(lip, x, pieces, s, iterations)


def _exact_newton(
    lip, x: np.ndarray, pieces: np.ndarray, s: np.ndarray, iterations: int = 30, polynomials=None
):
    """Newton on ``f(s) = 0`` for each (point, piece), started from ``s``, on the
    exact curve or on the pieces' ``polynomials`` (``(m, d + 1, 2)``); the
    parameter is kept in ``[-0.5, 1.5]`` (the polynomial piece extended a little).
    Only the pairs not yet converged are iterated on; a pair held at a bound twice
    in a row stays there (its foot is off the piece)."""
    s = s.copy()
    active = np.arange(s.size)
    bound = np.zeros(s.size, dtype=bool)
    for _ in range(iterations):
        if active.size == 0:
            break
        if polynomials is None:
            c = lip.curve(pieces[active], s[active])
            c_x, c_t, c_t2 = c.x, c.t, c.t2
        else:
            c_x, c_t, c_t2 = _horner(polynomials[active], s[active])
        r = x[active] - c_x
        f = -np.sum(r * c_t, axis=1)
        df = np.sum(c_t * c_t, axis=1) - np.sum(r * c_t2, axis=1)
        step = np.where(df > 0.0, f / np.where(df > 0.0, df, 1.0), 0.0)
        new = s[active] - step
        held = (new < -0.5) | (new > 1.5)
        s[active] = np.clip(new, -0.5, 1.5)
        keep = (np.abs(step) >= 1e-14) & ~(held & bound[active])
        bound[active] = held
        active = active[keep]
    return s


def _boxes(samples, radius):
    """The pieces' deformed boxes, grown by a quarter of their diagonal (the bulge
    of a curved piece between its samples) and the search radius: ``(low, high)``,
    each ``(P, 2)``."""
    low, high = samples.min(axis=1), samples.max(axis=1)
    grow = 0.25 * np.linalg.norm(high - low, axis=1)[:, None] + radius
    return low - grow, high + grow


def _grid(low, high):
    """A uniform grid over the boxes (cell size their mean extent) and, per grid
    cell, the boxes that overlap it: ``(origin (2,), size, shape (2,), offsets,
    boxes)`` (CSR: grid cell ``c`` holds ``boxes[offsets[c]:offsets[c + 1]]``)."""
    origin = low.min(axis=0)
    spread = high.max(axis=0) - origin
    size = float(np.mean(np.max(high - low, axis=1)))  # at most ~4 cells per box
    size = max(size, float(np.sqrt(np.prod(spread) / (4 * low.shape[0]))), 1e-300)
    first = np.floor((low - origin) / size).astype(np.int64)
    last = np.floor((high - origin) / size).astype(np.int64)
    shape = last.max(axis=0) + 1
    span = last - first + 1  # grid cells per box and direction
    count = span[:, 0] * span[:, 1]
    box = np.repeat(np.arange(low.shape[0]), count)
    k = np.arange(box.size) - np.repeat(np.cumsum(count) - count, count)  # within a box
    i = first[box, 0] + k % span[box, 0]
    j = first[box, 1] + k // span[box, 0]
    cell = i * shape[1] + j
    order = np.argsort(cell, kind="stable")
    offsets = np.zeros(shape[0] * shape[1] + 1, dtype=np.int64)
    np.cumsum(np.bincount(cell, minlength=shape[0] * shape[1]), out=offsets[1:])
    return origin, size, shape, offsets, box[order]


def _candidates(x, samples, radius, k):
    """The ``k`` pieces whose grown box holds each point, nearest sample first:
    ``(order (m, k), tried (m, k) bool, nearest sample distance (m,))``. The boxes
    are binned on a uniform grid (:func:`_grid`): each point is tested against the
    boxes of its grid cell only; the nearest sample is exact within the radius
    (every sample that near lies in a box holding the point), beyond it computed
    over the whole lip for those points only."""
    m = x.shape[0]
    low, high = _boxes(samples, radius)
    origin, size, shape, offsets, boxes = _grid(low, high)
    ij = np.floor((x - origin) / size).astype(np.int64)
    inside_grid = np.all((ij >= 0) & (ij < shape), axis=1)
    cell = np.where(inside_grid, ij[:, 0] * shape[1] + ij[:, 1], 0)
    count = np.where(inside_grid, offsets[cell + 1] - offsets[cell], 0)
    point = np.repeat(np.arange(m), count)
    piece = boxes[
        np.repeat(offsets[cell] - np.cumsum(count) + count, count) + np.arange(point.size)
    ]
    p = x[point]
    inside = np.all((p >= low[piece]) & (p <= high[piece]), axis=1)
    point, piece = point[inside], piece[inside]
    d2 = np.min(np.sum((x[point, None, :] - samples[piece]) ** 2, axis=2), axis=1)
    by = np.lexsort((piece, d2, point))  # per point: nearest first, ties by piece
    point, piece, d2 = point[by], piece[by], d2[by]
    starts = np.searchsorted(point, np.arange(m))
    rank = np.arange(point.size) - starts[point]
    keep = rank < k
    order = np.zeros((m, k), dtype=np.int64)
    tried = np.zeros((m, k), dtype=bool)
    order[point[keep], rank[keep]] = piece[keep]
    tried[point[keep], rank[keep]] = True
    nearest = np.full(m, np.inf)
    nearest[point[rank == 0]] = np.sqrt(d2[rank == 0])
    far = np.flatnonzero(~(nearest <= radius))
    for chunk in np.array_split(far, max(1, far.size // 256)) if far.size else ():
        d2 = np.sum((x[chunk, None, None, :] - samples[None]) ** 2, axis=3)
        nearest[chunk] = np.sqrt(d2.min(axis=(1, 2)))
    return order, tried, nearest


def lip_samples(lip) -> np.ndarray:
    """The deformed pieces at :data:`_SAMPLES`, ``(P, 5, 2)`` (m), cached on the lip
    until its next ``refresh`` when it offers it (``lip.cache``)."""
    cache = getattr(lip, "cache", None)
    if cache is not None and "samples" in cache:
        return cache["samples"]
    P = lip.size
    samples = lip.curve(np.repeat(np.arange(P), _SAMPLES.size), np.tile(_SAMPLES, P)).x
    samples = samples.reshape(P, _SAMPLES.size, 2)
    if cache is not None:
        cache["samples"] = samples
    return samples


def closest_points(
    lip,
    x: npt.NDArray[np.float64],
    radius: float,
    candidates: int = 4,
    only=None,
    given=None,
) -> Pairing:
    """Pair slave points with the deformed master lip (for its last ``refresh``).

    Args:
        lip: The :class:`~xfem_contact.mechanics.sliding.lips.MasterLip`.
        x: Deformed slave points (m), ``(m, 2)``.
        radius: Search radius (m): no master within it leaves a point unpaired.
        candidates: Pieces tried per point (nearest boxes first).
        only: A piece per point (``(m,)``, -1: unpaired) to project on instead of
            searching (the pairing frozen over a load step; no radius).
        given: Pieces per point (``(m, k)``, -1: none) to try instead of searching.

    Returns:
        The :class:`Pairing`. Local.
    """
    m = x.shape[0]
    if m == 0 or lip.size == 0:
        return Pairing(np.full(m, -1), np.zeros(m), np.full(m, np.inf))
    P = lip.size
    samples = lip_samples(lip)
    if only is not None:
        given = np.asarray(only)[:, None]
    if given is None:
        order, tried, nearest = _candidates(x, samples, radius, min(candidates, P))
    else:
        order, tried = np.where(given >= 0, given, 0), given >= 0
        nearest = np.full(m, np.inf)
    k = order.shape[1]
    rows = np.repeat(np.arange(m), k)
    pieces = order.ravel()
    start = _SAMPLES[np.argmin(np.sum((x[rows, None, :] - samples[pieces]) ** 2, axis=2), axis=1)]
    s = _newton(lip, x[rows], pieces, start)
    on_piece = (s >= -_ON_PIECE) & (s <= 1.0 + _ON_PIECE)
    s = np.where(on_piece, s, np.clip(s, 0.0, 1.0))  # off the piece: its nearest end
    distance = np.linalg.norm(x[rows] - lip.curve(pieces, s).x, axis=1).reshape(m, k)
    # rank: feet on their piece first, then by distance
    score = np.where(on_piece.reshape(m, k), distance, np.inf)
    score = np.where(tried, score, np.inf)
    fallback = np.where(tried, distance, np.inf)
    best = np.where(
        np.isfinite(score).any(axis=1), np.argmin(score, axis=1), np.argmin(fallback, axis=1)
    )
    pick = np.arange(m) * k + best
    piece = np.where(tried[np.arange(m), best], pieces[pick], -1)
    dist = distance.ravel()[pick]
    if only is None:
        piece = np.where(dist <= radius, piece, -1)
    dist = np.where(piece >= 0, dist, np.where(np.isfinite(nearest), nearest, dist))
    return Pairing(piece.astype(np.int64), np.where(piece >= 0, s[pick], 0.0), dist)
