"""Q1/Q2 level sets on hexahedra as tensor-product polynomials: monomial coefficients,
Bernstein coefficients on boxes (sign certificates), values, gradients and restrictions
to coordinate lines with their real roots (pure numpy and Basix).

A cell's level set is the Lagrange interpolant of degree ``p`` (1 or 2) of its nodal
values (Basix ``gll_warped`` node order on the reference hexahedron ``[0, 1]^3``),
written ``sum_{i,j,k <= p} C[i, j, k] X^i Y^j Z^k`` in reference coordinates. On a
box ``[lo, hi]`` its tensor Bernstein coefficients bound it: all ``> 0`` proves it
positive there, all ``< 0`` negative. Its restriction to a line parallel to an axis
is a polynomial of degree ``<= p`` in that coordinate, whose roots are closed-form.
"""

from __future__ import annotations

import functools
import math

import basix
import numpy as np
import numpy.typing as npt

from xfem_contact.geometry.cut_topology import nodal_values

__all__ = [
    "bernstein",
    "coefficients",
    "derivative",
    "evaluate",
    "gradient",
    "line_coefficients",
    "line_roots",
]


@functools.cache
def _from_nodal(degree: int) -> np.ndarray:
    """Matrix ``(ndofs, (p+1)^3)`` taking nodal values to monomial coefficients."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, degree, basix.LagrangeVariant.gll_warped
    )
    x = element.points
    powers = np.arange(degree + 1)
    V = np.einsum(
        "ni,nj,nk->nijk", x[:, :1] ** powers, x[:, 1:2] ** powers, x[:, 2:] ** powers
    ).reshape(x.shape[0], -1)
    return np.linalg.inv(V)


def coefficients(phi: npt.ArrayLike, degree: int) -> npt.NDArray[np.float64]:
    """Monomial coefficients of Q``degree`` level sets.

    Args:
        phi: Nodal values, shape ``(ncells, (degree + 1)^3)`` (Basix order).
        degree: 1 or 2.

    Returns:
        ``C`` of shape ``(ncells, p + 1, p + 1, p + 1)``, ``C[:, i, j, k]`` of ``X^i Y^j Z^k``.

    Raises:
        ValueError: Bad degree, shape or non-finite values (naming the first cell).
    """
    if degree not in (1, 2):
        raise ValueError(f"degree must be 1 or 2 for a hexahedron level set, got {degree!r}")
    n = (degree + 1) ** 3
    phi = nodal_values(phi, n, f"Q{degree} hexahedron", "hexahedron")
    # einsum, not BLAS: a cell's coefficients must not depend on the batch it is in
    C = np.einsum("nk,jk->nj", phi, _from_nodal(degree))
    return C.reshape(-1, degree + 1, degree + 1, degree + 1)


def _powers(x: np.ndarray, p: int) -> np.ndarray:
    """``x^0 .. x^p`` along a new last axis (``p <= 2``; products, as exact as ``**``)."""
    powers = np.empty((*x.shape, p + 1))
    powers[..., 0] = 1.0
    if p >= 1:
        powers[..., 1] = x
    if p >= 2:
        np.multiply(x, x, out=powers[..., 2])
    return powers


def evaluate(C: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Values at points ``X`` ``(m, 3)`` of polynomials ``C`` ``(m, p+1, p+1, p+1)`` (one
    polynomial per point), shape ``(m,)``."""
    p = C.shape[1] - 1
    along_z = np.einsum("mijk,mk->mij", C, _powers(X[:, 2], p))
    along_y = np.einsum("mij,mj->mi", along_z, _powers(X[:, 1], p))
    return np.einsum("mi,mi->m", along_y, _powers(X[:, 0], p))


def derivative(C: np.ndarray, axis: int) -> np.ndarray:
    """Coefficients of ``d/dX_axis`` (same shape, the top power zero)."""
    p = C.shape[1] - 1
    D = np.zeros_like(C)
    index = [slice(None)] * 4
    for i in range(1, p + 1):
        index[axis + 1] = i - 1
        src = [slice(None)] * 4
        src[axis + 1] = i
        D[tuple(index)] = i * C[tuple(src)]
    return D


def gradient(C: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Reference gradients at ``X`` ``(m, 3)`` (one polynomial per point), shape ``(m, 3)``."""
    return np.stack([evaluate(derivative(C, d), X) for d in range(3)], axis=1)


@functools.cache
def _to_bernstein(p: int) -> np.ndarray:
    """Inverse of ``M[a, i] = b_i(a / p)`` (Bernstein basis of degree ``p`` on ``[0, 1]``)."""
    t = np.arange(p + 1) / p
    M = np.array([[math.comb(p, i) * s**i * (1 - s) ** (p - i) for i in range(p + 1)] for s in t])
    return np.linalg.inv(M)


def bernstein(C: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Tensor Bernstein coefficients on boxes ``[lo, hi]`` (each ``(m, 3)``) of polynomials
    ``C`` ``(m, p+1, p+1, p+1)``, shape ``(m, p+1, p+1, p+1)``; the polynomial lies between
    their minimum and maximum on the box."""
    p = C.shape[1] - 1
    t = np.arange(p + 1) / p
    grid = lo[:, None, :] + (hi - lo)[:, None, :] * t[None, :, None]  # (m, p+1, 3)
    T = _to_bernstein(p)
    # per axis: monomial coefficients -> values at the grid -> Bernstein coefficients
    A = [np.einsum("ia,mak->mik", T, _powers(grid[:, :, d], p)) for d in range(3)]
    values = np.einsum("mijk,mck->mijc", C, A[2])
    values = np.einsum("mijc,mbj->mibc", values, A[1])
    return np.einsum("mibc,mai->mabc", values, A[0])


def line_coefficients(C: np.ndarray, axis: int, X: np.ndarray) -> np.ndarray:
    """Coefficients in ``t`` of the restrictions to the lines ``X + t e_axis`` (the
    ``axis`` coordinate of ``X`` is ignored), shape ``(m, p + 1)``, lowest power first."""
    p = C.shape[1] - 1
    others = [d for d in range(3) if d != axis]
    Cp = np.moveaxis(C, axis + 1, 3)  # (m, i, j, t) with i, j the other axes in order
    along = np.einsum("mijt,mj->mit", Cp, _powers(X[:, others[1]], p))
    return np.einsum("mit,mi->mt", along, _powers(X[:, others[0]], p))


def line_roots(c: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Real roots in ``[lo, hi]`` of polynomials of degree <= 2 (coefficients ``c``
    ``(m, 1..3)``, lowest first), shape ``(m, 2)``, NaN where there is none. A root within
    ``16 eps (hi - lo)`` of an end is that end; a double root counts twice, a polynomial
    that vanishes identically has none."""
    c = np.concatenate([c, np.zeros((c.shape[0], 3 - c.shape[1]))], axis=1)
    c0, b, a = c[:, 0], c[:, 1], c[:, 2]
    roots = np.full((c.shape[0], 2), np.nan)
    linear = (a == 0) & (b != 0)
    roots[linear, 0] = -c0[linear] / b[linear]
    quad = a != 0
    disc = b[quad] ** 2 - 4 * a[quad] * c0[quad]
    real = disc >= 0
    sq = np.sqrt(np.where(real, disc, 0.0))
    q = -0.5 * (b[quad] + np.where(b[quad] >= 0, sq, -sq))
    r1 = q / a[quad]
    r2 = np.divide(c0[quad], q, out=r1.copy(), where=q != 0)
    roots[quad] = np.where(real[:, None], np.stack([r1, r2], axis=1), np.nan)
    value = c0[:, None] + roots * (b[:, None] + roots * a[:, None])
    slope = b[:, None] + 2 * a[:, None] * roots
    step = np.divide(value, slope, out=np.zeros_like(value), where=slope != 0)
    small = np.isfinite(step) & (np.abs(step) <= 1e-8 * (hi - lo)[:, None])
    roots = roots - np.where(small, step, 0.0)  # one Newton step polishes simple roots
    tol = 16 * np.finfo(float).eps * (hi - lo)
    roots = np.where(np.abs(roots - lo[:, None]) <= tol[:, None], lo[:, None], roots)
    roots = np.where(np.abs(roots - hi[:, None]) <= tol[:, None], hi[:, None], roots)
    inside = (roots >= lo[:, None]) & (roots <= hi[:, None])
    return np.where(inside, roots, np.nan)
