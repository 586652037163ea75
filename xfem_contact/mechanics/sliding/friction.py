"""The hybrid element with friction: analytic residual, Jacobian by complex step.

With Coulomb friction the residual also holds the slip increment's gradient, whose
own linearisation (through the foot, the master tangent and its curvature) is long
to write by hand; the Jacobian is instead the complex-step derivative of the
residual, ``K e_j = Im R(z + i h e_j) / h`` (``h = 1e-30``: exact to round-off, no
cancellation). Complex quantities at the foot are first-order expansions about
the real foot ``s_r``: ``Q(s_r + ds) = Q(s_r) + ds Q'(s_r)`` with ``ds = -f / f'``
one Newton step of the closest-point equation (exact in the imaginary part),
which is why the curve's third derivative is needed.

Slip increment (between accepted load steps, measured along the master surface):
``s_t = tau . (du_s - du_m(s))``, ``du`` the displacements since the last
accepted step at the slave point and at the current foot, ``tau = (-n_y, n_x)``
the master tangent (``n`` out of the master). Its gradient, at a closest point::

    grad s_t = (S - B)^T tau - o (n . d) / |t| (B'^T n + (n . x_m'') grad s)
               - (tau . (B' (b - b_old))) grad s,     grad s = -F_z / F_s,

``d = du_s - du_m``. Law: ``P_n = min(0, lambda_n + r g)``, ``P_t = clamp(lambda_t
+ r s_t, -mu |P_n|, mu |P_n|)``; residual ``w (P_n grad g + P_t grad s_t - ((lambda_n
- P_n) L_n + (lambda_t - P_t) L_t) / r)``. Unknowns ``z = (a, l, b)`` as in
:mod:`~xfem_contact.mechanics.sliding.element`, the multiplier dofs node by node
``(lambda_n, lambda_t)``. Vectorised over points (numpy). SI units (m, Pa).
"""

from __future__ import annotations

import typing

import numpy as np

from xfem_contact.mechanics.sliding.element import PairTerms, node_slots

#: Complex step (any tiny number: no cancellation)
STEP = 1e-30


class PointData(typing.NamedTuple):
    """What the element needs at ``m`` slave points besides the unknowns.

    Attributes:
        X_s: Reference slave points (m), ``(m, 2)``.
        phi_s: Slave displacement basis, ``(m, nn_s)``.
        L: Multiplier basis, ``(m, nl)``.
        weights: Reference arc-length weights (m), ``(m,)``.
        r: Augmentation coefficients (Pa/m), ``(m,)``.
        orientation: Piece orientations, ``(m,)``.
        curve: Geometry at the real foot: ``(X, X', X'', X''')`` each ``(m, 2)``, and the
            master basis ``(phi, phi', phi'', phi''')`` each ``(m, nn_m)``.
        old: The slave and master dofs at the last accepted step, ``(m, 2 nn_s)`` and
            ``(m, 2 nn_m)``.
        paired: ``(m,)`` bool.
    """

    X_s: np.ndarray
    phi_s: np.ndarray
    L: np.ndarray
    weights: np.ndarray
    r: np.ndarray
    orientation: np.ndarray
    curve: tuple
    old: tuple
    paired: np.ndarray

    def repeat(self, k: int) -> PointData:
        """Each point's data ``k`` times (rows ``i k .. i k + k - 1`` are point ``i``)."""

        def rep(a):
            if isinstance(a, tuple):
                return tuple(rep(b) for b in a)
            return np.repeat(a, k, axis=0)

        return PointData(*(rep(a) for a in self))


def _dot(a, b):
    return np.sum(a * b, axis=-1)


def _pick(condition, a, b):
    return np.where(condition, a, b)


def residual(z: np.ndarray, data: PointData, friction: float | None):
    """The residual ``(m, nz)`` (complex when ``z`` is) and the state
    ``(g, s_t, lambda_n, lambda_t, P_n, P_t)``; ``friction`` None: frictionless."""
    m = z.shape[0]
    nn_s, nl = data.phi_s.shape[1], data.L.shape[1]
    c = 1 if friction is None else 2
    a = z[:, : 2 * nn_s].reshape(m, nn_s, 2)
    lam = z[:, 2 * nn_s : 2 * nn_s + c * nl].reshape(m, nl, c)
    nn_m = data.curve[1][0].shape[1]
    b = z[:, 2 * nn_s + c * nl :].reshape(m, nn_m, 2)
    (X, X1, X2, X3), (phi, dphi, ddphi, dddphi) = data.curve
    a_old, b_old = data.old[0].reshape(m, nn_s, 2), data.old[1].reshape(m, nn_m, 2)

    def field(basis, values):
        return np.einsum("mi,mid->md", basis, values)

    x_s = data.X_s + field(data.phi_s, a)
    x0, t0 = X + field(phi, b), X1 + field(dphi, b)
    t20, t30 = X2 + field(ddphi, b), X3 + field(dddphi, b)
    f = _dot(x_s - x0, t0)
    fp = -_dot(t0, t0) + _dot(x_s - x0, t20)
    ds = -f / fp.real  # one Newton step from the real foot
    x_m, t, t2 = x0 + ds[:, None] * t0, t0 + ds[:, None] * t20, t20 + ds[:, None] * t30
    phi_m, dphi_m = phi + ds[:, None] * dphi, dphi + ds[:, None] * ddphi
    tt = _dot(t, t)
    norm = np.sqrt(tt)
    n = data.orientation[:, None] * np.stack([-t[:, 1], t[:, 0]], axis=1) / norm[:, None]
    tau = np.stack([-n[:, 1], n[:, 0]], axis=1)
    g = _dot(x_s - x_m, n)
    kappa = _dot(n, t2)

    def slots(basis_s, basis_m, v):  # (a, l, b) with the multiplier slots empty
        zs, zm = node_slots(basis_s, v), node_slots(basis_m, v)
        return np.concatenate([zs, np.zeros((m, c * nl), dtype=zs.dtype), zm], axis=1)

    def multiplier_slot(k):
        out = np.zeros((m, z.shape[1]), dtype=float)
        out[:, 2 * nn_s + k : 2 * nn_s + c * nl : c] = data.L
        return out

    grad_g = slots(data.phi_s, -phi_m, n)
    lam_n = np.sum(data.L * lam[:, :, 0], axis=1)
    r = data.r
    trial_n = lam_n + r * _pick(data.paired, g, 0.0)
    contact = data.paired & (trial_n.real < 0.0)
    P_n = _pick(contact, trial_n, 0.0)
    R = P_n[:, None] * grad_g - ((lam_n - P_n) / r)[:, None] * multiplier_slot(0)
    lam_t = s_t = P_t = np.zeros(m)
    if friction is not None:
        zero = np.zeros_like(data.phi_s)
        cvec = slots(zero, dphi_m, n)
        F_s = -tt + g * kappa
        grad_s = -(slots(data.phi_s, -phi_m, t) + g[:, None] * cvec) / F_s[:, None]
        d = field(data.phi_s, a - a_old) - field(phi_m, b - b_old)
        dt = field(dphi_m, b - b_old)
        s_t = _dot(tau, d)
        grad_t = (
            slots(data.phi_s, -phi_m, tau)
            - (data.orientation * _dot(n, d) / norm)[:, None] * (cvec + kappa[:, None] * grad_s)
            - _dot(tau, dt)[:, None] * grad_s
        )
        lam_t = np.sum(data.L * lam[:, :, 1], axis=1)
        trial_t = lam_t + r * _pick(data.paired, s_t, 0.0)
        bound = -friction * P_n
        P_t = _pick(
            trial_t.real > bound.real, bound, _pick(trial_t.real < -bound.real, -bound, trial_t)
        )
        P_t = _pick(contact, P_t, 0.0)
        R = R + P_t[:, None] * grad_t - ((lam_t - P_t) / r)[:, None] * multiplier_slot(1)
    R = data.weights[:, None] * R
    return R, (g, s_t, lam_n, lam_t, P_n, P_t)


def hybrid_terms(z: np.ndarray, data: PointData, friction: float | None) -> tuple:
    """Residual ``(m, nz)`` and its complex-step Jacobian ``(m, nz, nz)``, with the
    state (see :func:`residual`)."""
    m, nz = z.shape
    R, state = residual(z, data, friction)
    Z = (z[:, None, :] + 1j * STEP * np.eye(nz)[None]).reshape(m * nz, nz)
    Rc, _ = residual(Z, data.repeat(nz), friction)
    K = np.transpose(Rc.imag.reshape(m, nz, nz), (0, 2, 1)) / STEP
    return R.real, K, state


def terms(z, data, friction) -> PairTerms:
    """:func:`hybrid_terms` as the :class:`PairTerms` of the frictionless element (the
    tangential state in ``.tangential``: slip increment, lambda_t, P_t)."""
    R, K, (g, s_t, lam_n, lam_t, P_n, P_t) = hybrid_terms(z, data, friction)
    out = PairTerms(R, K, np.where(data.paired, g, np.nan), lam_n, P_n)
    return out, (s_t, lam_t, P_t)
