"""Contact laws in large sliding: the slave/master hybrid element of the paper.

In large sliding the two lips of an interface no longer face each other at the same
reference point, so the gap is not the jump ``[u] . n``: every slave point is paired
with its closest point on the deformed master lip and the contact terms couple the
slave cell with the master cell (:mod:`xfem_contact.mechanics.sliding`), assembled
outside UFL (:meth:`SlidingFrictionless.coupling`). What stays in UFL is local to the
slave side: the multiplier's normal-gradient extension and its LBB stabilisation,
here against the slave side's own normal traction in the deformed configuration,
``lambda_n - (P N) . n~`` (``P`` the first Piola-Kirchhoff stress, ``N`` the slave's
outward reference normal, ``n~`` the deformed one, ``cof(F) N / |cof(F) N|``): the
multiplier is the contact pressure per unit reference length (Pa, compression
negative), objective under rigid rotations. SI units.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np
import ufl
from ufl.algorithms import extract_arguments, extract_coefficients

from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.laws.base import (
    Fields,
    FixedAtConstruction,
    InterfaceContext,
    InterfaceLaw,
)
from xfem_contact.mechanics.laws.contact import ContactLaw, CoulombFriction
from xfem_contact.mechanics.parameters import Parameter, constant
from xfem_contact.mechanics.sliding.coupling import PAIRING_UPDATES, SlidingCoupling

#: LBB treatments available in large sliding (the restriction needs a prolongation
#: the hybrid element's assembly does not apply)
SLIDING_LBB = ("stabilized", "none")
#: The pairing's search radius (m), when given
RADIUS = Parameter("m", minimum=0.0, strict=True)


class SlidingContact(ContactLaw):
    """Contact in large sliding (augmented Lagrangian, multipliers on the slave side;
    abstract: :class:`SlidingFrictionless`, :class:`SlidingCoulomb`).

    Args:
        slave: The slave side (-1 or +1); the master is the other one.
        pairing: ``"iterate"`` (pair at every Newton iterate) or ``"step"`` (pair at
            the start of each load step).
        radius: Search radius of the pairing (m); default the largest cut-cell size.
        segments: Segment-to-segment integration: each slave piece broken where the
            feet of its points cross master-piece ends, a Gauss rule per sub-segment
            (:mod:`~xfem_contact.mechanics.sliding.segments`); False: the interface
            rule's points. An attribute, settable between solves.
        **options: ``augmentation``, ``lbb``, ``multiplier_stabilization``,
            ``multiplier_extension``, ``multiplier_degree``, ``stabilization_length``: as
            for :class:`~xfem_contact.mechanics.laws.contact.Frictionless` (``lbb``:
            ``"stabilized"`` or ``"none"``; ``stabilization_length``: ``"cell"`` only).
    """

    #: Large sliding
    sliding = True
    slave = FixedAtConstruction()
    pairing = FixedAtConstruction()
    radius = FixedAtConstruction()

    def __init__(
        self,
        slave: int = DEFAULT.slave,
        pairing: str = DEFAULT.pairing,
        radius: float | None = None,
        segments: bool = True,
        **options,
    ):
        super().__init__(**options)
        if self.lbb not in SLIDING_LBB:
            raise ValueError(
                f"lbb {self.lbb!r} is not available in large sliding; valid: {SLIDING_LBB}"
            )
        if self.stabilization_length != "cell":
            raise ValueError(
                f"stabilization_length {self.stabilization_length!r} is not available in "
                "large sliding (its scale is the slave cell's); valid: ('cell',)"
            )
        if slave not in (-1, 1):
            raise ValueError(f"slave must be the side -1 or +1, got {slave!r}")
        if pairing not in PAIRING_UPDATES:
            raise ValueError(f"pairing must be one of {PAIRING_UPDATES}, got {pairing!r}")
        if radius is not None:
            radius = RADIUS.check(radius, "radius (of the pairing search)")
        self.slave, self.pairing, self.radius = slave, pairing, radius
        self.segments = segments

    @property
    def segments(self) -> bool:
        """Whether the pairing integrates segment to segment (settable between solves)."""
        return self._segments

    @segments.setter
    def segments(self, value: bool) -> None:
        if not isinstance(value, bool | np.bool_):
            raise ValueError(f"segments must be True or False, got {value!r}")
        self._segments = bool(value)

    def describe(self) -> dict:
        return super().describe() | {
            "kinematics": "large",
            "slave": self.slave,
            "pairing": self.pairing,
            "segments": self.segments,
        }

    def coupling(self, ctx: InterfaceContext) -> SlidingCoupling:
        """The interface's :class:`~xfem_contact.mechanics.sliding.coupling.SlidingCoupling`
        (made once per context; collective then)."""
        W = ctx.w_old.function_space
        return ctx.once(
            "coupling",
            lambda: SlidingCoupling(ctx, W, self, self.slave, self.radius, self.pairing),
        )

    # -- the UFL part: slave side only -------------------------------------------------
    def slave_traction(self, ctx: InterfaceContext, u: Fields) -> tuple:
        """``((P N) . n~, (P N) . t~)`` of the slave side (Pa per unit reference
        length; ``t~ = n~`` turned by +90 degrees), UFL."""
        u_s = u.minus if self.slave == -1 else u.plus
        N = ctx.normal if self.slave == -1 else -ctx.normal
        F = ufl.Identity(len(u_s)) + ufl.grad(u_s)
        deformed = ufl.det(F) * ufl.inv(F).T * N
        n = deformed / ufl.sqrt(ufl.dot(deformed, deformed))
        T = ctx.materials[self.slave].piola(u_s) * N
        return ufl.dot(T, n), ufl.dot(T, ufl.as_vector([-n[1], n[0]]))

    def residual(self, ctx: InterfaceContext, u: Fields, v: Fields):
        terms = []
        if self.extended:
            terms.append(-self.extension_form(ctx, u.multiplier, v.multiplier))
        if self.stabilized:
            (w,) = extract_coefficients(u.multiplier)
            (test,) = extract_arguments(v.multiplier)
            gamma = constant(self, "multiplier_stabilization")
            scale = gamma * ctx.cell_size / (2.0 * ctx.materials[self.slave].ufl_mu)
            T_n, T_t = self.slave_traction(ctx, u)
            lam_n, lam_t = self.multipliers(ctx, u)
            misfit = (lam_n - T_n) ** 2
            if lam_t is not None:
                misfit = misfit + (lam_t - T_t) ** 2
            energy = 0.5 * scale * misfit * ctx.measure
            terms.append(-ufl.derivative(energy, w, test))
        return sum(terms[1:], terms[0]) if terms else None

    # -- the state at the slave points -------------------------------------------------
    def state(self, ctx: InterfaceContext, w: dolfinx.fem.Function) -> dict[str, np.ndarray]:
        """As :meth:`ContactLaw.state`, from the pairing at ``w``: the gap to the
        master foot (unpaired points: the distance to the lip, beyond the search
        radius), ``paired`` (1.0 or 0.0); tangential entries zero. Collective."""
        coupling = self.coupling(ctx)
        pairing, terms = coupling.evaluate(w, jacobian=False)
        zero = np.zeros(pairing.piece.size)
        slip, lam_t, P_t = coupling.tangential if self.tangential else (zero, zero, zero)
        gap = np.where(pairing.paired, terms.gap, pairing.distance)
        return {
            "gap": gap,
            "slip": slip,
            "slip_increment": slip,
            "lambda_n": terms.lambda_n,
            "lambda_t": lam_t,
            "P_n": terms.P_n,
            "P_t": P_t,
            "r": coupling.r,
            "trial_t": lam_t + coupling.r * slip,
            "paired": pairing.paired.astype(float),
        }

    def status(self, state: dict[str, np.ndarray]) -> dict[str, int]:
        counts = super().status(state)
        return counts | {"unpaired": int(np.sum(state["paired"] == 0.0))}


class SlidingFrictionless(SlidingContact):
    """Frictionless contact in large sliding: a normal multiplier only; the hybrid
    element's Jacobian is the analytic one of :mod:`xfem_contact.mechanics.sliding.element`."""

    name = "frictionless"
    tangential = False


class SlidingCoulomb(CoulombFriction, SlidingContact):
    """Coulomb friction in large sliding, on the slip increment between accepted load
    steps measured along the master surface (:mod:`xfem_contact.mechanics.sliding.friction`;
    Jacobian by complex step).

    Args:
        friction: Coulomb coefficient ``mu`` (>= 0).
        slave, pairing, radius, ...: See :class:`SlidingContact`.
    """


#: The large-sliding version of each law that has one, by its name
SLIDING_VERSIONS: dict[str, type[SlidingContact]] = {
    law.name: law for law in (SlidingFrictionless, SlidingCoulomb)
}
#: The laws available in large sliding (by their small-sliding name)
SLIDING_LAWS = tuple(SLIDING_VERSIONS)


def large_sliding(
    law: InterfaceLaw, slave: int = DEFAULT.slave, pairing: str = DEFAULT.pairing
) -> InterfaceLaw:
    """The large-sliding version of a law, with the same options: contact laws become
    their hybrid-element counterparts; ``free`` and ``bonded`` (no relative motion or
    none resisted) stay.

    Raises:
        ValueError: for a contact law without a large-sliding version, naming the
            valid ones, or an LBB treatment large sliding does not offer.
    """
    if law.sliding or law.linear:
        return law
    if law.name not in SLIDING_VERSIONS:
        raise ValueError(
            f"The {law.name!r} law is not available in large sliding "
            f"(kinematics = 'large'); valid: {SLIDING_LAWS}"
        )
    return SLIDING_VERSIONS[law.name](**law.options(), slave=slave, pairing=pairing)
