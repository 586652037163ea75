"""Loads of a problem: boundary parts, magnitudes as data, load paths, supports.

A problem holds one :class:`Loads` (``problem.loads``). Parts are named
(:mod:`~xfem_contact.mechanics.loads.parts`), magnitudes given as numbers are
Constants (:mod:`~xfem_contact.mechanics.loads.values`), each load follows its own
path in pseudo-time (:mod:`~xfem_contact.mechanics.loads.history`), and each
``add_*`` returns a handle (:mod:`~xfem_contact.mechanics.loads.handles`).
"""

from xfem_contact.mechanics.loads.fields import PlainFields, SideFields
from xfem_contact.mechanics.loads.handles import (
    DirichletLoad,
    FormLoad,
    Load,
    RotationLoad,
    SpringSupport,
)
from xfem_contact.mechanics.loads.history import History, load_steps
from xfem_contact.mechanics.loads.loads import Loads
from xfem_contact.mechanics.loads.parts import (
    Part,
    annulus_parts,
    boundary_facets,
    named_parts,
    rectangle_parts,
)

__all__ = [
    "DirichletLoad",
    "FormLoad",
    "History",
    "Load",
    "Loads",
    "Part",
    "PlainFields",
    "RotationLoad",
    "SideFields",
    "SpringSupport",
    "annulus_parts",
    "boundary_facets",
    "load_steps",
    "named_parts",
    "rectangle_parts",
]
