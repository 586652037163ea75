"""Keys that [[interfaces]] and [[cracks]] tables share: the parameters of a shape and the
options of a law, each checked against what the shape or the law takes."""

from __future__ import annotations

from xfem_contact.mechanics.laws import LAW_OPTIONS
from xfem_contact.scenes.checks import SceneError


def shape_parameters(table: dict, where: str, shape_keys: dict) -> dict:
    """The parameters of ``table["shape"]`` in ``table``, given ``shape_keys`` (shape to
    (required, optional) keys): a missing required one or another shape's is an error."""
    shape = table["shape"]
    required, optional = shape_keys[shape]
    parameters = ", ".join(required + optional)
    for key in required:
        if key not in table:
            message = f"required for shape {shape!r} (its parameters: {parameters})"
            raise SceneError(f"{where}.{key}", message)
    for key in sorted({k for keys in shape_keys.values() for k in keys[0] + keys[1]}):
        if key in table and key not in required + optional:
            message = f"is not a parameter of shape {shape!r} (its parameters: {parameters})"
            raise SceneError(f"{where}.{key}", message)
    return {k: table[k] for k in required + optional if k in table}


#: The law options a table may give
LAW_KEYS = ("friction", "augmentation", "lbb", "multiplier_degree")


def law_options(table: dict, where: str, law: str) -> dict:
    """The :data:`LAW_KEYS` of ``law`` in ``table`` (None where not given): Coulomb needs
    its friction; an option the law does not take is an error."""
    if law == "coulomb" and "friction" not in table:
        raise SceneError(f"{where}.friction", "required for law 'coulomb' (coefficient >= 0)")
    for key in LAW_KEYS:
        if key in table and key not in LAW_OPTIONS[law]:
            options = ", ".join(LAW_OPTIONS[law]) or "none"
            raise SceneError(
                f"{where}.{key}", f"is not an option of law {law!r} (its options: {options})"
            )
    return {key: table.get(key) for key in LAW_KEYS}
