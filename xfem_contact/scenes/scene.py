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

import pathlib
import tomllib

from xfem_contact.mechanics.materials import Material
from xfem_contact.scenes.expressions import compile_expression
from xfem_contact.scenes.schema import (  # noqa: F401  (re-exported)
    BUILTIN_PARTS,
    CELLS,
    KINEMATICS,
    LAWS,
    LOAD_TYPES,
    MESH_KINDS,
    SCHEMA,
    SHAPES,
    SHARED_INTERFACE_KEYS,
    TOP_LEVEL,
    InterfaceSpec,
    LoadSpec,
    Scene,
)


def _check_keys(table: dict, allowed, where: str) -> None:
    unknown = sorted(set(table) - set(allowed))
    if unknown:
        raise ValueError(f"Unknown key(s) {unknown} in [{where}]; valid: {sorted(allowed)}")


def _choice(value, choices, where: str):
    if value not in choices:
        raise ValueError(f"{where} = {value!r} is not valid; choose one of {list(choices)}")
    return value


def load_scene(
    source: str | pathlib.Path | dict, folder: str | pathlib.Path | None = None
) -> Scene:
    """Read and validate a scene from a TOML file path or an already parsed dict.

    ``folder``: where relative file names (``mesh.file``) are looked up; default
    the scene file's folder, or the working directory for a dict.
    """
    if isinstance(source, dict):
        data = source
        folder = pathlib.Path(folder or ".")
    else:
        with open(source, "rb") as f:
            data = tomllib.load(f)
        folder = pathlib.Path(folder or pathlib.Path(source).parent)
    _check_keys(data, TOP_LEVEL, "top level")
    head = data.get("scene", {})
    _check_keys(head, SCHEMA["scene"], "scene")
    mesh = data.get("mesh", {})
    _check_keys(mesh, SCHEMA["mesh"], "mesh")
    disc = data.get("discretisation", {})
    _check_keys(disc, SCHEMA["discretisation"], "discretisation")
    degree = _choice(disc.get("degree", 2), (1, 2), "discretisation.degree")
    ls_degree = _choice(disc.get("levelset_degree", 2), (1, 2), "discretisation.levelset_degree")
    q_degree = int(disc.get("quadrature_degree", 6))
    if q_degree < 1:
        raise ValueError(f"discretisation.quadrature_degree must be >= 1, got {q_degree}")

    materials = {}
    for name, table in data.get("materials", {}).items():
        _check_keys(table, SCHEMA["material"], f"materials.{name}")
        try:
            materials[name] = Material(
                float(table["E"]), float(table["nu"]), table.get("plane", "strain")
            )
        except KeyError as missing:
            raise ValueError(f"materials.{name} needs {missing}") from None
    if not materials:
        raise ValueError("The scene defines no material ([materials.NAME] with E and nu)")

    interfaces = []
    for k, table in enumerate(data.get("interfaces", [])):
        where = f"interfaces[{k}]"
        _check_keys(table, SCHEMA["interface"], where)
        shape = _choice(table.get("shape"), SHAPES, f"{where}.shape")
        law = _choice(table.get("law", "bonded"), LAWS, f"{where}.law")
        kinematics = _choice(table.get("kinematics", "small"), KINEMATICS, f"{where}.kinematics")
        if kinematics == "large":
            raise NotImplementedError(
                f"{where}.kinematics = 'large' (large sliding with slave/master pairing) is "
                "not available yet; use 'small'"
            )
        for side_key in ("inside", "outside"):
            name = table.get(side_key, next(iter(materials)))
            if name not in materials:
                raise ValueError(
                    f"{where}.{side_key} = {name!r}: no such material; defined: {sorted(materials)}"
                )
        if shape == "expression":
            compile_expression(table.get("expression", ""), f"{where}.expression")
        params = {
            k2: v
            for k2, v in table.items()
            if k2 in ("centre", "radius", "axes", "angle", "point", "normal", "expression")
        }
        interfaces.append(
            InterfaceSpec(
                shape=shape,
                law=law,
                params=params,
                name=table.get("name", f"interface{k}"),
                inside=table.get("inside", next(iter(materials))),
                outside=table.get("outside", next(iter(materials))),
                friction=table.get("friction"),
                augmentation=float(table.get("augmentation", 1.0)),
                lbb=table.get("lbb", "stabilized"),
                kinematics=kinematics,
            )
        )
    _check_shared(interfaces)

    parts = {}
    for name, table in data.get("parts", {}).items():
        _check_keys(table, SCHEMA["part"], f"parts.{name}")
        compile_expression(table.get("where", ""), f"parts.{name}.where")
        parts[name] = table["where"]

    loads = []
    mesh_kind = _choice(mesh.get("kind", "rectangle"), MESH_KINDS, "mesh.kind")
    mesh_file, size = _gmsh_source(mesh, mesh_kind, folder)
    known_parts = set(BUILTIN_PARTS[mesh_kind]) | set(parts)
    if mesh_file is not None:
        from xfem_contact.io.gmsh import physical_parts

        known_parts |= set(physical_parts(mesh_file))
    for k, table in enumerate(data.get("loads", [])):
        where = f"loads[{k}]"
        _check_keys(table, SCHEMA["load"], where)
        kind = _choice(table.get("type"), LOAD_TYPES, f"{where}.type")
        part = table.get("part")
        if kind not in ("point_displacement", "body_force"):
            if part not in known_parts:
                raise ValueError(
                    f"{where}.part = {part!r}: no such boundary part; known: {sorted(known_parts)}"
                )
        side = table.get("side")
        if side is not None:
            _choice(side, (-1, 1), f"{where}.side")
        if "value" not in table:
            raise ValueError(f"{where} needs a value")
        loads.append(
            LoadSpec(
                part,
                kind,
                table["value"],
                side,
                table.get("component"),
                tuple(table["point"]) if "point" in table else None,
            )
        )

    solver = data.get("solver", {})
    _check_keys(solver, SCHEMA["solver"], "solver")
    load_steps = solver.get("load_steps", 1)
    if isinstance(load_steps, bool) or not isinstance(load_steps, int) or load_steps < 1:
        raise ValueError(f"solver.load_steps must be an integer >= 1, got {load_steps!r}")
    petsc = _petsc_options(solver)

    outputs = data.get("outputs", {})
    _check_keys(outputs, SCHEMA["outputs"], "outputs")
    cells = tuple(mesh.get("cells", [20, 20]))
    if len(cells) != 2 or min(cells) < 1:
        raise ValueError(f"mesh.cells must be [nx, ny] with positive entries, got {cells}")
    return Scene(
        name=head.get("name", "scene"),
        kind=mesh_kind,
        file=mesh_file,
        size=size,
        radii=tuple(map(float, mesh.get("radii", [1.0, 2.0]))),
        geometry_degree=_choice(mesh.get("geometry_degree", 1), (1, 2), "mesh.geometry_degree"),
        corners=tuple(tuple(map(float, c)) for c in mesh.get("corners", [[0, 0], [1, 1]])),
        cells=cells,
        cell=_choice(mesh.get("cell", "quadrilateral"), CELLS, "mesh.cell"),
        degree=degree,
        levelset_degree=ls_degree,
        quadrature_degree=q_degree,
        materials=materials,
        interfaces=tuple(interfaces),
        parts=parts,
        loads=tuple(loads),
        outputs={"vtx": True, "png": True, **outputs},
        load_steps=load_steps,
        petsc_options=petsc,
    )


def _check_shared(interfaces: list[InterfaceSpec]) -> None:
    """Interfaces of one scene lie in one body: they must agree in the outside
    material and the kinematics (laws, their options and inside materials may differ)."""
    for k, spec in enumerate(interfaces[1:], start=1):
        for key in SHARED_INTERFACE_KEYS:
            mine, first = getattr(spec, key), getattr(interfaces[0], key)
            if mine != first:
                raise NotImplementedError(
                    f"interfaces[{k}].{key} = {mine!r} differs from interfaces[0].{key} = "
                    f"{first!r}: the interfaces of one scene lie in one body and must share "
                    f"{list(SHARED_INTERFACE_KEYS)}"
                )
    names = [spec.name for spec in interfaces]
    if len(set(names)) != len(names):
        raise ValueError(f"Interface names must be unique, got {names}")


def _gmsh_source(mesh: dict, kind: str, folder: pathlib.Path):
    """(file, size) of a gmsh mesh, checked; (None, None) for built-in meshes."""
    if kind != "gmsh":
        for key in ("file", "size"):
            if key in mesh:
                raise ValueError(f"mesh.{key} is for mesh.kind = 'gmsh', not {kind!r}")
        return None, None
    if "file" not in mesh:
        raise ValueError("mesh.kind = 'gmsh' needs mesh.file (a .geo or .msh file)")
    path = (folder / mesh["file"]).resolve()
    if path.suffix not in (".geo", ".msh"):
        raise ValueError(f"mesh.file = {mesh['file']!r}: expected a .geo or .msh file")
    if not path.exists():
        raise ValueError(f"mesh.file = {mesh['file']!r}: no such file ({path})")
    if path.suffix == ".msh":
        given = sorted({"size", "cell", "geometry_degree"} & set(mesh))
        if given:
            raise ValueError(
                f"mesh.{given[0]} is read from the .msh file itself; give it only with a .geo"
            )
    size = mesh.get("size")
    if size is not None and not float(size) > 0.0:
        raise ValueError(f"mesh.size must be > 0 (m), got {size!r}")
    return path, None if size is None else float(size)


def _petsc_options(solver: dict) -> dict:
    """PETSc options of the [solver] table (Newton tolerances and the raw options)."""
    options = {}
    for key, option in (
        ("max_iterations", "snes_max_it"),
        ("rtol", "snes_rtol"),
        ("atol", "snes_atol"),
    ):
        if key in solver:
            value = solver[key]
            if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
                raise ValueError(f"solver.{key} must be a positive number, got {value!r}")
            options[option] = value
    raw = solver.get("petsc", {})
    if not isinstance(raw, dict):
        raise ValueError("solver.petsc must be a table of PETSc options")
    for key, value in raw.items():
        if not isinstance(value, str | int | float | bool):
            raise ValueError(f"solver.petsc.{key} must be a string, number or boolean")
    return options | raw


def bundled_scenes() -> dict[str, pathlib.Path]:
    """The scenes shipped with the package, by name."""
    folder = pathlib.Path(__file__).parent
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}
