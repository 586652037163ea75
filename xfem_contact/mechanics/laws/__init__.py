"""Interface laws: objects a problem composes, one per interface.

Each law declares the multiplier field it needs, contributes its residual terms and
evaluates its state at the interface rule points from the same definitions (see
:mod:`xfem_contact.mechanics.laws.base`). Small-sliding laws: ``free`` and ``bonded``
(linear, :mod:`~xfem_contact.mechanics.laws.bonding`), ``frictionless``, ``coulomb``
and ``sticking`` (augmented Lagrangian, :mod:`~xfem_contact.mechanics.laws.contact`);
in large sliding :func:`large_sliding` gives their hybrid-element versions
(:mod:`~xfem_contact.mechanics.laws.sliding`).
A new law subclasses :class:`InterfaceLaw` (or :class:`MultiplierLaw`) and is listed
in :data:`LAWS`.
"""

from xfem_contact.mechanics.laws.base import Fields, InterfaceContext, InterfaceLaw
from xfem_contact.mechanics.laws.bonding import Bonded, Free
from xfem_contact.mechanics.laws.contact import ContactLaw, Coulomb, Frictionless, Sticking
from xfem_contact.mechanics.laws.multiplier import LBB_OPTIONS, MultiplierLaw
from xfem_contact.mechanics.laws.sliding import (
    SLIDING_LAWS,
    SlidingContact,
    SlidingCoulomb,
    SlidingFrictionless,
    large_sliding,
)

#: The laws by name
LAWS: dict[str, type[InterfaceLaw]] = {
    law.name: law for law in (Free, Bonded, Frictionless, Coulomb, Sticking)
}
#: Names of the linear laws (one KSP solve) and of the contact laws (Newton)
LINEAR_LAWS = tuple(name for name, law in LAWS.items() if law.linear)
CONTACT_LAWS = tuple(name for name, law in LAWS.items() if not law.linear)


def make_law(name: str, **options) -> InterfaceLaw:
    """The law called ``name`` with its options.

    Options: ``friction`` (``coulomb``; ``None`` or a coefficient >= 0 is accepted
    and unused by the other laws), ``augmentation`` (contact laws; unused by
    ``free``/``bonded``), ``lbb``, ``multiplier_stabilization`` and
    ``multiplier_extension`` (laws with a multiplier; unused by ``free``).
    Any other option raises a ValueError naming it.
    """
    if name not in LAWS:
        raise ValueError(f"Unknown interface law {name!r}; valid: {tuple(LAWS)}")
    law = LAWS[name]
    options = dict(options)
    friction = options.pop("friction", None)
    if friction is not None and not friction >= 0.0:
        raise ValueError(f"The friction coefficient must be >= 0, got {friction}")
    if law is Coulomb:
        options["friction"] = friction
    if not issubclass(law, ContactLaw):
        options.pop("augmentation", None)
    if not issubclass(law, MultiplierLaw):
        for key in ("lbb", "multiplier_stabilization", "multiplier_extension"):
            options.pop(key, None)
    try:
        return law(**options)
    except TypeError:
        raise ValueError(f"The {name!r} law takes no option(s) {sorted(options)}") from None


__all__ = [
    "CONTACT_LAWS",
    "LAWS",
    "LBB_OPTIONS",
    "LINEAR_LAWS",
    "Bonded",
    "ContactLaw",
    "Coulomb",
    "Fields",
    "Free",
    "Frictionless",
    "InterfaceContext",
    "InterfaceLaw",
    "MultiplierLaw",
    "SLIDING_LAWS",
    "SlidingContact",
    "SlidingCoulomb",
    "SlidingFrictionless",
    "large_sliding",
    "Sticking",
    "make_law",
]
