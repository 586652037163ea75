"""The [[cracks]] of a scene: each table checked against its shape's keys and its law's
options (:func:`crack_spec`), the keys several cracks share (:func:`shared_crack_keys`);
where the cracks lie in the mesh is checked when they are built
(:mod:`xfem_contact.scenes.crack_builder`)."""

from __future__ import annotations

import math

from xfem_contact.scenes.checks import material_name
from xfem_contact.scenes.schema import (
    CRACK_SHAPE_KEYS,
    FIELDS,
    CrackSpec,
    SceneError,
    check_table,
)
from xfem_contact.scenes.table_keys import law_options, shape_parameters


def crack_spec(table, k: int, materials: dict) -> CrackSpec:
    """Crack ``k`` from its table: the parameters of its shape, its law's options, its
    body's material (default the first of ``materials``)."""
    where = f"cracks[{k}]"
    check_table(table, FIELDS["crack"], where)
    shape = table["shape"]
    params = shape_parameters(table, where, CRACK_SHAPE_KEYS)
    if shape == "segment" and len(params["points"]) != 2:
        message = f"a segment has 2 points, got {len(params['points'])} (use shape 'polyline')"
        raise SceneError(f"{where}.points", message)
    if shape in ("segment", "polyline"):
        points = params["points"]
        for i, (a, b) in enumerate(zip(points, points[1:], strict=False)):
            if math.dist(a, b) <= 1e-12 * max(1.0, *map(abs, a + b)):
                message = f"points {i} and {i + 1} coincide: each segment needs a length"
                raise SceneError(f"{where}.points", message)
    if shape == "arc" and not 0.0 < abs(params["angles_deg"][1] - params["angles_deg"][0]) < 360:
        message = f"the sweep |end - start| must be in (0, 360) degrees, got {params['angles_deg']}"
        raise SceneError(f"{where}.angles_deg", message)
    law = table.get("law", "free")
    options = law_options(table, where, law)
    material = material_name(table, "material", where, materials)
    reference = table.get("reference_K")
    if "reference_source" in table and reference is None:
        message = "a source needs reference_K = [K_I, K_II] (Pa m^1/2) to describe"
        raise SceneError(f"{where}.reference_source", message)
    return CrackSpec(
        shape=shape,
        params=params,
        material=material,
        name=table.get("name", "crack" if k == 0 else f"crack{k}"),
        law=law,
        tip_radius=table.get("tip_radius"),
        rings=table.get("rings"),
        reference_K=None if reference is None else tuple(float(k) for k in reference),
        reference_source=table.get("reference_source", ""),
        **options,
    )


def shared_crack_keys(cracks: list[CrackSpec], interfaces: list | None = None) -> None:
    """Several cracks lie in one body: distinct names, and the same ``material``,
    ``tip_radius`` and ``rings`` (one tip enrichment and one set of rings for all tips);
    closed ``interfaces`` among them: other names, the body's material outside, small
    kinematics."""
    for k, spec in enumerate(interfaces or () if cracks else ()):
        where, body = f"interfaces[{k}]", cracks[0].material
        if spec.name in [c.name for c in cracks]:
            raise SceneError(f"{where}.name", f"{spec.name!r} names a crack too")
        if spec.outside != body:
            message = f"{spec.outside!r}: the cracks lie in the body outside, of {body!r}"
            raise SceneError(f"{where}.outside", message + " (cracks[0].material)")
        if spec.kinematics != "small":
            message = f"{spec.kinematics!r}: with cracks, interfaces slide small only for now"
            raise SceneError(f"{where}.kinematics", message)
    for k, spec in enumerate(cracks[1:], start=1):
        first = cracks[0]
        names = [c.name for c in cracks[:k]]
        if spec.name in names:
            message = f"{spec.name!r} is the name of cracks[{names.index(spec.name)}] too"
            raise SceneError(f"cracks[{k}].name", message + ": give each crack its own name")
        for key in ("material", "tip_radius", "rings"):
            if getattr(spec, key) != getattr(first, key):
                raise SceneError(
                    f"cracks[{k}].{key}",
                    f"the cracks of a scene share one {key} (cracks[0]'s: "
                    f"{getattr(first, key)!r}), got {getattr(spec, key)!r}",
                )
