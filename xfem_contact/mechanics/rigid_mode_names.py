"""What the rigid-mode check tells a user of a free body: the free motions by name and
the point constraints that remove them (:mod:`~xfem_contact.mechanics.rigid_modes`)."""

from __future__ import annotations

import dataclasses

import numpy as np
from mpi4py import MPI

from xfem_contact.mechanics.rigid_motions import Body


@dataclasses.dataclass
class FreeBody:
    """A body with rigid modes nothing constrains.

    Attributes:
        body: e.g. ``"side -1 (inside interface 'inclusion')"``.
        modes: e.g. ``["translation x", "rotation about (0.5, 0.5)"]``.
        reasons: Why nothing holds them (Dirichlet data, interface laws).
        remedies: ``(point, component)`` of point constraints that remove them
            (``problem.loads.add_point_displacement(point, 0.0, component)``).
        spin_only: The free modes are rotations that a frictionless interface of the
            body leaves (a spin its geometry does not lock: a circle's, a sphere's
            three), not a missing support.
    """

    body: str
    modes: list[str]
    reasons: list[str]
    remedies: list[tuple[list[float], int]]
    spin_only: bool = False

    def message(self) -> str:
        one = len(self.modes) == 1
        fixes = ", ".join(
            f"loads.add_point_displacement([{', '.join(short_number(x, 6) for x in p)}], 0.0, {c})"
            for p, c in self.remedies
        )
        return (
            f"{self.body}: {' and '.join(self.modes)} {'is' if one else 'are'} not constrained "
            f"({'; '.join(self.reasons)}); fix {'it' if one else 'them'} with {fixes}"
        )


def short_number(value: float, digits: int) -> str:
    """``value`` to ``digits`` significant digits, round-off (below 1e-9) shown as 0."""
    return f"{(0.0 if abs(value) < 1e-9 else float(value)):.{digits}g}"


def describe(problem, body: Body, S: np.ndarray, reasons: list[str]) -> FreeBody:
    """Names of the free motions ``S`` of ``body`` and point constraints removing them."""
    theta = S[2]
    turns = np.linalg.norm(theta) > 0.1
    # translations: the motions without rotation
    T = S @ null_space(theta[None, :]) if turns else S
    modes, remedies = [], []
    pivot = body.centre
    if T.shape[1] == 2:
        modes.append("translations x, y")
        q = extreme_node(problem, body, 0, body.centre, farthest=False)
        remedies += [(q, 0), (q, 1)]
        pivot = np.asarray(q)
    elif T.shape[1] == 1:
        d = T[:2, 0] / np.linalg.norm(T[:2, 0])
        c = int(np.argmax(np.abs(d)))
        modes.append(
            ("translation x", "translation y")[c]
            if abs(d[c]) > 0.999
            else f"translation along ({short_number(d[0], 3)}, {short_number(d[1], 3)})"
        )
        remedies.append((extreme_node(problem, body, c, body.centre, farthest=False), c))
    if turns:
        v = S @ theta / np.linalg.norm(theta)  # the free motion turning most
        a, th = v[:2], v[2]
        centre = body.centre
        if T.shape[1] < 2:
            centre = body.centre + body.radius / th * np.array([-a[1], a[0]])
        modes.append(f"rotation about ({short_number(centre[0], 3)}, {short_number(centre[1], 3)})")
        if T.shape[1] < 2:
            pivot = centre
        q = extreme_node(problem, body, None, pivot, farthest=True)
        arm = np.asarray(q) - pivot
        remedies.append((q, int(np.argmax(np.abs([arm[1], arm[0]])))))
    return FreeBody(body.name, modes, reasons, remedies)


def describe_3d(problem, body: Body, S: np.ndarray, reasons: list[str]) -> FreeBody:
    """Names of the free motions ``S`` (6 x r) of a 3D ``body`` and point constraints
    removing them: the free translations (those of ``S`` without rotation), then each
    free rotation by its axis through the centroid, held by the point constraints
    :func:`rotation_holds` picks."""
    theta = S[3:]
    turning = np.linalg.svd(theta, full_matrices=False)[1] > 0.1
    T = S @ null_space(theta) if turning.any() else S
    modes, remedies = [], []
    if T.shape[1] == 3:
        modes.append("translations x, y, z")
    for a in T[:3].T if T.shape[1] < 3 else ():
        d = a / np.linalg.norm(a)
        c = int(np.argmax(np.abs(d)))
        modes.append(f"translation along ({', '.join(short_number(v, 3) for v in d)})")
        remedies.append((extreme_node(problem, body, c, body.centre, farthest=False), c))
    if T.shape[1] == 3:
        q = extreme_node(problem, body, 0, body.centre, farthest=False)
        remedies += [(q, 0), (q, 1), (q, 2)]
    U = np.linalg.svd(theta, full_matrices=False)[0][:, turning]  # free rotation axes
    centre = ", ".join(short_number(v, 3) for v in body.centre)
    for axis in U.T:
        direction = ", ".join(short_number(v, 3) for v in axis)
        modes.append(f"rotation about ({direction}) through ({centre})")
    remedies += rotation_holds(problem, body, U)
    return FreeBody(body.name, modes, reasons, remedies)


def rotation_holds(problem, body: Body, U: np.ndarray) -> list[tuple[list[float], int]]:
    """``r`` point constraints ``(node, component)`` that hold the free rotations about
    the axes ``U`` (3 x r, orthonormal) through the centroid: the candidates are the
    components of the node farthest from the centroid and of the node farthest from the
    point a radius off it across that node's arm; each pick is the candidate whose row
    (the velocity of every free rotation there) has the largest part outside the rows
    picked before. Collective (the same picks on every process)."""
    c = body.centre
    first = np.asarray(extreme_node(problem, body, None, c, farthest=True))
    arm = first - c
    across = np.cross(arm, np.eye(3)[int(np.argmin(np.abs(arm)))])
    off = c + body.radius * across / np.linalg.norm(across)
    second = np.asarray(extreme_node(problem, body, None, off, farthest=False))
    candidates = [(q, k) for q in (first, second) for k in range(3)]
    rows = np.array([[np.cross(axis, q - c)[k] for axis in U.T] for q, k in candidates])
    picks, basis = [], np.zeros((0, U.shape[1]))
    for _ in range(U.shape[1]):
        rest = rows - rows @ basis.T @ basis
        best = int(np.argmax(np.linalg.norm(rest, axis=1)))
        basis = np.vstack([basis, rest[best] / np.linalg.norm(rest[best])])
        picks.append((candidates[best][0].tolist(), candidates[best][1]))
    return picks


def null_space(A: np.ndarray) -> np.ndarray:
    _, s, Vt = np.linalg.svd(A)
    rank = int(np.sum(s > 0.1))
    return Vt[rank:].T


def extreme_node(problem, body: Body, component, point, farthest: bool) -> list[float]:
    """The node of ``body`` farthest from (or nearest to) ``point``, preferring nodes no
    other side's field uses (a point constraint fixes both sides' fields). Collective."""
    c = 0 if component is None else component
    x = body.coords[c]
    comm = problem.mesh.comm
    prefer = comm.allreduce(int(body.alone[c].sum()), op=MPI.SUM) > 0
    if prefer:
        x = x[body.alone[c]]
    best = None
    if x.shape[0]:
        dist = np.linalg.norm(x - point, axis=1)
        i = int(np.argmax(dist) if farthest else np.argmin(dist))
        best = (float(dist[i]) if farthest else -float(dist[i]), *x[i].tolist())
    candidates = [b for b in comm.allgather(best) if b is not None]
    return list(max(candidates)[1:])
