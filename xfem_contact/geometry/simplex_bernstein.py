"""Bernstein basis of degree ``p`` on the reference tetrahedron: the matrix taking a
polynomial's values at the lattice ``{alpha / p}`` to its Bernstein coefficients, built in
exact rational arithmetic (pure Python and numpy).

The Bernstein polynomial of multi-index ``alpha`` (``|alpha| = p``, barycentric
coordinates ``lambda_0 = 1 - x - y - z, lambda_1 = x, lambda_2 = y, lambda_3 = z``) is
``p! / prod(alpha!) prod(lambda^alpha)``. Its values at the lattice points are rationals;
the inverse of that matrix is computed with :class:`fractions.Fraction` and rounded once,
so entries such as ``2`` and ``-1/2`` come out exact (a floating-point inverse gives
``1.9999999999999998``).
"""

from __future__ import annotations

import functools
import itertools
import math
from fractions import Fraction

import numpy as np

__all__ = ["lattice_indices", "lattice_to_bernstein"]


def lattice_indices(degree: int) -> list[tuple[int, int, int, int]]:
    """Multi-indices ``alpha`` (``|alpha| = degree``, four entries, ``alpha[1:] / degree``
    the lattice point in reference coordinates), in lexicographic order."""
    if not (isinstance(degree, int) and degree >= 1):
        raise ValueError(f"degree must be an integer >= 1, got {degree!r}")
    return [a for a in itertools.product(range(degree + 1), repeat=4) if sum(a) == degree]


@functools.cache
def lattice_to_bernstein(degree: int) -> np.ndarray:
    """Matrix ``T`` ``(n, n)``, ``n = (degree + 1)(degree + 2)(degree + 3) / 6``: values at
    the lattice points (order of :func:`lattice_indices`) -> Bernstein coefficients (same
    order). Each entry is the correctly rounded float of the exact rational inverse."""
    alphas = lattice_indices(degree)
    n = len(alphas)
    scale = [math.factorial(degree) // math.prod(math.factorial(k) for k in b) for b in alphas]
    # M[i, j] = B_j(alpha_i / p), rational
    M = [
        [
            Fraction(
                scale[j] * math.prod(a**b for a, b in zip(ai, bj, strict=True)), degree**degree
            )
            for j, bj in enumerate(alphas)
        ]
        for ai in alphas
    ]
    A = [row + [Fraction(int(i == k)) for k in range(n)] for i, row in enumerate(M)]
    for col in range(n):  # Gauss-Jordan, exact
        pivot = next(r for r in range(col, n) if A[r][col] != 0)
        A[col], A[pivot] = A[pivot], A[col]
        inv = 1 / A[col][col]
        A[col] = [v * inv for v in A[col]]
        for r in range(n):
            if r != col and A[r][col] != 0:
                f = A[r][col]
                A[r] = [v - f * w for v, w in zip(A[r], A[col], strict=True)]
    return np.array([[float(v) for v in row[n:]] for row in A], dtype=np.float64)
