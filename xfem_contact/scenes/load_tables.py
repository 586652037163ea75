"""The [[loads]] of a scene: each table checked against its type's keys, its part, the
form of its value and the stage its load path names (:func:`load_spec`). Deprecated keys
and types are read under their new names (:func:`~xfem_contact.scenes.schema.renamed`)."""

from __future__ import annotations

from xfem_contact.scenes.load_kinds import LOAD_KINDS
from xfem_contact.scenes.schema import (
    BOX_FACES,
    FIELDS_BY_DIM,
    LOAD_KEYS,
    PLANE_LOAD_TYPES,
    LoadSpec,
    SceneError,
    check_table,
    renamed,
)


def load_spec(table, where: str, known_parts: set, stages: dict, gdim: int = 2) -> LoadSpec:
    """A load from its checked table on a mesh of dimension ``gdim``: the keys of its type,
    its part, the form of its value, the stage its load path names."""
    table = renamed(table, "load", where)
    check_table(table, FIELDS_BY_DIM[gdim]["load"], where)
    kind = table["type"]
    if gdim == 3 and kind in PLANE_LOAD_TYPES:
        message = (
            f"{kind!r} is a load of 2D meshes (in the plane); on a 3D mesh give a "
            "'displacement' (of expressions of x, y, z) instead"
        )
        raise SceneError(f"{where}.type", message)
    required, optional = LOAD_KEYS[kind]
    for key in required:
        if key not in table:
            raise SceneError(f"{where}.{key}", f"required for a {kind!r} load")
    for key in table:
        if key != "type" and key not in required + optional:
            keys = ", ".join(required + optional)
            message = f"is not a key of a {kind!r} load (its keys: {keys})"
            raise SceneError(f"{where}.{key}", message)
    part = table.get("part")
    if "part" in required and part not in known_parts:
        message = f"{part!r}: no such boundary part; known: {sorted(known_parts)}"
        if gdim == 2 and part in BOX_FACES[2]:
            message += " (front and back are the z faces of a 3D box)"
        raise SceneError(f"{where}.part", message)
    if kind == "rotation" and ("value" in table) == ("angle_deg" in table):
        raise SceneError(f"{where}.value", "give the angle once: value (rad) or angle_deg")
    if "value" in table:
        LOAD_KINDS[kind].check(table["value"], "component" in table, f"{where}.value", gdim)
    path = table.get("path")
    if isinstance(path, str) and path not in stages:
        message = f"{path!r}: no such stage; known: {sorted(stages)}"
        raise SceneError(f"{where}.path", message)
    return LoadSpec(
        part,
        kind,
        table.get("value"),
        table.get("side"),
        table.get("component"),
        tuple(table["point"]) if "point" in table else None,
        tuple(table.get("centre", (0.0, 0.0))),
        path if isinstance(path, str | None) else tuple(map(tuple, path)),
        table.get("angle_deg"),
    )
