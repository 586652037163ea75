"""The four branch functions of the crack-tip enrichment, for numpy and UFL from one definition.

``F = sqrt(r) (sin(t/2), cos(t/2), sin(t/2) sin(t), cos(t/2) sin(t))`` at the tip's polar
coordinates ``(r, t)`` (m, rad; ``t`` in ``[-pi, pi]``, the crack at ``t = +-pi``): they
span the leading term of the Williams expansion of the displacement near a crack tip
(:mod:`xfem_contact.mechanics.fracture.williams`). An :class:`Ops` (:data:`NUMPY` or
:data:`UFL`) says which pointwise functions evaluate them. Also the tip enrichment's
bases (:data:`TIP_BASES`) and the values of the shifted basis' interpolants.
"""

from __future__ import annotations

import typing

import numpy as np
import ufl
from mpi4py import MPI

__all__ = [
    "NUMPY",
    "ROUND_OFF",
    "TIP_BASES",
    "UFL",
    "Ops",
    "angular",
    "branch_values",
    "checked_tip_basis",
    "null_pins",
    "side_of",
    "side_values",
    "tied_values",
]

#: Level set values (relative to the mesh's extent) taken for 0: a node on a crack's line
ROUND_OFF = 1e-12
#: The bases of the tip enrichment (:class:`~xfem_contact.fem.enrichment.EnrichedSpace`)
TIP_BASES = ("auto", "plain", "shifted")


def _np_vector(components) -> np.ndarray:
    return np.stack(np.broadcast_arrays(*components))


def _np_matrix(rows) -> np.ndarray:
    return np.stack([_np_vector(row) for row in rows])


class Ops(typing.NamedTuple):
    """Pointwise functions and constructors, so that one definition serves UFL and numpy."""

    sqrt: typing.Callable
    sin: typing.Callable
    cos: typing.Callable
    atan2: typing.Callable
    vector: typing.Callable
    matrix: typing.Callable


NUMPY = Ops(np.sqrt, np.sin, np.cos, np.arctan2, _np_vector, _np_matrix)
UFL = Ops(ufl.sqrt, ufl.sin, ufl.cos, ufl.atan2, ufl.as_vector, ufl.as_matrix)


def angular(theta, ops: Ops) -> tuple[tuple, tuple]:
    """The angular factors of the branch functions and their ``theta`` derivatives."""
    s2, c2, s, c = ops.sin(theta / 2), ops.cos(theta / 2), ops.sin(theta), ops.cos(theta)
    return (s2, c2, s2 * s, c2 * s), (c2 / 2, -s2 / 2, c2 / 2 * s + s2 * c, c2 * c - s2 / 2 * s)


def branch_values(r, theta, ops: Ops = NUMPY) -> tuple:
    """The branch functions ``F_j`` (m^1/2, a 4-tuple) at polar coordinates ``(r, theta)``:
    ``F = sqrt(r) (sin(t/2), cos(t/2), sin(t/2) sin(t), cos(t/2) sin(t))``."""
    sr = ops.sqrt(r)
    return tuple(sr * a for a in angular(theta, ops)[0])


def side_values(phi, psi, ramp, tolerance: float) -> dict[int, np.ndarray]:
    """Per side ``s``, ``R F_k`` of that side (m^1/2, shape ``(4, n)``) at ``n`` points
    with the crack's level sets ``phi``, ``psi`` (m) and the ramp ``R`` (a number or
    ``(n,)``): ``r = sqrt(phi^2 + psi^2)``, ``theta = s |atan2(phi, psi)|``. A point with
    ``r <= tolerance`` (m) lies on a tip: its values are 0 (``F_k(0) = 0``; the square
    root would turn the level sets' round-off there, which differs between meshes of the
    same nodes, into values of order ``sqrt(tolerance)`` at a meaningless angle)."""
    r, angle = np.sqrt(phi**2 + psi**2), np.abs(np.arctan2(phi, psi))
    r = np.where(r <= tolerance, 0.0, r)
    return {s: ramp * np.array(branch_values(r, s * angle)) for s in (-1, 1)}


def side_of(phi, tolerance: float) -> np.ndarray:
    """The side (-1 or +1) of points with the level set ``phi`` (m): -1 where
    ``phi < -tolerance``, else +1 (a point on the crack's line, whose ``phi`` the
    mesh's round-off may make of either sign, takes side +1 on every process)."""
    return np.where(np.asarray(phi) < -tolerance, -1, 1)


def tied_values(
    values: dict[int, np.ndarray], tied: np.ndarray, phi, tolerance: float
) -> dict[int, np.ndarray]:
    """``values`` of :func:`side_values` with, at the points where ``tied`` (the two
    sides share one unknown), both sides' taking those of the side the point lies on
    (:func:`side_of`)."""
    own = np.where(side_of(phi, tolerance) < 0, values[-1], values[1])
    return {s: np.where(tied, own, v) for s, v in values.items()}


def checked_tip_basis(tip_basis: str, degree: int, aggregated: bool = False) -> str:
    """``tip_basis`` (one of :data:`TIP_BASES`) for displacement ``degree``, resolved:
    ``"auto"`` is ``"shifted"`` for degree 2 without cell aggregation (``aggregated``),
    else ``"plain"``. ``"shifted"`` asked for needs degree 2 and no cell aggregation: its
    vertex interpolant times a hat must be a function of the standard space (no dof
    extended from another cell)."""
    if tip_basis not in TIP_BASES:
        raise ValueError(f"tip_basis must be one of {TIP_BASES}, got {tip_basis!r}")
    if tip_basis == "auto":
        return "shifted" if degree == 2 and not aggregated else "plain"
    if tip_basis == "shifted" and (degree != 2 or aggregated):
        raise ValueError(
            f"tip_basis='shifted' needs displacement degree 2 and no cell aggregation (its "
            f"vertex interpolant times a hat is then a standard function), got degree "
            f"{degree}, aggregation {'on' if aggregated else 'off'}: use 'plain' or 'auto'"
        )
    return tip_basis


def null_pins(x, tips, directions, offset: float, comm: MPI.Comm) -> np.ndarray:
    """Per node ``x`` (m, ``(n, 2)``) of the branch dofs: True at the one node per tip whose
    ``F_1`` and ``F_2`` dofs are to be dropped. With a complete P1 partition of unity
    around a tip (the ramp), ``sum_k F_k p_k = 0`` for the linear ``p = (-g x2, a x2,
    -a x2 - g x1, -a x1 + g x2)`` (tip frame, any ``a``, ``g``): two null vectors per
    displacement component. Dropping ``F_1`` and ``F_2`` at a node off the crack line
    (``x2 != 0``) removes them and no function of the space. The node: the nearest to
    the point ``offset`` (m, half a tip cell) off the tip along the crack's normal, the
    first by position of equally near ones (the same on every process, whatever the
    round-off of the nodes' coordinates); nearer the tip keeps the conditioning's
    growth with 1/h lower. Collective."""
    pins = np.zeros(len(x), dtype=bool)
    tolerance = 1e-6 * offset  # nodes nearer than this apart from the nearest tie with it
    for tip, d in zip(np.asarray(tips), np.asarray(directions), strict=True):
        distance = np.linalg.norm(x - (tip + offset * np.array([-d[1], d[0]])), axis=1)
        nearest = comm.allreduce(float(distance.min()) if len(x) else np.inf, op=MPI.MIN)
        near = np.flatnonzero(distance <= nearest + tolerance)
        # of equally near nodes, the first by rounded position (the same on every process)
        keys = np.concatenate(comm.allgather(np.round(x[near] / tolerance)))
        first = keys[np.lexsort(keys.T[::-1])[0]]
        pins[near[np.all(np.round(x[near] / tolerance) == first, axis=1)]] = True
    return pins
