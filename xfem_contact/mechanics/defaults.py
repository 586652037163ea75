"""Every default of a problem and of its interface laws, in one table.

Constructors, the scene schema and the docs read their defaults from :data:`DEFAULTS`
(as FFCx's ``options.py`` does), so that a default is written once.
"""

from __future__ import annotations

import types
import typing


class Default(typing.NamedTuple):
    """A default value and what it means."""

    value: typing.Any
    doc: str


#: Defaults by option name
DEFAULTS: dict[str, Default] = {
    "law": Default("free", "interface law of a Problem (scenes: 'bonded')"),
    "kinematics": Default(
        "small", "'small' (linear elasticity) or 'large' (Saint Venant-Kirchhoff)"
    ),
    "ghost_penalty": Default(0.01, "dimensionless weight of the ghost penalty (0: none)"),
    "ghost_penalty_higher": Default(
        1.0, "factor of the ghost penalty's jumps of second and higher derivatives (degree 2)"
    ),
    "min_support_fraction": Default(
        None, "enriched dofs kept down to this cut fraction (None: all with the ghost penalty)"
    ),
    "aggregation": Default(
        None, "cell aggregation: side volume fraction of a badly cut cell (None: off)"
    ),
    "augmentation": Default(1.0, "dimensionless factor of r = augmentation E / h (contact laws)"),
    "lbb": Default("stabilized", "LBB treatment: 'stabilized', 'restriction' or 'none'"),
    "crack_lbb": Default(
        "restriction", "LBB treatment of a crack's law given by name ('stabilized' refused)"
    ),
    "multiplier_degree": Default(
        1, "multiplier degree: 1 (the cut cells' vertices) or 2 (their vertices and edge nodes)"
    ),
    "multiplier_stabilization": Default(
        None,
        "weight of the Barbosa-Hughes term (None: 0.1 with the 'cell' length, 0.5 'cut', 'patch')",
    ),
    "stabilization_length": Default(
        "cell",
        "length of the Barbosa-Hughes scale: the cell's diameter, the cut's ('cut') or the "
        "cut's credited through the ghost penalty ('patch')",
    ),
    "multiplier_extension": Default(1e-12, "weight of the multiplier's normal-gradient term"),
    "slave": Default(-1, "slave side of large sliding (-1 or +1)"),
    "pairing": Default("iterate", "large-sliding pairing: at every 'iterate' or once a 'step'"),
}


#: The default values as attributes (``DEFAULT.ghost_penalty``), for signatures
DEFAULT = types.SimpleNamespace(**{name: d.value for name, d in DEFAULTS.items()})
