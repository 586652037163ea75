"""The [[loads]] of a scene: each table checked against its type's keys, its part, the
form of its value and the stage its load path names (:func:`load_spec`). Deprecated keys
and types are read under their new names (:func:`~xfem_contact.scenes.schema.renamed`)."""

from __future__ import annotations

from xfem_contact.scenes.load_kinds import LOAD_KINDS
from xfem_contact.scenes.schema import (
    FIELDS,
    LOAD_KEYS,
    LoadSpec,
    SceneError,
    check_table,
    renamed,
)


def load_spec(table, where: str, known_parts: set, stages: dict) -> LoadSpec:
    """A load from its checked table: the keys of its type, its part, the form of its
    value, the stage its load path names."""
    table = renamed(table, "load", where)
    check_table(table, FIELDS["load"], where)
    kind = table["type"]
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
        raise SceneError(f"{where}.part", message)
    if kind == "rotation" and ("value" in table) == ("angle_deg" in table):
        raise SceneError(f"{where}.value", "give the angle once: value (rad) or angle_deg")
    if "value" in table:
        LOAD_KINDS[kind].check(table["value"], "component" in table, f"{where}.value")
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
