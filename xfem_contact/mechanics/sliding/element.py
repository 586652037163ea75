"""The hybrid slave/master contact element: residual and consistent Jacobian per point.

Local unknowns of one pair, ``z = (a, l, b)``: the slave cell's displacement dofs ``a``
(``2 nn``, node by node), its multiplier dofs ``l`` (``nl``) and the master cell's
displacement dofs ``b`` (``2 nn``). With ``x_s = X_s + phi_s a`` (the slave point),
the master curve ``x_m(s) = F(X(s)) + phi_m(s) b``, its tangent ``t = x_m'`` and unit
normal ``n = o (-t_y, t_x) / |t|`` out of the master (``o`` the piece orientation), the
foot ``s`` solves ``(x_s - x_m) . t = 0`` and the gap is ``g = (x_s - x_m) . n``.

Kept linearisation terms: all of them. ``grad g = (S - B)^T n`` (the variations of the
foot and of the normal drop out of it at a closest point), and its Hessian adds the
variation of the foot ``ds = -F_z / F_s`` and of the normal through the master's
tangent derivative ``c = B'^T n`` and curvature ``kappa = n . x_m''``::

    H = -(ds c^T + c ds^T) (1 - g kappa / |t|^2) + (F_s kappa / |t|^2) ds ds^T
        + (g / |t|^2) c c^T,    F_s = -|t|^2 + g kappa,  F_z = (S - B)^T t + g c.

The frictionless augmented-Lagrangian law of
:class:`~xfem_contact.mechanics.laws.contact.ContactLaw` then gives, with
``lambda_n = L l``, ``P = min(0, lambda_n + r g)`` and the slave point's weight ``w``
(reference arc length, m)::

    R = w (P grad g - (lambda_n - P) L / r)
    K = w (grad g L^T + L grad g^T + r grad g grad g^T + P H)   (contact, P < 0)
    K = -w L L^T / r                                             (no contact)

Vectorised over the points (numpy). SI units: m, Pa.
"""

from __future__ import annotations

import typing

import numpy as np
import numpy.typing as npt


class PairTerms(typing.NamedTuple):
    """Per-point residual ``(m, nz)`` and Jacobian ``(m, nz, nz)`` (N/m and N/m^2 per
    unit thickness), and the state: gap (m), ``lambda_n`` and ``P_n`` (Pa)."""

    residual: npt.NDArray[np.float64]
    jacobian: npt.NDArray[np.float64]
    gap: npt.NDArray[np.float64]
    lambda_n: npt.NDArray[np.float64]
    P_n: npt.NDArray[np.float64]


def node_slots(basis: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``basis (x) v`` node by node: the vector field ``sum_i basis_i v`` as
    coefficients of the 2-D nodal dofs, ``(m, 2 nnodes)`` for ``basis`` ``(m, nnodes)``
    and ``v`` ``(m, 2)``."""
    return (basis[:, :, None] * v[:, None, :]).reshape(basis.shape[0], 2 * basis.shape[1])


class GapHessian(typing.NamedTuple):
    """The gap's Hessian in the displacement unknowns as a sum of outer products,
    ``H = ds (x) e + e (x) ds + gamma c (x) c`` (``ds``, ``e``, ``c`` each
    ``(m, nz_u)``, ``gamma`` ``(m,)``): rank 3 per point, so the element's matrix is
    one batched product (:func:`frictionless_terms`)."""

    ds: npt.NDArray[np.float64]
    e: npt.NDArray[np.float64]
    c: npt.NDArray[np.float64]
    gamma: npt.NDArray[np.float64]

    def dense(self) -> npt.NDArray[np.float64]:
        """``H``, ``(m, nz_u, nz_u)``."""
        X = self.ds[:, :, None] * self.e[:, None, :]
        return (
            X
            + np.transpose(X, (0, 2, 1))
            + self.gamma[:, None, None] * (self.c[:, :, None] * self.c[:, None, :])
        )

    def scaled(self, k) -> GapHessian:
        """``k H`` (``k`` a scalar or ``(m,)``)."""
        k = np.broadcast_to(np.asarray(k, dtype=float), self.gamma.shape)
        return GapHessian(self.ds, k[:, None] * self.e, self.c, k * self.gamma)


def gap_derivatives(x_s, phi_s, curve, orientation):
    """Gap, its gradient ``(m, nz_u)`` and Hessian (a :class:`GapHessian`; ``.dense()``
    ``(m, nz_u, nz_u)``) in the displacement unknowns ``(a, b)`` of the pairs (the
    multiplier slots excluded).

    Args:
        x_s: Deformed slave points (m), ``(m, 2)``.
        phi_s: Slave displacement basis at them, ``(m, nn_s)``.
        curve: The :class:`~xfem_contact.mechanics.sliding.lips.CurvePoint` at the feet.
        orientation: Piece orientation (+-1) of each foot, ``(m,)``.
    """
    t, t2 = curve.t, curve.t2
    tt = np.sum(t * t, axis=1)
    n = orientation[:, None] * np.column_stack([-t[:, 1], t[:, 0]]) / np.sqrt(tt)[:, None]
    r = x_s - curve.x
    g = np.sum(r * n, axis=1)
    kappa = np.sum(n * t2, axis=1)

    def slots(basis_a, basis_b, v):
        return np.concatenate([node_slots(basis_a, v), node_slots(basis_b, v)], axis=1)

    zero_s = np.zeros_like(phi_s)
    grad = slots(phi_s, -curve.phi, n)
    c = slots(zero_s, curve.dphi, n)
    F_s = -tt + g * kappa
    F_z = slots(phi_s, -curve.phi, t) + g[:, None] * c
    ds = -F_z / F_s[:, None]
    # H = -(1 - g kappa / tt) (ds c + c ds) + (F_s kappa / tt) ds ds + (g / tt) c c
    e = -(1.0 - g * kappa / tt)[:, None] * c + (0.5 * F_s * kappa / tt)[:, None] * ds
    return g, grad, GapHessian(ds, e, c, g / tt)


def frictionless_terms(
    x_s, phi_s, lam_basis, lam_values, curve, orientation, weights, r, paired, jacobian=True
) -> PairTerms:
    """The hybrid element's terms at ``m`` slave points, unknowns ordered ``(a, l, b)``.

    Args:
        x_s: Deformed slave points (m), ``(m, 2)``.
        phi_s: Slave displacement basis, ``(m, nn)``.
        lam_basis: Multiplier basis, ``(m, nl)``.
        lam_values: Multiplier dof values, ``(m, nl)`` (Pa).
        curve: The master curve at the feet (any values where unpaired).
        orientation: Piece orientations, ``(m,)``.
        weights: Reference arc-length weights (m), ``(m,)``.
        r: Augmentation coefficients (Pa/m), ``(m,)``.
        paired: Which points have a master foot, ``(m,)``; the others carry no contact.
        jacobian: False: the residual and state only (``jacobian`` None).
    """
    m, nn = phi_s.shape
    nl = lam_basis.shape[1]
    g, grad_u, H_u = gap_derivatives(x_s, phi_s, curve, orientation)
    g = np.where(paired, g, np.inf)
    lam = np.sum(lam_basis * lam_values, axis=1)
    trial = lam + r * np.where(paired, g, 0.0)
    contact = paired & (trial < 0.0)
    P = np.where(contact, trial, 0.0)
    nz = 4 * nn + nl

    def slots(v):  # displacement slots (a, b) -> all unknowns (a, l, b)
        out = np.zeros((v.shape[0], nz))
        out[:, : 2 * nn] = v[:, : 2 * nn]
        out[:, 2 * nn + nl :] = v[:, 2 * nn :]
        return out

    grad = slots(grad_u)
    L = np.zeros((m, nz))
    L[:, 2 * nn : 2 * nn + nl] = lam_basis
    residual = weights[:, None] * (P[:, None] * grad - ((lam - P) / r)[:, None] * L)
    if not jacobian:
        return PairTerms(residual, None, np.where(paired, g, np.nan), lam, P)
    # contact: grad L + L grad + r grad grad + P H = X + X^T, X = U^T V (rank 3)
    K = np.zeros((m, nz, nz))
    on = np.flatnonzero(contact)
    H, Pc, gc = H_u, P[on], grad[on]
    U = np.stack([gc, slots(H.ds[on]), slots(H.c[on])], axis=1)
    V = np.stack(
        [
            L[on] + 0.5 * r[on, None] * gc,
            Pc[:, None] * slots(H.e[on]),
            (0.5 * Pc * H.gamma[on])[:, None] * slots(H.c[on]),
        ],
        axis=1,
    )
    X = np.matmul(np.transpose(U, (0, 2, 1)), V)
    K[on] = X + np.transpose(X, (0, 2, 1))
    off = np.flatnonzero(~contact)  # -L L / r
    lam_slots = slice(2 * nn, 2 * nn + nl)
    K[off, lam_slots, lam_slots] = (
        -(lam_basis[off, :, None] * lam_basis[off, None, :]) / r[off, None, None]
    )
    K *= weights[:, None, None]
    return PairTerms(residual, K, np.where(paired, g, np.nan), lam, P)
