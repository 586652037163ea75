"""Loads of a problem: boundary parts, magnitudes as data, load paths, supports.

A problem holds one :class:`Loads` (``problem.loads``). Parts are named
(:mod:`~xfem_contact.mechanics.loads.parts`), magnitudes given as numbers are
Constants (:mod:`~xfem_contact.mechanics.loads.values`), each load follows its own
path in pseudo-time (:mod:`~xfem_contact.mechanics.loads.load_path`), and each
``add_*`` returns a handle (:mod:`~xfem_contact.mechanics.loads.handles`).
"""

from xfem_contact._deprecation import renamed
from xfem_contact.mechanics.loads.fields import PlainFields, SideFields
from xfem_contact.mechanics.loads.handles import (
    DirichletLoad,
    FormLoad,
    Load,
    RotationLoad,
    TangentialSpring,
)
from xfem_contact.mechanics.loads.load_path import LoadPath, load_steps
from xfem_contact.mechanics.loads.loads import Loads
from xfem_contact.mechanics.loads.parts import (
    BOX_FACES,
    Part,
    annulus_parts,
    boundary_facets,
    box_parts,
    named_parts,
    rectangle_parts,
)

__all__ = [
    "DirichletLoad",
    "FormLoad",
    "Load",
    "LoadPath",
    "Loads",
    "Part",
    "PlainFields",
    "RotationLoad",
    "SideFields",
    "TangentialSpring",
    "BOX_FACES",
    "annulus_parts",
    "box_parts",
    "boundary_facets",
    "load_steps",
    "named_parts",
    "rectangle_parts",
]

#: Deprecated names of this package's classes: old name -> new name
_RENAMED = {"History": "LoadPath", "SpringSupport": "TangentialSpring"}


__getattr__ = renamed(__name__, _RENAMED, globals())
