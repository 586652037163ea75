"""The scene schema: allowed keys, choices and the validated scene records.

One table (:data:`SCHEMA`) names every key of every table with its meaning; the
frozen dataclasses are what :func:`xfem_contact.scenes.scene.load_scene` returns.
"""

from __future__ import annotations

import dataclasses
import pathlib

from xfem_contact.mechanics.laws import CONTACT_LAWS, LINEAR_LAWS
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.options import defaults

_NEWTON = defaults("newton")  # the [solver] defaults are the Newton solver's

LAWS = LINEAR_LAWS + CONTACT_LAWS
SHAPES = ("circle", "ellipse", "line", "half-plane", "expression")
LOAD_TYPES = ("pressure", "traction", "displacement", "point_displacement", "body_force")
KINEMATICS = ("small", "large")
CELLS = ("quadrilateral", "triangle")
MESH_KINDS = ("rectangle", "annulus", "gmsh")
BUILTIN_PARTS = {
    "rectangle": ("left", "right", "bottom", "top", "boundary"),
    "annulus": ("inner", "outer", "boundary"),
    "gmsh": ("boundary",),  # plus the file's named 1-D physical groups
}
#: Keys in which the interfaces of one scene must agree: they lie in one body (the
#: outside material) and share the kinematics; laws and inside materials may differ
SHARED_INTERFACE_KEYS = ("kinematics", "outside")

#: Allowed keys of each table, with their meaning (the schema in one place)
SCHEMA = {
    "scene": {"name": "scene name", "description": "free text"},
    "mesh": {
        "kind": f"one of {MESH_KINDS}",
        "file": "a gmsh .geo or .msh file, relative to the scene file (gmsh)",
        "size": "target cell size (m) when meshing a .geo file (gmsh)",
        "corners": "[[x0, y0], [x1, y1]] (m, rectangle)",
        "radii": "[r_inner, r_outer] (m, annulus centred at the origin)",
        "cells": "[nx, ny] or [n_radial, n_angular]",
        "cell": f"one of {CELLS}",
        "geometry_degree": "1 (straight cells) or 2 (curved cells: annulus, gmsh .geo)",
    },
    "discretisation": {
        "degree": "displacement degree 1 or 2",
        "levelset_degree": "1 or 2",
        "quadrature_degree": ">= 1",
    },
    "interface": {
        "name": "label",
        "shape": f"one of {SHAPES}",
        "centre": "[x, y] (m)",
        "radius": "(m)",
        "axes": "[a, b] (m)",
        "angle": "(rad)",
        "point": "[x, y]",
        "normal": "[nx, ny]",
        "expression": "phi(x, y), negative inside",
        "law": f"one of {LAWS}",
        "friction": "Coulomb coefficient >= 0",
        "augmentation": "> 0",
        "lbb": "stabilized | restriction",
        "kinematics": f"one of {KINEMATICS}",
        "inside": "material of side -1",
        "outside": "material of side +1",
    },
    "material": {
        "E": "Young's modulus (Pa) > 0",
        "nu": "Poisson ratio in (-1, 0.5)",
        "plane": "strain | stress",
    },
    "solver": {
        "load_steps": "number of equal load steps (>= 1, default 1)",
        "max_iterations": f"Newton iterations per step (default {_NEWTON['snes_max_it']})",
        "rtol": f"relative Newton tolerance (default {_NEWTON['snes_rtol']})",
        "atol": f"absolute Newton tolerance (default {_NEWTON['snes_atol']})",
        "petsc": "table of extra PETSc options (without prefix)",
    },
    "part": {"where": "boolean expression of x, y selecting boundary facets"},
    "load": {
        "part": "a boundary part name",
        "type": f"one of {LOAD_TYPES}",
        "value": "number, [vx, vy], or expression(s) of x, y",
        "side": "-1 or +1 (default both)",
        "component": "0 or 1 (displacement)",
        "point": "[x, y] (point_displacement)",
    },
    "outputs": {"vtx": "write VTX fields (bool)", "png": "write pictures (bool)"},
}
TOP_LEVEL = (
    "scene",
    "mesh",
    "discretisation",
    "materials",
    "interfaces",
    "parts",
    "loads",
    "solver",
    "outputs",
)


@dataclasses.dataclass(frozen=True)
class InterfaceSpec:
    shape: str
    law: str
    inside: str
    outside: str
    params: dict
    name: str = "interface"
    friction: float | None = None
    augmentation: float = 1.0
    lbb: str = "stabilized"
    kinematics: str = "small"


@dataclasses.dataclass(frozen=True)
class LoadSpec:
    part: str | None
    type: str
    value: object
    side: int | None = None
    component: int | None = None
    point: tuple | None = None


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
    quadrature_degree: int
    materials: dict[str, Material]
    interfaces: tuple[InterfaceSpec, ...]
    parts: dict[str, str]
    loads: tuple[LoadSpec, ...]
    outputs: dict
    load_steps: int = 1
    #: PETSc options of the solver (SNES/KSP, without prefix)
    petsc_options: dict = dataclasses.field(default_factory=dict)
