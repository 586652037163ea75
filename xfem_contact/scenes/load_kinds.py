"""The load types of a scene, in one registry: each type's keys, the form of its value and
how it is added to a problem's :class:`~xfem_contact.mechanics.loads.Loads`.

:data:`LOAD_KINDS` is what the schema lists (:data:`~xfem_contact.scenes.schema.LOAD_KEYS`),
what :func:`~xfem_contact.scenes.load_tables.load_spec` checks and what the builder
applies: a new load type is one row here.
"""

from __future__ import annotations

import typing

from xfem_contact.scenes.checks import Number, Scalar, SceneError, Vector


def _number(value, component: bool, key: str) -> None:
    Number()(value, key)


def _stiffness(value, component: bool, key: str) -> None:
    Number(0.0, open=True)(value, key)


def _scalar_load(value, component: bool, key: str) -> None:
    Scalar("load")(value, key)


def _vector_load(value, component: bool, key: str) -> None:
    Vector(2, Scalar("load"))(value, key)


def _displacement(value, component: bool, key: str) -> None:
    """A component's value, or [vx, vy]; a single expression needs a component."""
    if component:
        Scalar("number")(value, key)
    elif isinstance(value, list | tuple):
        Vector(2, Scalar("number"))(value, key)
    elif isinstance(value, str):
        raise SceneError(key, "an expression needs component = 0 or 1; for both give [vx, vy]")
    else:
        Scalar("number")(value, key)


def _rotation(loads, load, value, path: dict) -> None:
    angle = {"angle": load.value} if load.angle_deg is None else {"angle_deg": load.angle_deg}
    loads.add_rotation(load.part, centre=load.centre, **angle, **path)


class LoadKind(typing.NamedTuple):
    """One load type.

    Attributes:
        required: The keys a load of this type must have (besides ``type``).
        optional: The keys it may have.
        check: ``check(value, component, key)``: raises :class:`SceneError` unless the
            value has this type's form (``component``: whether the table gives one).
        add: ``add(loads, spec, value, path)``: adds the load of the checked ``spec``
            (:class:`~xfem_contact.scenes.records.LoadSpec`) to ``loads``; ``value`` is
            the spec's value made a number, tuple or callable, ``path`` the keyword
            arguments of its load path (``{"path": ...}``).
    """

    required: tuple[str, ...]
    optional: tuple[str, ...]
    check: typing.Callable[[object, bool, str], None]
    add: typing.Callable[..., None]


#: Every load type of a scene, by name
LOAD_KINDS: dict[str, LoadKind] = {
    "pressure": LoadKind(
        ("part", "value"),
        ("side", "path"),
        _scalar_load,
        lambda loads, load, value, path: loads.add_pressure(load.part, value, load.side, **path),
    ),
    "traction": LoadKind(
        ("part", "value"),
        ("side", "path"),
        _vector_load,
        lambda loads, load, value, path: loads.add_traction(load.part, value, load.side, **path),
    ),
    "displacement": LoadKind(
        ("part", "value"),
        ("component", "path"),
        _displacement,
        lambda loads, load, value, path: loads.add_displacement(
            load.part, value, load.component, **path
        ),
    ),
    "point_displacement": LoadKind(
        ("point", "component", "value"),
        ("path",),
        _number,
        lambda loads, load, value, path: loads.add_point_displacement(
            load.point, float(load.value), int(load.component), **path
        ),
    ),
    "body_force": LoadKind(
        ("value",),
        ("side", "path"),
        _vector_load,
        lambda loads, load, value, path: loads.add_body_force(value, load.side, **path),
    ),
    "rotation": LoadKind(("part",), ("value", "angle_deg", "centre", "path"), _number, _rotation),
    "tangential_spring": LoadKind(
        ("part", "value"),
        (),
        _stiffness,
        lambda loads, load, value, path: loads.add_tangential_spring(load.part, float(load.value)),
    ),
}
