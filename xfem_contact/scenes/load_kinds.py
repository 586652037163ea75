"""The load types of a scene, in one registry: each type's keys, the form of its value and
how it is added to a problem's :class:`~xfem_contact.mechanics.loads.Loads`.

:data:`LOAD_KINDS` is what the schema lists (:data:`~xfem_contact.scenes.schema.LOAD_KEYS`),
what :func:`~xfem_contact.scenes.load_tables.load_spec` checks and what the builder
applies: a new load type is one row here.
"""

from __future__ import annotations

import typing

from xfem_contact.scenes.checks import Number, Scalar, SceneError, Vector


def _number(value, component: bool, key: str, gdim: int = 2) -> None:
    Number()(value, key)


def _stiffness(value, component: bool, key: str, gdim: int = 2) -> None:
    Number(0.0, open=True)(value, key)


def _scalar_load(value, component: bool, key: str, gdim: int = 2) -> None:
    Scalar("load", gdim)(value, key)


def _vector_load(value, component: bool, key: str, gdim: int = 2) -> None:
    Vector(gdim, Scalar("load", gdim))(value, key)


def _displacement(value, component: bool, key: str, gdim: int = 2) -> None:
    """A component's value, or [vx, vy] ([vx, vy, vz] in 3D); a single expression needs a
    component."""
    if component:
        Scalar("number", gdim)(value, key)
    elif isinstance(value, list | tuple):
        Vector(gdim, Scalar("number", gdim))(value, key)
    elif isinstance(value, str):
        if gdim == 2:
            message = "an expression needs component = 0 or 1; for both give [vx, vy]"
        else:
            message = "an expression needs component = 0, 1 or 2; for all give [vx, vy, vz]"
        raise SceneError(key, message)
    else:
        Scalar("number", gdim)(value, key)


def _rotation(loads, load, value, path: dict) -> None:
    angle = {"angle": load.value} if load.angle_deg is None else {"angle_deg": load.angle_deg}
    loads.add_rotation(load.part, centre=load.centre, **angle, **path)


class LoadKind(typing.NamedTuple):
    """One load type.

    Attributes:
        required: The keys a load of this type must have (besides ``type``).
        optional: The keys it may have.
        check: ``check(value, component, key, gdim=2)``: raises :class:`SceneError` unless
            the value has this type's form (``component``: whether the table gives one;
            ``gdim``: the mesh's geometric dimension).
        add: ``add(loads, spec, value, path)``: adds the load of the checked ``spec``
            (:class:`~xfem_contact.scenes.records.LoadSpec`) to ``loads``; ``value`` is
            the spec's value made a number, tuple or callable, ``path`` the keyword
            arguments of its load path (``{"path": ...}``).
    """

    required: tuple[str, ...]
    optional: tuple[str, ...]
    check: typing.Callable[[object, bool, str, int], None]
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
