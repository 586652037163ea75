"""The validated scene records: frozen dataclasses of an interface, a crack, a load and a scene
(:func:`xfem_contact.scenes.scene.load_scene` returns a :class:`Scene`; the keys and
checks behind them are :mod:`xfem_contact.scenes.schema`'s). SI units."""

from __future__ import annotations

import dataclasses
import pathlib

from xfem_contact.mechanics.materials import Material


@dataclasses.dataclass(frozen=True)
class InterfaceSpec:
    shape: str
    law: str
    inside: str
    outside: str
    params: dict
    name: str = "interface"
    friction: float | None = None
    #: None: the law's default (:data:`~xfem_contact.mechanics.defaults.DEFAULTS`)
    augmentation: float | None = None
    lbb: str | None = None
    multiplier_degree: int | None = None
    kinematics: str = "small"
    slave: int = -1
    pairing: str = "iterate"


@dataclasses.dataclass(frozen=True)
class CrackSpec:
    """A crack: its shape's parameters (``points``; ``centre``, ``radius``,
    ``angles_deg``; or ``phi``, ``psi`` expressions), the law of its lips, the tip
    enrichment radius (m; None: the default, half the tip's crack length), the rings of
    K (m; None: the default, in units of the tip's crack length) and the reference
    ``(K_I, K_II)`` (Pa m^1/2) of every tip with its source (None: no reference)."""

    shape: str
    params: dict
    material: str
    name: str = "crack"
    law: str = "free"
    friction: float | None = None
    augmentation: float | None = None
    lbb: str | None = None
    multiplier_degree: int | None = None
    tip_radius: float | None = None
    rings: tuple | None = None
    reference_K: tuple | None = None
    reference_source: str = ""


@dataclasses.dataclass(frozen=True)
class LoadSpec:
    part: str | None
    type: str
    value: object
    side: int | None = None
    component: int | None = None
    point: tuple | None = None
    centre: tuple = (0.0, 0.0)
    #: Load path: None (factor = t), ((t, factor), ...) or a stage name
    path: object = None
    #: A rotation's angle in degrees (``value`` holds radians otherwise)
    angle_deg: float | None = None


@dataclasses.dataclass(frozen=True)
class Scene:
    """A validated scene (see the module docstring for the TOML form)."""

    name: str
    kind: str
    file: pathlib.Path | None
    size: float | None
    corners: tuple
    radii: tuple
    geometry_degree: int
    cells: tuple
    cell: str
    degree: int
    levelset_degree: int
    #: None: the cut's default (6 for interfaces, 16 for a crack)
    quadrature_degree: int | None
    materials: dict[str, Material]
    interfaces: tuple[InterfaceSpec, ...]
    parts: dict[str, str]
    loads: tuple[LoadSpec, ...]
    outputs: dict
    load_steps: int = 1
    #: Named load stages: name -> (start, end) pseudo-times
    stages: dict = dataclasses.field(default_factory=dict)
    #: Pseudo-time of the last load step (None: the loads' last time, at least 1)
    end_time: float | None = None
    #: PETSc options of the solver (SNES/KSP, without prefix)
    petsc_options: dict = dataclasses.field(default_factory=dict)
    #: The cracks (one at most today; not with interfaces)
    cracks: tuple[CrackSpec, ...] = ()
    #: The geometric dimension of the mesh: 2, or 3 (a box, a 3D gmsh file)
    gdim: int = 2
