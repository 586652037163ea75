"""Crack paths (a polyline or a circular arc) and their two level sets as signed distances.

A :class:`CrackPath` is a curve from its start ``ends[0]`` to its end ``ends[1]``, with
arc length ``s`` (m) from the start. Its level sets (:meth:`CrackPath.levelsets`) are

- ``phi``: the signed distance to the curve *extended* beyond both ends (polyline: along
  its first and last segments; arc: along its circle), negative on the right of the
  direction of travel (side -1), positive on the left (side +1);
- ``psi``: the signed distance *along* the extended curve beyond the nearer end,
  ``max(-s - e_0, s - L - e_1)`` with ``s`` the arc length of the nearest point of the
  extended curve and ``L`` the path's length: negative on the crack, zero at its tips.
  ``e_k = 0`` makes end ``k`` a tip; ``e_k > 0`` carries the crack ``e_k`` beyond it
  (an end on or beyond the body's boundary: an edge crack leaves the body there).

Both are exact signed distances near a straight crack and near the tips; ``phi`` is the
distance to the extended curve everywhere (pseudo-normal sign at the polyline's
corners). Pure numpy; points as DOLFINx passes them, ``x`` of shape ``(gdim or 3, n)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import numpy.typing as npt

__all__ = ["CrackPath", "polyline", "arc"]


def _turn(v: np.ndarray) -> np.ndarray:
    """``v`` turned by +90 degrees, ``(..., 2)``."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


class CrackPath:
    """A crack's curve: a polyline (:func:`polyline`) or a circular arc (:func:`arc`).

    Attributes:
        ends: The start and end points, ``(2, 2)`` (m).
        tangents: Unit tangents at the ends in the direction *out of* the curve
            (backwards at the start, forwards at the end), ``(2, 2)``.
        length: Arc length ``L`` (m).
    """

    ends: np.ndarray
    tangents: np.ndarray
    length: float

    def project(self, x: np.ndarray, extend: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
        """``(phi, s)`` of points ``x`` (``(2, n)``): signed distance to the curve
        extended by ``extend = (e_0, e_1)`` (m, may be inf) and arc length of the foot."""
        raise NotImplementedError

    def levelsets(
        self, extend: Sequence[float] = (0.0, 0.0)
    ) -> tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]:
        """``(phi, psi)``, callables of ``x`` ``(gdim or 3, n)`` returning ``(n,)``;
        ``extend = (e_0, e_1)`` (m): how far the crack runs on beyond each end
        (0: a tip there)."""
        e0, e1 = (float(e) for e in extend)

        def phi(x):
            return self.project(np.asarray(x)[:2], (math.inf, math.inf))[0]

        def psi(x):
            s = self.project(np.asarray(x)[:2], (math.inf, math.inf))[1]
            return np.maximum(-s - e0, s - self.length - e1)

        return phi, psi

    def arclength(self, x: npt.ArrayLike) -> np.ndarray:
        """Arc length ``s`` (m) from the start of the nearest point of the curve to each
        of the points ``x`` ``(2, n)`` (clipped to ``[0, L]``)."""
        s = self.project(np.asarray(x, dtype=np.float64)[:2], (0.0, 0.0))[1]
        return np.clip(s, 0.0, self.length)


class _Polyline(CrackPath):
    def __init__(self, points: np.ndarray):
        self.points = points
        d = np.diff(points, axis=0)
        self.lengths = np.linalg.norm(d, axis=1)
        self.t = d / self.lengths[:, None]
        self.start = np.concatenate([[0.0], np.cumsum(self.lengths)[:-1]])
        self.length = float(self.lengths.sum())
        self.ends = points[[0, -1]].copy()
        self.tangents = np.array([-self.t[0], self.t[-1]])

    def project(self, x, extend):
        x = np.asarray(x, dtype=np.float64).T  # (n, 2)
        m = self.lengths.size
        best = np.full(x.shape[0], np.inf)
        phi, s = np.zeros(x.shape[0]), np.zeros(x.shape[0])
        for k in range(m):
            a, t = self.points[k], self.t[k]
            along = (x - a) @ t
            low = -extend[0] if k == 0 else 0.0
            high = self.lengths[k] + (extend[1] if k == m - 1 else 0.0)
            foot = np.clip(along, low, high)
            delta = x - (a + foot[:, None] * t)
            dist = np.linalg.norm(delta, axis=1)
            # the side: the segment's normal, or at a corner the pseudo-normal (the
            # mean of the two segments' normals), the sign of the nearest side
            normal = np.broadcast_to(_turn(t), x.shape).copy()
            if k > 0:
                normal[foot <= 0.0] = _turn(self.t[k - 1] + t)
            if k < m - 1:
                normal[foot >= self.lengths[k]] = _turn(t + self.t[k + 1])
            sign = np.where(np.sum(delta * normal, axis=1) < 0.0, -1.0, 1.0)
            closer = dist < best
            best = np.where(closer, dist, best)
            phi = np.where(closer, sign * dist, phi)
            s = np.where(closer, self.start[k] + foot, s)
        return phi, s


class _Arc(CrackPath):
    def __init__(self, centre: np.ndarray, radius: float, a0: float, a1: float):
        self.centre, self.radius, self.a0, self.a1 = centre, radius, a0, a1
        self.sense = 1.0 if a1 > a0 else -1.0
        self.length = radius * abs(a1 - a0)
        self.ends = centre + radius * np.array([[math.cos(a), math.sin(a)] for a in (a0, a1)])
        radial = (self.ends - centre) / radius
        forward = self.sense * _turn(radial)  # the direction of travel at each end
        self.tangents = np.array([-forward[0], forward[1]])

    def project(self, x, extend):
        x = np.asarray(x, dtype=np.float64)
        dx, dy = x[0] - self.centre[0], x[1] - self.centre[1]
        rho = np.hypot(dx, dy)
        # the angle, unwrapped about the arc's middle (the crack then lies within +-pi)
        middle = 0.5 * (self.a0 + self.a1)
        angle = middle + np.angle(np.exp(1j * (np.arctan2(dy, dx) - middle)))
        s = self.sense * (angle - self.a0) * self.radius
        low, high = -min(extend[0], math.inf), self.length + min(extend[1], math.inf)
        s = np.clip(s, low, high)
        # phi: positive on the left of the travel (towards the centre for a counter-
        # clockwise arc)
        return self.sense * (self.radius - rho), s


def polyline(points: npt.ArrayLike) -> CrackPath:
    """The polyline through ``points`` ``(m >= 2, 2)`` (m): a segment for two points.

    Raises:
        ValueError: fewer than two points, or two consecutive points equal.
    """
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 2 or points.shape[0] < 2:
        raise ValueError(f"a crack path needs at least two points [x, y], got {points.tolist()}")
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    if not np.all(lengths > 1e-12 * max(1.0, float(np.abs(points).max()))):
        k = int(np.argmin(lengths))
        raise ValueError(f"points {k} and {k + 1} coincide: each segment needs a length")
    return _Polyline(points)


def arc(centre: npt.ArrayLike, radius: float, angles: Sequence[float]) -> CrackPath:
    """The arc of the circle ``(centre, radius)`` (m) from polar angle ``angles[0]`` to
    ``angles[1]`` (rad; counter-clockwise when the second is larger), less than a turn.

    Raises:
        ValueError: a radius <= 0, equal angles or a sweep of a full turn or more.
    """
    a0, a1 = (float(a) for a in angles)
    if not radius > 0.0:
        raise ValueError(f"the radius must be > 0, got {radius}")
    if not 0.0 < abs(a1 - a0) < 2.0 * math.pi:
        raise ValueError(f"the sweep must be in (0, 360) degrees, got {math.degrees(a1 - a0):g}")
    return _Arc(np.asarray(centre, dtype=np.float64), float(radius), a0, a1)
