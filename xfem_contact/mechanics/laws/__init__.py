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

from xfem_contact.mechanics.laws.base import Fields, InterfaceContext, InterfaceLaw, law_options
from xfem_contact.mechanics.laws.bonding import Bonded, Free
from xfem_contact.mechanics.laws.contact import ContactLaw, Coulomb, Frictionless, Sticking
from xfem_contact.mechanics.laws.multiplier import LBB_OPTIONS, MULTIPLIER_DEGREES, MultiplierLaw
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


#: The options of each law by name
LAW_OPTIONS: dict[str, tuple[str, ...]] = {name: law_options(law) for name, law in LAWS.items()}


def make_law(name: str, **options) -> InterfaceLaw:
    """The law called ``name`` with its options (an option given as ``None`` is
    absent: the law's default holds).

    Raises:
        ValueError: for an unknown law, or an option the law does not take (naming
            the law's options), or an invalid value.
    """
    if name not in LAWS:
        raise ValueError(f"Unknown interface law {name!r}; valid: {tuple(LAWS)}")
    options = {k: v for k, v in options.items() if v is not None}
    unknown = sorted(set(options) - set(LAW_OPTIONS[name]))
    if unknown:
        valid = LAW_OPTIONS[name] or "none"
        raise ValueError(f"The {name!r} law takes no option {unknown}; its options: {valid}")
    return LAWS[name](**options)


__all__ = [
    "CONTACT_LAWS",
    "LAWS",
    "LAW_OPTIONS",
    "LBB_OPTIONS",
    "LINEAR_LAWS",
    "MULTIPLIER_DEGREES",
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
    "law_options",
    "Sticking",
    "make_law",
]
