"""Quasi-static crack growth: the maximum hoop stress kink angle, a polyline crack's level
sets, and the step that advances its tips and re-cuts the problem.

A :class:`GrowthPath` is a polyline (m) whose first and last points are its tips (or ends
outside the body, for an edge crack: they do not move, see ``moving``). Its normal level
set ``phi`` is the signed distance to the polyline with its end segments continued as
rays (positive on the left of the path's direction), its tangential level set ``psi``
the largest, over the tips, of the distance ahead of the tip along its last segment
(negative along the whole crack for kinks below 90 degrees). :func:`grow` evaluates
K_I, K_II at every moving tip, turns each by :func:`kink_angle`, advances it by ``da``
(the crack's past stays where it was) and re-cuts the problem through
``problem.update_interface``. SI units.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from mpi4py import MPI

from xfem_contact.mechanics.fracture.rings import cells_at
from xfem_contact.mechanics.fracture.tips import TipIntegrals

__all__ = ["GrowthPath", "GrowthStep", "grow", "kink_angle", "paris_increment"]


def kink_angle(K_I: float, K_II: float) -> float:
    """The maximum hoop stress kink angle (rad, from the crack's direction, positive
    counter-clockwise): ``2 arctan[(K_I - sqrt(K_I^2 + 8 K_II^2)) / (4 K_II)]``, 0 in pure
    mode I; its sign is opposite to ``K_II``'s."""
    if K_II == 0.0:
        return 0.0
    return 2.0 * math.atan((K_I - math.sqrt(K_I**2 + 8.0 * K_II**2)) / (4.0 * K_II))


def paris_increment(delta_K: float, C: float, m: float, cycles: float) -> float:
    """Paris' law: the advance (m) in ``cycles`` load cycles of stress intensity range
    ``delta_K`` (Pa m^1/2): ``da = C delta_K^m cycles`` (``C`` in m per cycle per
    (Pa m^1/2)^m)."""
    for name, value in (("delta_K", delta_K), ("C", C), ("m", m), ("cycles", cycles)):
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    return C * delta_K**m * cycles


@dataclasses.dataclass
class GrowthPath:
    """The polyline of a growing crack: :func:`grow` appends a point at each moving tip
    (a fixed crack shape of a scene is a
    :class:`~xfem_contact.geometry.crack_paths.CrackPath`).

    Attributes:
        points: The vertices (m), ``(k, 2)``, ``k >= 2``, from one end to the other.
        moving: Which ends are tips that grow: ``(first, last)``.
    """

    points: np.ndarray
    moving: tuple[bool, bool] = (True, True)

    def __post_init__(self):
        self.points = np.asarray(self.points, dtype=np.float64)
        if self.points.ndim != 2 or self.points.shape[1] != 2 or len(self.points) < 2:
            raise ValueError(f"points must be at least two (x, y) pairs, got {self.points.shape}")
        lengths = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        if not np.all(np.isfinite(self.points)) or np.any(lengths == 0.0):
            raise ValueError("points must be finite and consecutive points distinct")

    def ends(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """``(position, unit direction ahead)`` of the first and last points."""
        p = self.points
        first, last = p[0] - p[1], p[-1] - p[-2]
        return [(p[0], first / np.linalg.norm(first)), (p[-1], last / np.linalg.norm(last))]

    def phi(self, x: np.ndarray) -> np.ndarray:
        """Signed distance (m) to the polyline, end segments continued as rays; positive
        on the left of the direction from the first point to the last. ``x``: (3, n)."""
        X = np.asarray(x[:2]).T  # (n, 2)
        best = np.full(X.shape[0], np.inf)
        value = np.zeros(X.shape[0])
        p, last = self.points, len(self.points) - 2
        for k in range(last + 1):
            a, b = p[k], p[k + 1]
            t = b - a
            s = ((X - a) @ t) / (t @ t)
            lo = -np.inf if k == 0 else 0.0
            hi = np.inf if k == last else 1.0
            foot = a + np.clip(s, lo, hi)[:, None] * t
            d = np.linalg.norm(X - foot, axis=1)
            side = np.sign(t[0] * (X[:, 1] - a[1]) - t[1] * (X[:, 0] - a[0]))
            closer = d < best
            best = np.where(closer, d, best)
            value = np.where(closer, side * d, value)
        return value

    def psi(self, x: np.ndarray) -> np.ndarray:
        """The largest distance (m) ahead of a tip along its last segment: negative along
        the crack. Ends that do not move count as tips too (an end outside the body
        never cuts it). ``x``: (3, n)."""
        X = np.asarray(x[:2]).T
        return np.max([(X - tip) @ d for tip, d in self.ends()], axis=0)

    def advance(self, angles: Sequence[float], da: float) -> None:
        """Move every moving tip by ``da`` (m) in its direction turned by its angle (rad)."""
        for end, ((tip, d), angle, moving) in enumerate(
            zip(self.ends(), angles, self.moving, strict=True)
        ):
            if not moving:
                continue
            c, s = math.cos(angle), math.sin(angle)
            new = tip + da * np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
            self.points = (
                np.vstack([new, self.points]) if end == 0 else np.vstack([self.points, new])
            )


@dataclasses.dataclass(frozen=True)
class GrowthStep:
    """One growth step: per end, its tip (m), K_I, K_II (Pa m^1/2, first ring) and kink
    angle (rad) before the advance (None for an end that does not move)."""

    tips: list[np.ndarray | None]
    K: list[tuple[float, float] | None]
    angles: list[float | None]


def grow(problem, path: GrowthPath, da: float, rings, solve: bool = True) -> GrowthStep:
    """One quasi-static step: K at the tips of the solved ``problem``, the kink angles,
    the tips advanced by ``da`` (m), the problem re-cut on the new path (and solved again
    when ``solve``). The problem's crack must be ``path`` (its tips in the cut's order
    are matched to the path's ends by position). Collective.

    Raises:
        ValueError: ``da`` not positive, or an advance that leaves the mesh (the cut
            refuses a tip outside the body).
        NotImplementedError: a cut with several cracks.
    """
    if not (da > 0 and math.isfinite(da)):
        raise ValueError(f"da must be a positive length (m), got {da!r}")
    names = problem.cut.interface_names
    if len(names) > 1:
        raise NotImplementedError(
            f"problem: grow() moves one crack; this cut has the cracks {list(names)} "
            "(growing several is not available yet)"
        )
    results = TipIntegrals(problem, rings).evaluate()
    tips = problem.cut.crack.tips
    per_end: list = [None, None]
    for (position, _), end in zip(path.ends(), range(2), strict=True):
        if not path.moving[end]:
            continue
        k = int(np.argmin(np.linalg.norm(tips - position, axis=1)))
        ring = results[k][0]
        per_end[end] = (position.copy(), (ring.K_I, ring.K_II))
    angles = [None if e is None else kink_angle(*e[1]) for e in per_end]
    before = path.points.copy()
    path.advance([0.0 if a is None else a for a in angles], da)
    mesh = problem.mesh
    for end in (0, -1):
        tip = path.points[end]
        if path.moving[end] and mesh.comm.allreduce(len(cells_at(mesh, tip)), op=MPI.SUM) == 0:
            path.points = before
            raise ValueError(
                f"da = {da:.6g} m takes the tip at {tuple(np.round(before[end], 6))} out of the "
                "body: take a smaller da (or stop the growth there)"
            )
    problem.update_interface(path.phi, tangent=path.psi)
    if solve:
        problem.solve()
    return GrowthStep(
        [None if e is None else e[0] for e in per_end],
        [None if e is None else e[1] for e in per_end],
        angles,
    )
