"""Contact laws in small sliding: mixed augmented-Lagrangian formulation.

Unknowns: the displacement of each side (``u_-``, ``u_+``, m) and the interface
multipliers (Pa): the normal pressure ``lambda_n`` and, with friction, the
tangential traction ``lambda_t``; ``lambda = lambda_n n + lambda_t`` is the traction
``sigma n`` on side -1, compression negative. Tangential quantities are tangential parts
(:meth:`~xfem_contact.mechanics.laws.base.InterfaceContext.tangential`): scalars along
``t`` in 2D, where the multiplier field holds ``(lambda_n, lambda_t)``; vectors
``(I - n n) v`` in 3D, where it holds the Cartesian traction ``lambda`` and
``lambda_n = lambda.n``, ``lambda_t = (I - n n) lambda`` (no tangent frame is smooth on a
closed surface; docs' mechanics page). With the jump ``[u] = u_+ - u_-``, gap
``g_n = [u].n`` and slip ``g_t`` the tangential part of ``[u]`` (sticking: the
tangential jump from the reference state) or of ``[u - u_old]`` (Coulomb, path
dependent: ``u_old`` the last accepted load step), the Alart-Curnier augmented
multipliers are (:meth:`ContactLaw.augmented`)::

    P_n = min(0, lambda_n + r g_n)
    P_t = lambda_t + r g_t                                 (sticking)
    P_t = proj_{|P| <= -mu P_n}(lambda_t + r g_t)         (Coulomb)

the Coulomb one the projection on the disc of radius ``mu |P_n|``
(:func:`~xfem_contact.mechanics.laws.base.project_on_disc`; in 2D the clamp on
``[mu P_n, -mu P_n]``), and the law's residual terms (Ben Dhia's mixed form;
generalized Newton through ``ufl.derivative``):

    int (P_n [v].n + P_t.[v]_t) - int (1/r) ((lambda_n - P_n) mu_n + (lambda_t - P_t).mu_t)

minus the LBB terms. ``r = augmentation * E / h`` (Pa/m, ``E`` the harmonic mean of
the two sides' moduli, ``h`` the cell diameter). The same :meth:`ContactLaw.augmented`
evaluates the reported state at the rule points, with the same normal.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.laws.base import (
    NUMPY_OPS,
    OPEN,
    SLIP,
    STICK,
    UFL_OPS,
    Fields,
    InterfaceContext,
    Ops,
    project_on_disc,
)
from xfem_contact.mechanics.laws.multiplier import MultiplierLaw
from xfem_contact.mechanics.parameters import Parameter, constant


class ContactLaw(MultiplierLaw):
    """Unilateral contact (abstract base of the three laws below).

    Args:
        augmentation: Dimensionless factor of ``r = augmentation * E / h`` (> 0).
        **lbb_options: ``lbb``, ``multiplier_stabilization``, ``multiplier_extension``,
            ``multiplier_degree``, ``stabilization_length``: see
            :class:`~xfem_contact.mechanics.laws.multiplier.MultiplierLaw`.
    """

    linear = False
    #: Whether the law has a tangential multiplier
    tangential = True

    augmentation = Parameter(minimum=0.0, strict=True)

    def __init__(self, augmentation: float = DEFAULT.augmentation, **lbb_options):
        super().__init__(**lbb_options)
        self.augmentation = augmentation

    def describe(self) -> dict:
        return super().describe() | {"augmentation": self.augmentation}

    @property
    def transmits(self) -> str:
        """``"normal"`` without a friction bound above zero, else ``"full"``."""
        if not self.tangential or self.friction_bound(-1.0, NUMPY_OPS) == 0.0:
            return "normal"
        return "full"

    def multiplier_components(self, gdim: int) -> int:
        return gdim if self.tangential else 1

    # -- one definition for UFL and numpy --------------------------------------------
    def augmentation_coefficient(self, materials: dict, h):
        """``r = augmentation * E / h`` (Pa/m) of ``materials`` (``{-1: Moduli, 1:
        Moduli}``) for ``h`` a UFL (Constants) or numpy
        (values) cell size (m), ``E = 2 E_- E_+ / (E_- + E_+)``: the softer side sets
        it. With the arithmetic mean, a 1e6 times stiffer inclusion under hydrostatic
        pressure opened part of its interface (tests/stability/test_materials.py)."""
        m = materials
        if isinstance(h, np.ndarray):
            E_minus, E_plus, a = m[-1].E, m[1].E, self.augmentation
        else:
            E_minus, E_plus, a = m[-1].ufl_E, m[1].ufl_E, constant(self, "augmentation")
        return a * (2.0 * E_minus * E_plus / (E_minus + E_plus)) / h

    def friction_bound(self, P_n, ops: Ops):
        """The bound of ``|P_t|`` (Pa) given ``P_n``; None for no bound."""
        return None

    def augmented(self, lam_n, lam_t, gap, slip, r, ops: Ops) -> tuple:
        """Augmented multipliers ``(P_n, P_t)`` (Pa; ``P_t`` None without a tangential
        multiplier) from the multipliers, gap and slip (increment; tangential parts) and
        ``r``."""
        P_n = ops.minimum(0.0, lam_n + r * gap)
        if lam_t is None:
            return P_n, None
        trial = lam_t + ops.scale(r, slip)
        bound = self.friction_bound(P_n, ops)
        if bound is None:
            return P_n, trial
        return P_n, project_on_disc(trial, bound, ops)

    def multipliers(self, ctx: InterfaceContext, u: Fields) -> tuple:
        """``(lambda_n, lambda_t or None)`` of the law's fields (``lambda_t`` a
        tangential part: see the module docstring)."""
        if not self.tangential:
            return u.multiplier, None
        return ctx.multiplier_parts(u.multiplier)

    def traction_vector(self, ctx: InterfaceContext, u: Fields):
        """Cartesian multiplier vector ``lambda_n n + lambda_t`` (UFL)."""
        n = ctx.normal
        lam_n, lam_t = self.multipliers(ctx, u)
        return lam_n * n if lam_t is None else lam_n * n + ctx.tangent_vector(lam_t)

    # -- the residual ----------------------------------------------------------------
    def residual(self, ctx: InterfaceContext, u: Fields, v: Fields) -> ufl.Form:
        n = ctx.normal
        r = self.augmentation_coefficient(ctx.materials, ctx.cell_size)
        lam_n, lam_t = self.multipliers(ctx, u)
        mu_n, mu_t = self.multipliers(ctx, v)
        slip_jump = u.jump
        if self.incremental:
            slip_jump = slip_jump - ctx.fields(ctx.split(ctx.w_old)).jump
        P_n, P_t = self.augmented(
            lam_n, lam_t, ufl.dot(u.jump, n), ctx.tangential(slip_jump), r, UFL_OPS
        )
        interface = P_n * ufl.dot(v.jump, n) - (lam_n - P_n) * mu_n / r
        if P_t is not None:
            interface += ufl.dot(P_t, ctx.tangential(v.jump)) - ufl.dot(lam_t - P_t, mu_t) / r
        F = interface * ctx.measure
        lbb = self.lbb_terms(ctx, self.traction_vector(ctx, u), self.traction_vector(ctx, v), u, v)
        if lbb is not None:
            F -= lbb
        if self.incremental and self.stabilized:
            # The tangential law is incremental (slip of the step): its share of the
            # stabilisation is measured from the last accepted step too, so that the
            # steps telescope (sticking in n steps = in one). Jacobian unchanged.
            old = ctx.fields(ctx.split(ctx.w_old))
            _, old_t = self.multipliers(ctx, old)
            old_residual = old_t - ctx.tangential(self.interface_traction(ctx, old))
            F += ufl.dot(self.stabilization_scale(ctx) * old_residual, mu_t) * ctx.measure
        return F

    # -- the state at the rule points ------------------------------------------------
    def state(self, ctx: InterfaceContext, w: dolfinx.fem.Function) -> dict[str, np.ndarray]:
        """Point values at this process's rule points of the interface, each
        ``(npoints,)`` (tangential parts ``(npoints, 3)`` in 3D): ``gap``, ``slip`` and
        ``slip_increment`` (the slip the tangential law sees: of the load step for
        Coulomb, else the slip) (m), the multipliers ``lambda_n``, ``lambda_t``, the
        augmented (applied) tractions ``P_n``, ``P_t`` (Pa; tangential ones zero when
        frictionless), the trial tangential traction ``trial_t`` (Pa) and ``r``
        (Pa/m)."""
        n = ctx.normal_at()
        jump, lam = ctx.jump_at(w), ctx.values_at(w, ctx.field)
        r = self.augmentation_coefficient(ctx.materials, ctx.cell_size_at())
        gap = np.sum(jump * n, axis=1)
        slip = ctx.tangential_at(jump)
        slip_increment = slip
        if self.incremental:
            slip_increment = slip - ctx.tangential_at(ctx.jump_at(ctx.w_old))
        lam_n, lam_t = ctx.multiplier_parts_at(lam) if self.tangential else (lam[:, 0], None)
        P_n, P_t = self.augmented(lam_n, lam_t, gap, slip_increment, r, NUMPY_OPS)
        lam_t = np.zeros_like(slip) if lam_t is None else lam_t
        return {
            "gap": gap,
            "slip": slip,
            "slip_increment": slip_increment,
            "lambda_n": lam_n,
            "lambda_t": lam_t,
            "P_n": P_n,
            "P_t": np.zeros_like(slip) if P_t is None else P_t,
            "r": r,
            "trial_t": lam_t + NUMPY_OPS.scale(r, slip_increment),
        }

    def point_status(self, state: dict[str, np.ndarray], npoints: int) -> np.ndarray:
        """In contact where the applied pressure ``P_n < 0``; sticking where the trial
        tangential traction lies within the friction bound (always for ``sticking``,
        never without a tangential multiplier)."""
        contact = state["P_n"] < 0.0
        if not self.tangential:
            stick = np.zeros_like(contact)
        else:
            bound = self.friction_bound(state["P_n"], NUMPY_OPS)
            trial = state["trial_t"]
            size = np.abs(trial) if trial.ndim == 1 else np.linalg.norm(trial, axis=1)
            stick = contact if bound is None else contact & (size <= bound)
        return np.where(contact, np.where(stick, STICK, SLIP), OPEN).astype(np.int8)

    def status(self, state: dict[str, np.ndarray]) -> dict[str, int]:
        """Local counts of rule points in contact and, with friction, stick / slip."""
        codes = self.point_status(state, state["P_n"].size)
        counts = {"contact": int(np.sum(codes != OPEN))}
        if self.tangential:
            counts |= {"stick": int(np.sum(codes == STICK)), "slip": int(np.sum(codes == SLIP))}
        return counts


class Frictionless(ContactLaw):
    """Frictionless contact: a normal multiplier only."""

    name = "frictionless"
    tangential = False
    symmetric = True


class Sticking(ContactLaw):
    """Contact with no slip: the tangential jump is held at zero while in contact."""

    name = "sticking"
    symmetric = True


class CoulombFriction:
    """Coulomb's bound ``|P_t| <= mu |P_n|`` (a disc; a segment in 2D) on the slip of the
    step, written once for the small- and large-sliding laws (the first base of :class:`Coulomb` and
    :class:`~xfem_contact.mechanics.laws.sliding.SlidingCoulomb`).

    Args:
        friction: Coulomb coefficient ``mu`` (>= 0); a Constant of the forms.
    """

    name = "coulomb"
    incremental = True

    friction = Parameter(minimum=0.0)

    def __init__(self, friction: float | None = None, **options):
        if friction is None:
            raise ValueError("The 'coulomb' law needs a friction coefficient (friction=...)")
        super().__init__(**options)
        self.friction = friction

    def describe(self) -> dict:
        return super().describe() | {"friction": self.friction}

    def friction_bound(self, P_n, ops: Ops):
        mu = self.friction if ops is NUMPY_OPS else constant(self, "friction")
        return -mu * P_n


class Coulomb(CoulombFriction, ContactLaw):
    """Coulomb friction, incremental: ``|P_t| <= mu |P_n|`` on the slip of the step.

    Args:
        friction: Coulomb coefficient ``mu`` (>= 0).
        augmentation, lbb, ...: See :class:`ContactLaw`.
    """
