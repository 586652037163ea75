"""The scene schema: allowed keys, choices and the validated scene records.

One table (:data:`FIELDS`) names every key of every table with its type, range and
meaning (:data:`SCHEMA` is its text); :func:`check_table` checks a table against it.
Errors are :class:`SceneError`: one line ``KEY: message`` naming the key path
(``interfaces[0].radius``) and the valid choices. The frozen dataclasses
(:mod:`xfem_contact.scenes.records`) are what :func:`xfem_contact.scenes.scene.load_scene`
returns.
"""

from __future__ import annotations

import warnings

from xfem_contact.mechanics.laws import CONTACT_LAWS, LBB_OPTIONS, LINEAR_LAWS, MULTIPLIER_DEGREES
from xfem_contact.mechanics.loads import BOX_FACES
from xfem_contact.mechanics.sliding.coupling import PAIRING_UPDATES
from xfem_contact.scenes.checks import (  # noqa: F401  (re-exported)
    NAME,
    Choice,
    Expression,
    Field,
    Number,
    Scalar,
    SceneError,
    Text,
    Vector,
    check_table,
    describe,
    flag,
    join,
    load_path,
    petsc_table,
    stages_table,
)
from xfem_contact.scenes.load_kinds import LOAD_KINDS
from xfem_contact.scenes.records import CrackSpec, InterfaceSpec, LoadSpec, Scene  # noqa: F401
from xfem_contact.solvers.options import LINEAR_PRESETS, defaults

_NEWTON = defaults("newton")  # the [solver] defaults are the Newton solver's

LAWS = LINEAR_LAWS + CONTACT_LAWS
#: The interface shapes of a scene on a mesh of each geometric dimension
SHAPES_BY_DIM = {
    2: ("circle", "ellipse", "line", "half-plane", "expression"),
    3: ("sphere", "ellipsoid", "plane", "cylinder", "expression"),
}
SHAPES = SHAPES_BY_DIM[2] + SHAPES_BY_DIM[3][:-1]
#: The shapes of the other dimension a shape stands for (named when it is refused)
SHAPE_ANALOGUES = {
    "circle": ("sphere", "cylinder"),
    "ellipse": ("ellipsoid",),
    "line": ("plane",),
    "half-plane": ("plane",),
    "sphere": ("circle",),
    "ellipsoid": ("ellipse",),
    "plane": ("line", "half-plane"),
    "cylinder": ("circle",),
}
LOAD_TYPES = tuple(LOAD_KINDS)
#: Load types of 2D meshes only (a rotation in the plane, a spring along the boundary's tangent)
PLANE_LOAD_TYPES = ("rotation", "tangential_spring")
KINEMATICS = ("small", "large")
CELLS = ("quadrilateral", "triangle")
CELLS_3D = ("tetrahedron", "hexahedron")
MESH_KINDS = ("rectangle", "annulus", "box", "gmsh")
#: The geometric dimension of each built-in mesh kind (a gmsh file's is the file's)
MESH_DIMENSION = {"rectangle": 2, "annulus": 2, "box": 3}
BUILTIN_PARTS = {
    "rectangle": ("left", "right", "bottom", "top", "boundary"),
    "annulus": ("inner", "outer", "boundary"),
    "box": (*(name for pair in BOX_FACES for name in pair), "boundary"),
    "gmsh": ("boundary",),  # plus the file's named (d-1)-D physical groups
}
#: Material modes on a mesh of each geometric dimension (the first is the default)
MATERIAL_MODES = {2: ("strain", "stress"), 3: ("3d",)}
#: Keys in which the interfaces of one scene must agree: they lie in one body (the
#: outside material) and share the kinematics; laws and inside materials may differ
SHARED_INTERFACE_KEYS = ("kinematics", "outside", "slave", "pairing")
#: The [mesh] keys each mesh kind reads (besides ``kind``)
MESH_KEYS = {
    "rectangle": ("corners", "cells", "cell"),
    "annulus": ("radii", "cells", "geometry_degree"),
    "box": ("corners", "cells", "cell"),
    "gmsh": ("file", "size", "cell", "geometry_degree"),
}
#: The parameters of each interface shape: (required, optional)
SHAPE_KEYS = {
    "circle": (("centre", "radius"), ()),
    "ellipse": (("centre", "axes"), ("angle", "angle_deg")),
    "line": (("point", "normal"), ()),
    "half-plane": (("point", "normal"), ()),
    "expression": (("expression",), ()),
    "sphere": (("centre", "radius"), ()),
    "ellipsoid": (("centre", "axes"), ()),
    "plane": (("point", "normal"), ()),
    "cylinder": (("point", "axis", "radius"), ()),
}
#: The shapes of a crack and their parameters: (required, optional)
CRACK_SHAPES = ("segment", "polyline", "arc", "expression")
CRACK_SHAPE_KEYS = {
    "segment": (("points",), ()),
    "polyline": (("points",), ()),
    "arc": (("centre", "radius", "angles_deg"), ()),
    "expression": (("phi", "psi"), ()),
}
#: Default rings of the stress intensity factors, in units of the tip's crack length
#: (:func:`~xfem_contact.fem.tip_scale.tip_lengths`: ``a`` for a crack of length ``2a``)
CRACK_RINGS = ((0.2, 0.6), (0.3, 0.8))
#: The keys of each load type besides ``type``: (required, optional)
LOAD_KEYS = {name: (kind.required, kind.optional) for name, kind in LOAD_KINDS.items()}


_POSITIVE = Number(0.0, open=True)
_POINT = Vector(2, Number())
_POINT_3D = Vector(3, Number())
_DEGREE = Choice((1, 2))


#: Old key -> its name today, per table (read for one more release, with a warning)
RENAMED_KEYS = {"load": {"history": "path"}, "solver": {"linear": "preset"}}
#: Old load type -> its name today (read for one more release, with a warning)
RENAMED_LOAD_TYPES = {"tangential_support": "tangential_spring"}


def renamed(table, kind: str, where: str):
    """``table`` (a ``kind`` table, e.g. ``"load"``) with its deprecated keys (and load
    type) under their new names, each with a DeprecationWarning naming the old and the
    new name; both names given is refused."""
    if not isinstance(table, dict):
        return table
    table = dict(table)
    for old, new in RENAMED_KEYS.get(kind, {}).items():
        if old in table:
            if new in table:
                raise SceneError(f"{where}.{old}", f"give it once, as {new!r} (its old name)")
            _deprecated(f"{where}.{old}", f"the key {old!r} is now {new!r}")
            table[new] = table.pop(old)
    if (
        kind == "load"
        and isinstance(table.get("type"), str)
        and table["type"] in RENAMED_LOAD_TYPES
    ):
        old, new = table["type"], RENAMED_LOAD_TYPES[table["type"]]
        _deprecated(f"{where}.type", f"the load type {old!r} is now {new!r}")
        table["type"] = new
    return table


def _deprecated(key: str, what: str) -> None:
    warnings.warn(
        f"{key}: {what}; the old name is read until the next release",
        DeprecationWarning,
        stacklevel=4,
    )


def point_list(value, key: str) -> tuple:
    """A list of at least two points [x, y] (m)."""
    if not isinstance(value, list | tuple) or len(value) < 2:
        raise SceneError(key, f"expected a list of at least 2 points [x, y], got {describe(value)}")
    return tuple(_POINT(p, join(key, i)) for i, p in enumerate(value))


def ring_list(value, key: str) -> tuple:
    """A non-empty list of rings ``[r_inf, r_sup]`` (m), ``0 <= r_inf < r_sup``."""
    if not isinstance(value, list | tuple) or not value:
        raise SceneError(key, f"expected a list of [r_inf, r_sup] pairs, got {describe(value)}")
    rings = []
    for i, pair in enumerate(value):
        r_inf, r_sup = Vector(2, Number(0.0))(pair, join(key, i))
        if not r_inf < r_sup:
            raise SceneError(join(key, i), f"r_inf must be < r_sup, got {list(pair)}")
        rings.append((float(r_inf), float(r_sup)))
    return tuple(rings)


#: Every key of every table: its check and meaning (the schema in one place)
FIELDS = {
    "scene": {
        "name": Field(NAME, "scene name (names the default output folder results/NAME)"),
        "description": Field(Text(), "free text"),
    },
    "mesh": {
        "kind": Field(Choice(MESH_KINDS), f"one of {MESH_KINDS} (box: 3D)"),
        "file": Field(Text(), "a gmsh .geo or .msh file, relative to the scene file (gmsh)"),
        "size": Field(_POSITIVE, "target cell size (m) when meshing a .geo file (gmsh)"),
        "corners": Field(Vector(2, _POINT), "[[x0, y0], [x1, y1]] (m, rectangle)"),
        "radii": Field(
            Vector(2, _POSITIVE), "[r_inner, r_outer] (m, annulus centred at the origin)"
        ),
        "cells": Field(
            Vector(2, Number(1, integer=True)),
            "cells along x and y (rectangle) or [n_radial, n_angular] (annulus)",
        ),
        "cell": Field(Choice(CELLS), f"one of {CELLS}"),
        "geometry_degree": Field(
            _DEGREE, "1 (straight cells) or 2 (curved cells: annulus, gmsh .geo)"
        ),
    },
    "discretisation": {
        "degree": Field(_DEGREE, "displacement degree 1 or 2"),
        "levelset_degree": Field(_DEGREE, "1 or 2"),
        "quadrature_degree": Field(Number(1, 30, integer=True), ">= 1 and <= 30"),
    },
    "interface": {
        "name": Field(NAME, "label (names the multiplier field)"),
        "shape": Field(Choice(SHAPES), f"one of {SHAPES}", required=True),
        "centre": Field(_POINT, "[x, y] (m), centre of a circle or an ellipse"),
        "radius": Field(_POSITIVE, "(m) > 0, radius of a circle (sphere, cylinder in 3D)"),
        "axes": Field(
            Vector(2, _POSITIVE),
            "[a, b] (m) > 0, the semi-axes of an ellipse: a along the direction at angle "
            "from the x axis, b across it",
        ),
        "angle": Field(
            Number(),
            "(rad) in [-2 pi, 2 pi], of an ellipse's axis a from the x axis, "
            "counter-clockwise; or angle_deg",
        ),
        "angle_deg": Field(Number(), "(degrees), instead of angle"),
        "point": Field(_POINT, "[x, y] (m), a point of a line or half-plane's boundary"),
        "axis": Field(
            _POINT_3D, "[ax, ay, az], non-zero, any length: the direction of a cylinder's axis (3D)"
        ),
        "normal": Field(
            _POINT,
            "[nx, ny], non-zero, any length: the normal of a line, pointing to side +1 (outside)",
        ),
        "expression": Field(
            Expression(),
            "phi(x, y) of x, y in m: the interface is phi = 0, side -1 (inside) phi < 0",
        ),
        "law": Field(Choice(LAWS), f"one of {LAWS}"),
        "friction": Field(Number(0.0), "Coulomb coefficient >= 0"),
        "augmentation": Field(_POSITIVE, "> 0"),
        "lbb": Field(Choice(LBB_OPTIONS), " | ".join(LBB_OPTIONS)),
        "multiplier_degree": Field(
            Choice(MULTIPLIER_DEGREES),
            "1 (P1 multiplier on the cut cells' vertices; default) | 2 (P2: their vertices "
            "and edge nodes; small kinematics)",
        ),
        "kinematics": Field(Choice(KINEMATICS), f"one of {KINEMATICS}"),
        "slave": Field(Choice((-1, 1)), "slave side -1 or +1 (large kinematics; default -1)"),
        "master": Field(Choice((-1, 1)), "master side, the other one (large kinematics)"),
        "pairing": Field(
            Choice(PAIRING_UPDATES), f"one of {PAIRING_UPDATES} (large kinematics; default iterate)"
        ),
        "inside": Field(Text(), "material of side -1"),
        "outside": Field(Text(), "material of side +1"),
    },
    "crack": {
        "name": Field(NAME, "label (names the crack's multiplier field and outputs)"),
        "shape": Field(Choice(CRACK_SHAPES), f"one of {CRACK_SHAPES}", required=True),
        "points": Field(
            point_list,
            "[[x, y], ...] (m): 2 for a segment, >= 2 for a polyline; an end inside the "
            "body is a tip, one on or beyond its boundary an edge crack's mouth",
        ),
        "centre": Field(_POINT, "[x, y] (m), centre of an arc"),
        "radius": Field(_POSITIVE, "(m) > 0, radius of an arc"),
        "angles_deg": Field(
            Vector(2, Number()),
            "[start, end] polar angles (degrees, counter-clockwise from the x axis, about "
            "centre) of an arc's ends, |end - start| < 360",
        ),
        "phi": Field(
            Expression(), "normal level set phi(x, y): the crack is phi = 0 where psi < 0"
        ),
        "psi": Field(Expression(), "tangential level set psi(x, y), 0 at the tips"),
        "law": Field(Choice(LAWS), f"law of the lips: one of {LAWS} (default free)"),
        "friction": Field(Number(0.0), "Coulomb coefficient >= 0"),
        "augmentation": Field(_POSITIVE, "> 0"),
        "lbb": Field(Choice(LBB_OPTIONS), " | ".join(LBB_OPTIONS)),
        "tip_radius": Field(
            _POSITIVE,
            "tip enrichment radius (m); below the tip cells' size, the tip cells' nodes "
            "with a warning (default: half the tip's crack length, at least the tip "
            "cells' size)",
        ),
        "rings": Field(
            ring_list,
            "[[r_inf, r_sup], ...] (m) of the K integrals (default: "
            f"{[list(r) for r in CRACK_RINGS]} tip's crack lengths, r_sup kept off the "
            "boundary)",
        ),
        "material": Field(Text(), "material of the cracked body (default: the first)"),
        "reference_K": Field(
            Vector(2, Number()),
            "[K_I, K_II] (Pa m^1/2) to compare every tip's K with (printed beside it, with "
            "the difference)",
        ),
        "reference_source": Field(
            Text(), "where reference_K comes from and what it includes (e.g. the plate's size)"
        ),
    },
    "material": {
        "E": Field(_POSITIVE, "Young's modulus (Pa) > 0", required=True),
        "nu": Field(Number(-1.0, 0.5, open=True), "Poisson ratio in (-1, 0.5)", required=True),
        "plane": Field(
            Choice(MATERIAL_MODES[2] + MATERIAL_MODES[3]),
            "strain | stress (2D meshes, default strain) | 3d (3D meshes, the default there)",
        ),
    },
    "solver": {
        "load_steps": Field(
            Number(1, 10_000, integer=True), "number of equal load steps (>= 1, default 1)"
        ),
        "end_time": Field(
            _POSITIVE,
            "pseudo-time of the last step (steps at k end_time / load_steps; default: the "
            "last time of any load path or stage, at least 1)",
        ),
        "max_iterations": Field(
            Number(1, 10_000, integer=True),
            f"Newton iterations per step (default {_NEWTON['snes_max_it']})",
        ),
        "rtol": Field(_POSITIVE, f"relative Newton tolerance (default {_NEWTON['snes_rtol']})"),
        "atol": Field(_POSITIVE, f"absolute Newton tolerance (default {_NEWTON['snes_atol']})"),
        "preset": Field(
            Choice(tuple(LINEAR_PRESETS)),
            f"linear solver of the Newton steps: one of {tuple(LINEAR_PRESETS)} (default direct)",
        ),
        "petsc": Field(petsc_table, "table of extra PETSc options (without prefix)"),
    },
    "part": {
        "where": Field(
            Expression("boolean"), "boolean expression of x, y selecting boundary facets", True
        )
    },
    "load": {
        "part": Field(Text(), "a boundary part name"),
        "type": Field(Choice(LOAD_TYPES), f"one of {LOAD_TYPES}", required=True),
        "value": Field(
            lambda value, key: value,
            "number, [vx, vy], or expression(s) of x, y (m): Pa for a pressure (positive "
            "pushes) or traction, N/m^3 for a body force, m for a displacement, rad for a "
            "rotation (or angle_deg), Pa/m for a tangential_spring's stiffness",
        ),
        "side": Field(Choice((-1, 1)), "-1 or +1 (default both)"),
        "component": Field(Choice((0, 1)), "0 (x) or 1 (y): the one prescribed (displacement)"),
        "point": Field(_POINT, "[x, y] (m), the node held (point_displacement)"),
        "centre": Field(_POINT, "[x, y] (m), centre of a rotation (default [0, 0])"),
        "angle_deg": Field(Number(), "rotation angle in degrees (instead of value, in rad)"),
        "path": Field(
            load_path,
            "load path: [[t, factor], ...] (piecewise linear in pseudo-time t) or a stage "
            "name (default: factor = t)",
        ),
    },
    "outputs": {
        "vtx": Field(flag, "write VTX fields (bool)"),
        "png": Field(flag, "write pictures (bool)"),
    },
}
#: What differs in 3D: the keys of :data:`FIELDS` that hold points, vectors, components
#: or expressions of the coordinates
_FIELDS_3D = {
    "mesh": {
        "corners": Field(
            Vector(2, _POINT_3D), "[[x0, y0, z0], [x1, y1, z1]] (m, box; default the unit cube)"
        ),
        "cells": Field(
            Vector(3, Number(1, integer=True)), "cells along x, y and z (box; default [8, 8, 8])"
        ),
        "cell": Field(Choice(CELLS_3D), f"one of {CELLS_3D} (default tetrahedron)"),
    },
    "interface": {
        "centre": Field(_POINT_3D, "[x, y, z] (m), centre of a sphere or an ellipsoid"),
        "axes": Field(
            Vector(3, _POSITIVE), "[a, b, c] (m) > 0, the semi-axes of an ellipsoid along x, y, z"
        ),
        "point": Field(_POINT_3D, "[x, y, z] (m), a point of a plane or of a cylinder's axis"),
        "normal": Field(
            _POINT_3D,
            "[nx, ny, nz], non-zero, any length: the normal of a plane, pointing to side +1",
        ),
        "expression": Field(
            Expression(dim=3),
            "phi(x, y, z) of x, y, z in m: the interface is phi = 0, side -1 (inside) phi < 0",
        ),
    },
    "part": {
        "where": Field(
            Expression("boolean", dim=3),
            "boolean expression of x, y, z selecting boundary facets",
            True,
        )
    },
    "load": {
        "component": Field(Choice((0, 1, 2)), "0 (x), 1 (y) or 2 (z): the one prescribed"),
        "point": Field(_POINT_3D, "[x, y, z] (m), the node held (point_displacement)"),
    },
}
#: The tables of keys on a mesh of each geometric dimension
FIELDS_BY_DIM = {
    2: FIELDS,
    3: {table: fields | _FIELDS_3D.get(table, {}) for table, fields in FIELDS.items()},
}
#: The meaning of every key of every table (the text of :data:`FIELDS`)
SCHEMA = {table: {key: f.doc for key, f in fields.items()} for table, fields in FIELDS.items()}
TOP_LEVEL = (
    "scene",
    "stages",
    "mesh",
    "discretisation",
    "materials",
    "interfaces",
    "cracks",
    "parts",
    "loads",
    "solver",
    "outputs",
)
