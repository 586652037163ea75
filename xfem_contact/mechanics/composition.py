"""How a problem is composed: one law object per interface, one material per side.

:func:`interface_laws` turns what a user gives (one law for all interfaces, or one per
name; objects or names) into law objects; :func:`side_and_law_materials` turns the
materials (one, or one per side with one per inclusion inside) into the bulk's and the
laws' views of them. SI units (Pa).
"""

from __future__ import annotations

from collections.abc import Mapping

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.bulk import SIDES
from xfem_contact.mechanics.laws import InterfaceLaw, make_law
from xfem_contact.mechanics.materials import Material, MaterialField

#: Materials: one for both sides, or ``{-1: m, 1: m}`` where side -1 may map
#: interface names to the material inside each
Materials = Material | Mapping[int, Material | Mapping[str, Material]]


def interface_laws(cut: CutMesh, interfaces) -> dict[str, InterfaceLaw]:
    """One law object per interface name of ``cut``."""
    names = cut.interface_names
    if not isinstance(interfaces, Mapping):
        interfaces = {name: interfaces for name in names}
    if set(interfaces) != set(names):
        raise ValueError(f"Give a law for each interface {list(names)}; got {sorted(interfaces)}")
    laws = {}
    for name in names:
        law = interfaces[name]
        laws[name] = make_law(law) if isinstance(law, str) else law
        if not isinstance(laws[name], InterfaceLaw):
            raise ValueError(f"Interface {name!r}: {law!r} is not an interface law")
    return laws


def side_and_law_materials(cut: CutMesh, materials: Materials):
    """Per side (Material or MaterialField) and per interface ({-1, 1}: Material)."""
    if isinstance(materials, Material):
        materials = {-1: materials, 1: materials}
    missing = [s for s in SIDES if s not in materials]
    if missing:
        raise ValueError(f"Give a Material for sides -1 and +1 (missing: {missing})")
    names = cut.interface_names
    inside = materials[-1]
    if isinstance(inside, Mapping):
        if set(inside) != set(names):
            raise ValueError(
                f"Side -1 materials must name the interfaces {list(names)}; got {sorted(inside)}"
            )
        per_interface = dict(inside)
    else:
        per_interface = {name: inside for name in names}
    if not all(isinstance(m, Material) for m in [*per_interface.values(), materials[1]]):
        raise ValueError("Give a Material for sides -1 and +1")
    distinct = len({per_interface[n] for n in names}) > 1
    side_minus = (
        MaterialField(cut.cell_regions(), [per_interface[n] for n in names])
        if distinct
        else per_interface[names[0]]
    )
    law_materials = {name: {-1: per_interface[name], 1: materials[1]} for name in names}
    return {-1: side_minus, 1: materials[1]}, law_materials
