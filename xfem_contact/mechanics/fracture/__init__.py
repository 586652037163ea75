"""Fracture mechanics post-processing: near-tip fields, exact crack solutions, and the
stress intensity factors of a crack tip.

:mod:`~.williams` holds the tip's branch functions and the exact mode I / II fields,
:mod:`~.westergaard` the Griffith crack in an infinite plate, :mod:`~.rings` the
q-functions of the domain integrals, :mod:`~.interaction` the interaction integral
(K_I, K_II) and the J-integral, :mod:`~.tips` those of every tip of a cracked
problem, and :mod:`~.growth` quasi-static propagation.
"""

from xfem_contact._deprecation import renamed
from xfem_contact.mechanics.fracture.growth import (
    GrowthPath,
    GrowthStep,
    grow,
    kink_angle,
    paris_increment,
)
from xfem_contact.mechanics.fracture.interaction import (
    InteractionIntegral,
    Lip,
    Piece,
    RingResult,
    graded_facet_measure,
    spread,
)
from xfem_contact.mechanics.fracture.rings import Ring, scaled_rings, tip_cell_size
from xfem_contact.mechanics.fracture.tips import TipIntegrals, lip_tractions
from xfem_contact.mechanics.fracture.westergaard import GriffithCrack
from xfem_contact.mechanics.fracture.williams import (
    NUMPY,
    UFL,
    TipFrame,
    WilliamsField,
    branch_functions,
    branch_gradients,
    effective_modulus,
    kolosov,
    tip_frame,
)

__all__ = [
    "GrowthPath",
    "GrowthStep",
    "NUMPY",
    "UFL",
    "GriffithCrack",
    "InteractionIntegral",
    "Lip",
    "Piece",
    "Ring",
    "RingResult",
    "TipFrame",
    "TipIntegrals",
    "WilliamsField",
    "branch_functions",
    "branch_gradients",
    "effective_modulus",
    "graded_facet_measure",
    "grow",
    "kink_angle",
    "paris_increment",
    "kolosov",
    "lip_tractions",
    "scaled_rings",
    "spread",
    "tip_cell_size",
    "tip_frame",
]


#: ``CrackPath`` is GrowthPath here (``geometry.crack_paths.CrackPath`` is a scene's crack shape)
__getattr__ = renamed(__name__, {"CrackPath": "GrowthPath"}, globals())
