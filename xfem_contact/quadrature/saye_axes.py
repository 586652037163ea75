"""The axes of Saye's rules on a box (:mod:`xfem_contact.quadrature.saye`): a height axis
``k3`` along which the level set ``psi`` is monotone and an axis ``k2`` along which each face
function ``psi(x_k3 = lo_k3)``, ``psi(x_k3 = hi_k3)`` is monotone or free of zeros, certified
by Bernstein coefficients (pure numpy).

Of the valid pairs, the one whose certified slopes are steepest wins: its score is the
lower bound of ``|d psi / d x_k3|`` relative to the bound of ``|grad psi|``, and of
``|d psi / d x_k2|`` relative to the face gradient for face functions with zeros (steep
slopes keep the roots smooth functions of the outer coordinates). Scores within
:data:`SCORE_TOLERANCE` of the best are ties, won by the steepest mean slope along ``k3``
(the mean of ``|d psi / d x_k3|``'s coefficients relative to the same bound), then by the
first pair in the fixed order of :data:`PAIRS`: a change of the coefficients by a few ulps
(a different cell numbering, another partition) does not change the choice, hence the rule.
"""

from __future__ import annotations

import numpy as np

from xfem_contact.geometry.tensor_levelset import bernstein, derivative

__all__ = ["PAIRS", "SCORE_TOLERANCE", "choose_axes", "first_best", "mean_slopes"]

PAIRS = [(k3, k2) for k3 in range(3) for k2 in range(3) if k2 != k3]
"""The candidate ``(k3, k2)`` pairs, in the order that breaks ties."""

SCORE_TOLERANCE = 1e-9
"""Scores of axis choices (slope ratios in ``[0, 1]``) closer than this to the best are
ties (see the module): round-off in the level set's coefficients (a few ulps)
does not change the choice, hence the rule."""


def _certain(B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Strict sign certificates of Bernstein coefficients ``(m, ...)``: (one sign, all zero)."""
    flat = B.reshape(B.shape[0], int(np.prod(B.shape[1:])))
    return (flat > 0).all(axis=1) | (flat < 0).all(axis=1), (flat == 0).all(axis=1)


def choose_axes(
    C: np.ndarray, lo: np.ndarray, hi: np.ndarray, B: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The axes of Saye's rules on boxes ``[lo, hi]`` (each ``(m, 3)``) of polynomials ``C``
    ``(m, p+1, p+1, p+1)`` whose Bernstein coefficients there are ``B``: the index into
    :data:`PAIRS` of the best valid ``(k3, k2)`` per box (-1: none), the best monotone
    height axis alone (-1: none) and the chosen pair's score (its least slope relative to
    the gradient's bound; ``-inf``: none), each ``(m,)`` (see the module)."""
    m = C.shape[0]
    D = [bernstein(derivative(C, k), lo, hi) for k in range(3)]
    size = [np.abs(d).reshape(m, -1) for d in D]
    steepest = np.maximum.reduce([a.max(axis=1) for a in size])
    margin = [a.min(axis=1) / np.where(steepest > 0, steepest, 1.0) for a in size]
    mean = mean_slopes(D)
    monotone = [_certain(d)[0] for d in D]
    scores = np.full((len(PAIRS), m), -np.inf)  # -inf: not valid
    for index, (k3, k2) in enumerate(PAIRS):
        k1 = 3 - k3 - k2
        valid = monotone[k3].copy()
        pair_score = margin[k3].copy()
        for end in (0, B.shape[1] - 1):
            face_sign, face_zero = _certain(np.take(B, end, axis=k3 + 1))
            face_slope = np.abs(np.take(D[k2], end, axis=k3 + 1)).reshape(m, -1)
            face_monotone, _ = _certain(np.take(D[k2], end, axis=k3 + 1))
            valid &= face_sign | face_zero | face_monotone
            face_steepest = np.maximum(
                face_slope.max(axis=1),
                np.abs(np.take(D[k1], end, axis=k3 + 1)).reshape(m, -1).max(axis=1),
            )
            face_margin = face_slope.min(axis=1) / np.where(face_steepest > 0, face_steepest, 1.0)
            pair_score = np.minimum(
                pair_score, np.where(face_sign | face_zero, np.inf, face_margin)
            )
        scores[index] = np.where(valid, pair_score, -np.inf)
    height_scores = np.where(monotone, margin, -np.inf)
    second = np.array([mean[k3] for k3, _ in PAIRS])
    pair = first_best(scores, second)
    score = np.where(pair >= 0, scores[np.maximum(pair, 0), np.arange(m)], -np.inf)
    return pair, first_best(height_scores, np.array(mean)), score


def mean_slopes(D: list[np.ndarray]) -> list[np.ndarray]:
    """The tie-breaking slopes: per axis ``k``, the mean of ``|d psi / d x_k|``'s Bernstein
    coefficients ``D[k]`` ``(m, ...)`` relative to the largest of the three, each ``(m,)``."""
    m = D[0].shape[0]
    size = [np.abs(d).reshape(m, -1) for d in D]
    steepest = np.maximum.reduce([a.max(axis=1) for a in size])
    return [a.mean(axis=1) / np.where(steepest > 0, steepest, 1.0) for a in size]


def first_best(scores: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Per column of ``scores`` ``(candidates, m)`` (``-inf``: not valid): of the candidates
    whose score is within :data:`SCORE_TOLERANCE` of the column's best, those whose
    ``second`` score (same shape) is within it of theirs, the first; -1 where none is
    valid."""
    near = (scores > -np.inf) & (scores >= scores.max(axis=0) - SCORE_TOLERANCE)
    second = np.where(near, second, -np.inf)
    near &= second >= second.max(axis=0) - SCORE_TOLERANCE
    return np.where(near.any(axis=0), near.argmax(axis=0), -1)
