"""Vectorised scalar root finding for many independent problems at once.

Each function works on arrays of problems: ``func(idx, x)`` evaluates problems
``idx`` at points ``x`` (both shape ``(m,)``). Used to place interface nodes on
the zero set of an interpolated or exact level set.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

#: Steps (in the search parameter) by which a bracket is widened away from a start point
_WIDEN = (1e-12, 1e-9, 1e-6, 1e-3, 1e-1, np.inf)


def newton_bracketed(
    func: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
    x: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    tol: np.ndarray,
    maxiter: int = 100,
) -> np.ndarray:
    """Newton from ``x``, falling back to bisection when a step leaves the bracket."""
    x, lo, hi = x.copy(), lo.copy(), hi.copy()
    idx = np.arange(x.size)
    for _ in range(maxiter):
        if idx.size == 0:
            break
        xi = x[idx]
        f, df = func(idx, xi)
        below = f < 0
        lo[idx] = np.where(below, xi, lo[idx])
        hi[idx] = np.where(below, hi[idx], xi)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = f / df
        xn = xi - step
        done = (f == 0) | (np.abs(step) <= tol[idx]) | (hi[idx] - lo[idx] <= tol[idx])
        inside = np.isfinite(xn) & (xn > lo[idx]) & (xn < hi[idx])
        xn = np.where(inside, xn, 0.5 * (lo[idx] + hi[idx]))
        final = np.clip(xi - np.where(np.isfinite(step), step, 0.0), lo[idx], hi[idx])
        x[idx] = np.where(done, final, xn)
        idx = idx[~done]
    return x


def illinois(
    func: Callable[[np.ndarray, np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    flo: np.ndarray,
    fhi: np.ndarray,
    tol: np.ndarray,
    maxiter: int = 120,
) -> np.ndarray:
    """Illinois (modified regula falsi) until the bracket is narrower than ``tol``;
    plain bisection after 40 iterations guarantees termination."""
    lo, hi, flo, fhi = lo.copy(), hi.copy(), flo.copy(), fhi.copy()
    x = 0.5 * (lo + hi)
    last = np.zeros(x.size, dtype=np.int8)
    idx = np.arange(x.size)
    for it in range(maxiter):
        if idx.size == 0:
            break
        lo_i, hi_i, flo_i, fhi_i = lo[idx], hi[idx], flo[idx], fhi[idx]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (lo_i * fhi_i - hi_i * flo_i) / (fhi_i - flo_i)
        good = np.isfinite(t) & (t > lo_i) & (t < hi_i) & (it < 40)
        t = np.where(good, t, 0.5 * (lo_i + hi_i))
        ft = func(idx, t)
        below = ft < 0
        same = np.where(below, -1, 1) == last[idx]
        lo[idx], hi[idx] = np.where(below, t, lo_i), np.where(below, hi_i, t)
        flo[idx] = np.where(below, ft, np.where(same, 0.5 * flo_i, flo_i))
        fhi[idx] = np.where(below, np.where(same, 0.5 * fhi_i, fhi_i), ft)
        last[idx] = np.where(below, -1, 1)
        x[idx] = t
        idx = idx[~((ft == 0) | (hi[idx] - lo[idx] <= tol[idx]))]
    return x


def bracketed_root(
    func: Callable[[np.ndarray, np.ndarray], np.ndarray],
    x0: np.ndarray,
    lo_lim: np.ndarray,
    hi_lim: np.ndarray,
    tol: np.ndarray,
) -> np.ndarray:
    """Root of ``func`` near ``x0`` within ``[lo_lim, hi_lim]``: bracket by steps of
    growing size away from ``x0`` (up to the limits), then Illinois. Entries with
    no sign change keep ``x0``."""
    everything = np.arange(x0.size)
    f0 = func(everything, x0)
    lo, hi, flo, fhi = x0.copy(), x0.copy(), f0.copy(), f0.copy()
    up = f0 < 0  # x0 is the lower end: search upwards
    pending = f0 != 0
    for delta in _WIDEN:
        idx = np.flatnonzero(pending)
        if idx.size == 0:
            break
        x, u = x0[idx], up[idx]
        t = np.where(u, np.minimum(x + delta, hi_lim[idx]), np.maximum(x - delta, lo_lim[idx]))
        ft = func(idx, t)
        below = ft < 0
        lo[idx], flo[idx] = np.where(below, t, lo[idx]), np.where(below, ft, flo[idx])
        hi[idx], fhi[idx] = np.where(below, hi[idx], t), np.where(below, fhi[idx], ft)
        pending[idx[below != u]] = False
    x = x0.copy()
    br = np.flatnonzero((f0 != 0) & ~pending)
    if br.size:
        x[br] = illinois(lambda i, t: func(br[i], t), lo[br], hi[br], flo[br], fhi[br], tol[br])
    return x
