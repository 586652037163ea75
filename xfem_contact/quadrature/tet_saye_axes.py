"""The axes of Saye's rules on truncated boxes of the reference tetrahedron
(:mod:`xfem_contact.quadrature.tet_saye`): the pair ``(k3, k2)`` of a box that reaches the
slanted face ``x + y + z = 1``, and the boxes whose roots depend on slopes too small
against the level set's curvature (pure numpy).

A box inside the half-space ``x + y + z <= 1`` takes Saye's pair
(:func:`~xfem_contact.quadrature.saye_axes.choose_axes`). A box that reaches the slanted
face needs the same certificates on the faces the truncated box has (bottom, top where it
meets the half-space) and ``psi`` monotone along the slanted face in the direction
``e_k2 - e_k3``, whose margin enters the score; near-ties are broken as Saye's.
"""

from __future__ import annotations

import numpy as np

from xfem_contact.geometry.tensor_levelset import derivative
from xfem_contact.quadrature.saye_axes import (
    PAIRS,
    SCORE_TOLERANCE,
    choose_axes,
    first_best,
    mean_slopes,
)

__all__ = ["CURVED", "CURVED_DEPTH", "curved_boxes", "truncated_axes"]


def truncated_axes(C, lo, hi, B, DB):
    """Index into ``PAIRS`` of the best valid ``(k3, k2)`` per box (-1: none) and the best
    monotone height axis alone (-1: none), and the pair's score (``-inf``: none). The pair
    is Saye's for a box inside the half-space, else the same criteria on the faces the truncated box
    has (bottom ``x_k3 = lo``, top ``x_k3 = hi`` where it meets the half-space, the
    slanted face along ``e_k2 - e_k3``) with the slanted face's margin in the score, and
    near-ties broken as Saye's (:func:`~xfem_contact.quadrature.saye_axes.first_best`). ``B``,
    ``DB``: Bernstein coefficients of ``psi`` and of its three derivatives on the boxes."""
    pair, height, chosen = choose_axes(C, lo, hi, B)
    reaching = np.flatnonzero(hi.sum(axis=1) > 1.0)
    if reaching.size == 0:
        return pair, height, chosen
    lo, hi, B = lo[reaching], hi[reaching], B[reaching]
    DB = [d[reaching] for d in DB]
    m = reaching.size
    scores = np.full((len(PAIRS), m), -np.inf)  # -inf: not valid
    for index, (k3, k2) in enumerate(PAIRS):
        k1 = 3 - k3 - k2
        valid, pair_score = _certain(DB[k3]), _margin(DB[k3], DB)
        top_inside = lo[:, k1] + lo[:, k2] + hi[:, k3] < 1.0
        for end, present in ((0, np.ones(m, bool)), (B.shape[1] - 1, top_inside)):
            face = np.take(B, end, axis=k3 + 1)
            slope = [np.take(DB[k], end, axis=k3 + 1) for k in (k2, k1)]
            definite = _certain(face) | (face.reshape(m, -1) == 0).all(axis=1)
            valid &= ~present | definite | _certain(slope[0])
            face_score = np.where(definite | ~present, np.inf, _margin(slope[0], slope))
            pair_score = np.minimum(pair_score, face_score)
        along, across = DB[k2] - DB[k3], DB[k1] - DB[k3]  # Bernstein forms are linear
        valid &= _certain(along)
        pair_score = np.minimum(pair_score, _margin(along, [along, across]))
        # a score within SCORE_TOLERANCE of 0 is a certificate by round-off only: not valid
        scores[index] = np.where(valid & (pair_score > SCORE_TOLERANCE), pair_score, -np.inf)
    mean = mean_slopes(DB)
    best = first_best(scores, np.array([mean[k3] for k3, _ in PAIRS]))
    pair, chosen = pair.copy(), chosen.copy()
    pair[reaching] = best
    chosen[reaching] = np.where(best >= 0, scores[np.maximum(best, 0), np.arange(m)], -np.inf)
    return pair, height, chosen


CURVED = 4.0
"""Largest ``|d2 psi| size / min |d psi / d x_k3|`` of a box with axes: a box above it is
subdivided (the roots of its height lines have branch points too close for the rule)."""


CURVED_DEPTH = 3
"""Box levels subdivided by :data:`CURVED` (boxes of ``1 / 8`` of the cube at most: a
slope that vanishes on the interface itself, such as a face function's where the
interface touches the face, is not resolved by subdivision)."""


def curved_boxes(C, lo, hi, B, DB, pair):
    """Boxes with axes where a slope the roots depend on (of ``psi`` along ``k3``; along
    ``k2`` on each face with zeros and along the slanted face) is small against ``psi``'s
    second derivatives times the box size (see :data:`CURVED`), ``(m,)`` bool; ``B``,
    ``DB`` as in :func:`truncated_axes`."""
    m = C.shape[0]
    second = np.zeros(m)
    for a in range(3):
        for b in range(a, 3):
            second = np.maximum(second, np.abs(derivative(derivative(C, a), b)[:, 0, 0, 0]))
    slope = np.full(m, np.inf)
    for index, (k3, k2) in enumerate(PAIRS):
        group = np.flatnonzero(pair == index)
        if group.size == 0:
            continue
        least = np.abs(DB[k3][group]).reshape(group.size, -1).min(axis=1)
        for end in (0, B.shape[1] - 1):
            face = np.take(B[group], end, axis=k3 + 1).reshape(group.size, -1)
            crossed = ~((face > 0).all(axis=1) | (face < 0).all(axis=1))
            face_slope = np.abs(np.take(DB[k2][group], end, axis=k3 + 1))
            face_slope = face_slope.reshape(group.size, -1).min(axis=1)
            least = np.where(crossed, np.minimum(least, face_slope), least)
        along = np.abs(DB[k2][group] - DB[k3][group]).reshape(group.size, -1).min(axis=1)
        reaching = hi[group].sum(axis=1) > 1.0
        slope[group] = np.where(reaching, np.minimum(least, along), least)
    size = (hi - lo).max(axis=1)
    return (pair >= 0) & (second * size > CURVED * slope)


def _certain(B):
    """Bernstein coefficients ``(m, ...)`` of one strict sign."""
    flat = B.reshape(B.shape[0], -1)
    return (flat > 0).all(axis=1) | (flat < 0).all(axis=1)


def _margin(slope, slopes):
    """Least ``|slope|`` relative to the largest of ``slopes`` (Bernstein bounds), ``(m,)``."""
    m = slope.shape[0]
    steepest = np.maximum.reduce([np.abs(s).reshape(m, -1).max(axis=1) for s in slopes])
    return np.abs(slope).reshape(m, -1).min(axis=1) / np.where(steepest > 0, steepest, 1.0)
