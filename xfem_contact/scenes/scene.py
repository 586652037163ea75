"""Scenes: a declarative description of a simulation, loadable from TOML.

A scene names the mesh, the interfaces (level sets) with their laws, the
materials of each side, boundary conditions and loads, and the discretisation.
:func:`load_scene` validates everything before anything is built; errors name
the key and the valid choices. :func:`xfem_contact.scenes.run.run` then builds
*only the effects the scene names* (no interface: plain elasticity, no cut;
``free``/``bonded``: one linear solve; contact laws: SNES).

Example (TOML)::

    [mesh]
    corners = [[0.0, 0.0], [1.0, 1.0]]
    cells = [20, 20]
    cell = "quadrilateral"

    [materials.rubber]
    E = 100e6
    nu = 0.0

    [[interfaces]]
    shape = "circle"
    centre = [0.5, 0.5]
    radius = 0.2
    law = "sticking"
    inside = "rubber"
    outside = "rubber"

    [[loads]]
    part = "top"
    type = "pressure"
    value = 2.0
"""

from __future__ import annotations

import math
import pathlib
import re
import tomllib

from xfem_contact.mechanics.laws import LINEAR_LAWS, SLIDING_LAWS
from xfem_contact.mechanics.laws.sliding import SLIDING_LBB
from xfem_contact.mechanics.materials import Material
from xfem_contact.scenes.checks import material_name
from xfem_contact.scenes.crack_tables import crack_spec, shared_crack_keys
from xfem_contact.scenes.load_tables import load_spec
from xfem_contact.scenes.schema import (  # noqa: F401  (re-exported)
    BUILTIN_PARTS,
    CELLS,
    FIELDS,
    FIELDS_BY_DIM,
    KINEMATICS,
    LAWS,
    LOAD_KEYS,
    LOAD_TYPES,
    MATERIAL_MODES,
    MESH_DIMENSION,
    MESH_KEYS,
    MESH_KINDS,
    SCHEMA,
    SHAPE_ANALOGUES,
    SHAPE_KEYS,
    SHAPES,
    SHAPES_BY_DIM,
    SHARED_INTERFACE_KEYS,
    TOP_LEVEL,
    InterfaceSpec,
    LoadSpec,
    Number,
    Scalar,
    Scene,
    SceneError,
    Vector,
    check_table,
    describe,
    join,
    renamed,
    stages_table,
)
from xfem_contact.scenes.table_keys import law_options, shape_parameters
from xfem_contact.solvers.options import preset


def read_toml(path: str | pathlib.Path) -> dict:
    """The parsed TOML file at ``path``; a syntax error is a :class:`SceneError` naming
    the line and column. Raises ``OSError`` when the file cannot be read."""
    with open(path, "rb") as f:
        raw = f.read()
    try:
        return tomllib.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as error:
        raise SceneError("file", f"not UTF-8 text (byte {error.start}: {error.reason})") from None
    except tomllib.TOMLDecodeError as error:
        found = re.fullmatch(r"(.*) \((?:at )?(line \d+, column \d+|end of document)\)", str(error))
        where, message = (found[2], found[1]) if found else ("file", str(error))
        raise SceneError(where, f"TOML syntax error: {message}") from None
    except RecursionError:
        raise SceneError("file", "TOML nested too deeply") from None


def _tables(value, key: str, listed: bool) -> list[tuple[str, str | int, object]]:
    """(key path, name or index, table) of the tables of ``[key.NAME]`` (a table of
    tables) or ``[[key]]`` (``listed``: a list of tables); each checked by its caller."""
    if listed:
        if not isinstance(value, list | tuple):
            raise SceneError(key, f"expected a list of tables ([[{key}]]), got {describe(value)}")
        return [(join(key, k), k, table) for k, table in enumerate(value)]
    if not isinstance(value, dict):
        raise SceneError(key, f"expected a table of tables ([{key}.NAME]), got {describe(value)}")
    return [(join(key, name), name, table) for name, table in value.items()]


def load_scene(
    source: str | pathlib.Path | dict, folder: str | pathlib.Path | None = None
) -> Scene:
    """Read and validate a scene from a TOML file path or an already parsed dict.

    ``folder``: where relative file names (``mesh.file``) are looked up; default
    the scene file's folder, or the working directory for a dict.

    Raises:
        SceneError: (a ``ValueError``) one line ``KEY: message`` naming the key path
            (``interfaces[0].radius``; ``line L, column C`` for a TOML syntax error),
            with the valid choices where there are some.
        NotImplementedError: ``KEY: message`` for a valid choice not available yet.
    """
    if isinstance(source, dict):
        data = source
        folder = pathlib.Path(folder or ".")
    else:
        data = read_toml(source)
        folder = pathlib.Path(folder or pathlib.Path(source).parent)
    if not isinstance(data, dict):
        raise SceneError("file", f"expected a table of scene keys, got {describe(data)}")
    unknown = [key for key in data if key not in TOP_LEVEL]
    if unknown:
        raise SceneError(join("", unknown[0]), f"unknown key; valid: {list(TOP_LEVEL)}")
    head = check_table(data.get("scene", {}), FIELDS["scene"], "scene")
    mesh = _mesh(data.get("mesh", {}), folder)
    gdim = mesh["gdim"]
    fields = FIELDS_BY_DIM[gdim]
    disc = check_table(data.get("discretisation", {}), FIELDS["discretisation"], "discretisation")

    materials = {}
    for where, name, table in _tables(data.get("materials", {}), "materials", listed=False):
        check_table(table, FIELDS["material"], where)
        materials[name] = Material(
            float(table["E"]), float(table["nu"]), _material_mode(table, where, gdim)
        )
    if not materials:
        raise SceneError("materials", "the scene defines no material ([materials.NAME] E, nu)")
    interfaces = [
        _interface(table, k, materials, gdim)
        for _, k, table in _tables(data.get("interfaces", []), "interfaces", listed=True)
    ]
    _check_shared(interfaces)
    cracks = [
        crack_spec(table, k, materials)
        for _, k, table in _tables(data.get("cracks", []), "cracks", listed=True)
    ]
    if cracks and gdim == 3:
        raise NotImplementedError("cracks: a scene's cracks are 2D; this mesh is 3D")
    shared_crack_keys(cracks, interfaces)

    parts = {}
    for where, name, table in _tables(data.get("parts", {}), "parts", listed=False):
        parts[name] = check_table(table, fields["part"], where)["where"]
    known_parts = set(BUILTIN_PARTS[mesh["kind"]]) | set(parts)
    if mesh["file"] is not None:
        from xfem_contact.io.gmsh import physical_parts

        try:
            known_parts |= set(physical_parts(mesh["file"]))
        except (OSError, ValueError) as error:
            raise SceneError("mesh.file", " ".join(str(error).split())) from None
    stages = stages_table(data.get("stages", {}), "stages")
    loads = [
        load_spec(table, where, known_parts, stages, gdim)
        for where, _, table in _tables(data.get("loads", []), "loads", listed=True)
    ]

    solver = renamed(data.get("solver", {}), "solver", "solver")
    solver = check_table(solver, FIELDS["solver"], "solver")
    outputs = check_table(data.get("outputs", {}), FIELDS["outputs"], "outputs")
    return Scene(
        name=head.get("name", "scene"),
        **mesh,
        degree=disc.get("degree", 2),
        levelset_degree=disc.get("levelset_degree", 2),
        quadrature_degree=disc.get("quadrature_degree"),
        materials=materials,
        interfaces=tuple(interfaces),
        parts=parts,
        loads=tuple(loads),
        outputs={"vtx": True, "png": True, **outputs},
        load_steps=solver.get("load_steps", 1),
        stages=stages,
        end_time=solver.get("end_time"),
        petsc_options=_petsc_options(solver),
        cracks=tuple(cracks),
    )


def _mesh(mesh, folder: pathlib.Path) -> dict:
    """The mesh fields of a :class:`Scene` from the checked [mesh] table, with its
    geometric dimension ``gdim`` (its kind's, or a gmsh file's)."""
    if not isinstance(mesh, dict):
        check_table(mesh, FIELDS["mesh"], "mesh")  # raises
    kind = FIELDS["mesh"]["kind"].check(mesh.get("kind", "rectangle"), "mesh.kind")
    if "file" in mesh:
        FIELDS["mesh"]["file"].check(mesh["file"], "mesh.file")
    path, gdim = _gmsh_source(mesh, kind, folder), MESH_DIMENSION.get(kind)
    if gdim is None:
        from xfem_contact.io.gmsh import dimension

        try:
            gdim = dimension(path)
        except (OSError, ValueError) as error:
            raise SceneError("mesh.file", " ".join(str(error).split())) from None
    check_table(mesh, FIELDS_BY_DIM[gdim]["mesh"], "mesh")
    for key in mesh:
        if key != "kind" and key not in MESH_KEYS[kind]:
            kinds = [k for k, keys in MESH_KEYS.items() if key in keys]
            message = f"is for mesh.kind = {' or '.join(map(repr, kinds))}, not {kind!r}"
            raise SceneError(f"mesh.{key}", message)
    if gdim == 3:  # the defaults in 3D (each key's doc says it)
        mesh = {"corners": [[0, 0, 0], [1, 1, 1]], "cells": [8, 8, 8], "cell": "tetrahedron"} | mesh
    corners = tuple(tuple(map(float, c)) for c in mesh.get("corners", [[0, 0], [1, 1]]))
    if not all(high > low for low, high in zip(*corners, strict=True)):
        where = "right of and above" if gdim == 2 else "beyond (along x, y and z)"
        message = f"the second corner must lie {where} the first, got {mesh['corners']}"
        raise SceneError("mesh.corners", message)
    radii = tuple(map(float, mesh.get("radii", [1.0, 2.0])))
    if not radii[0] < radii[1]:
        raise SceneError("mesh.radii", f"r_inner must be < r_outer, got {list(radii)}")
    size = mesh.get("size")
    return {
        "kind": kind,
        "file": path,
        "size": None if size is None else float(size),
        "corners": corners,
        "radii": radii,
        "geometry_degree": mesh.get("geometry_degree", 1),
        "cells": tuple(mesh.get("cells", [20, 20])),
        "cell": mesh.get("cell", "quadrilateral"),
        "gdim": gdim,
    }


def _material_mode(table: dict, where: str, gdim: int) -> str:
    """The mode of a checked material table on a mesh of dimension ``gdim`` (default:
    plane strain in 2D, 3d in 3D); a mode of the other dimension is refused."""
    mode = table.get("plane", "strain") if gdim == 2 else table.get("plane", "3d")
    if mode not in MATERIAL_MODES[gdim]:
        message = (
            f"{mode!r} is not a mode of a {gdim}D mesh; valid there: "
            f"{list(MATERIAL_MODES[gdim])} (the default {MATERIAL_MODES[gdim][0]!r})"
        )
        raise SceneError(f"{where}.plane", message)
    return mode


def _interface(table, k: int, materials: dict, gdim: int = 2) -> InterfaceSpec:
    """Interface ``k`` from its checked table on a mesh of dimension ``gdim``: the
    parameters of its shape, its law's."""
    where = f"interfaces[{k}]"
    _check_shape(table, where, gdim)
    check_table(table, FIELDS_BY_DIM[gdim]["interface"], where)
    shape = table["shape"]
    params = shape_parameters(table, where, SHAPE_KEYS)
    if gdim == 3:
        _check_in_3d(table, where)
    if "angle" in table and "angle_deg" in table:
        raise SceneError(f"{where}.angle_deg", "give the angle once: angle (rad) or angle_deg")
    if abs(table.get("angle", 0.0)) > 2.0 * math.pi:
        message = f"is in radians ({table['angle']} rad is more than a turn); use angle_deg"
        raise SceneError(f"{where}.angle", message)
    for key in ("normal", "axis"):
        if key in table and not 0.0 < math.hypot(*table[key]) < math.inf:
            raise SceneError(f"{where}.{key}", f"must be a non-zero vector, got {table[key]}")
    law = table.get("law", "bonded")
    options = law_options(table, where, law)
    kinematics = table.get("kinematics", "small")
    slave = _sides(table, kinematics, where)
    if kinematics == "large":
        if law not in SLIDING_LAWS + LINEAR_LAWS:
            message = (
                f"{law!r} is not available in large sliding (kinematics = 'large'); "
                f"valid: {SLIDING_LAWS + LINEAR_LAWS}"
            )
            raise SceneError(f"{where}.law", message)
        if law in SLIDING_LAWS and table.get("lbb", "stabilized") not in SLIDING_LBB:
            message = f"{table['lbb']!r} is not available in large sliding; valid: {SLIDING_LBB}"
            raise SceneError(f"{where}.lbb", message)
    inside, outside = (material_name(table, key, where, materials) for key in ("inside", "outside"))
    return InterfaceSpec(
        shape=shape,
        law=law,
        params=params,
        name=table.get("name", f"interface{k}"),
        inside=inside,
        outside=outside,
        **options,
        kinematics=kinematics,
        slave=slave,
        pairing=table.get("pairing", "iterate"),
    )


def _check_shape(table, where: str, gdim: int) -> None:
    """Refuse a shape of the other dimension (``circle`` on a 3D mesh, ``sphere`` on a 2D
    one), naming its analogues and the valid shapes."""
    shape = table.get("shape") if isinstance(table, dict) else None
    valid = SHAPES_BY_DIM[gdim]
    if not isinstance(shape, str) or shape not in SHAPES or shape in valid:
        return  # checked with the table
    other = 5 - gdim
    analogues = " or ".join(repr(s) for s in SHAPE_ANALOGUES[shape])
    message = (
        f"{shape!r} is a {other}D shape and the mesh is {gdim}D: use {analogues}; the "
        f"shapes of a {gdim}D mesh: {list(valid)}"
    )
    raise SceneError(f"{where}.shape", message)


def _check_in_3d(table, where: str) -> None:
    """Refuse the law options and kinematics of an interface that exist in 2D only."""
    if table.get("kinematics") == "large":
        message = "'large' (large sliding) is 2D only; valid on a 3D mesh: ['small']"
        raise SceneError(f"{where}.kinematics", message)


def _sides(table, kinematics: str, where: str) -> int:
    """The slave side of an interface table (large kinematics only; the master is the
    other side)."""
    for key in ("slave", "master", "pairing"):
        if key in table and kinematics != "large":
            raise SceneError(f"{where}.{key}", "only with kinematics = 'large' (large sliding)")
    slave = table.get("slave", -table.get("master", 1))
    if "master" in table and table["master"] == slave:
        message = f"slave and master are both side {slave}: the master is the other side"
        raise SceneError(f"{where}.master", message)
    return slave


def _check_shared(interfaces: list[InterfaceSpec]) -> None:
    """Interfaces of one scene lie in one body: they must agree in the outside
    material and the kinematics (laws, their options and inside materials may differ)."""
    for k, spec in enumerate(interfaces[1:], start=1):
        for key in SHARED_INTERFACE_KEYS:
            mine, first = getattr(spec, key), getattr(interfaces[0], key)
            if mine != first:
                raise NotImplementedError(
                    f"interfaces[{k}].{key}: {mine!r} differs from interfaces[0].{key} = "
                    f"{first!r}: the interfaces of one scene lie in one body and must share "
                    f"{list(SHARED_INTERFACE_KEYS)}"
                )
    names = [spec.name for spec in interfaces]
    for k, name in enumerate(names):
        if name in names[:k]:
            message = f"{name!r} names interfaces[{names.index(name)}] too; names must be unique"
            raise SceneError(f"interfaces[{k}].name", message)


def _gmsh_source(mesh: dict, kind: str, folder: pathlib.Path) -> pathlib.Path | None:
    """The file of a gmsh mesh, checked; None for built-in meshes."""
    if kind != "gmsh":
        return None
    if "file" not in mesh:
        raise SceneError("mesh.file", "required for mesh.kind = 'gmsh' (a .geo or .msh file)")
    path = (folder / mesh["file"]).resolve()
    if path.suffix not in (".geo", ".msh"):
        raise SceneError("mesh.file", f"{mesh['file']!r}: expected a .geo or .msh file")
    if not path.is_file():
        raise SceneError("mesh.file", f"{mesh['file']!r}: no such file ({path})")
    if path.suffix == ".msh":
        given = sorted({"size", "cell", "geometry_degree"} & set(mesh))
        if given:
            message = "is read from the .msh file itself; give it only with a .geo"
            raise SceneError(f"mesh.{given[0]}", message)
    return path


def _petsc_options(solver: dict) -> dict:
    """PETSc options of the checked [solver] table: the linear-solver preset, the Newton
    tolerances and the raw options, later ones winning."""
    options = preset(solver.get("preset", "direct")) | {
        option: solver[key]
        for key, option in (
            ("max_iterations", "snes_max_it"),
            ("rtol", "snes_rtol"),
            ("atol", "snes_atol"),
        )
        if key in solver
    }
    return options | solver.get("petsc", {})


def bundled_scenes() -> dict[str, pathlib.Path]:
    """The scenes shipped with the package, by name."""
    folder = pathlib.Path(__file__).parent
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}
