"""How a problem is composed: one law object per interface, one material per side.

:func:`interface_laws` turns what a user gives (one law for all interfaces, or one per
name; objects or names) into law objects; :func:`side_and_law_materials` turns the
materials (one, or one per side with one per inclusion inside) into the bulk's and the
laws' views of them. SI units (Pa).
"""

from __future__ import annotations

import typing
from collections.abc import Mapping

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.bulk import SIDES
from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.laws import LAW_OPTIONS, InterfaceLaw, make_law
from xfem_contact.mechanics.materials import Material, MaterialField, Moduli

#: Materials: one for both sides, or ``{-1: m, 1: m}`` where side -1 may map
#: interface names to the material inside each
Materials = Material | Mapping[int, Material | Mapping[str, Material]]


def crack_law(name: str, **options) -> InterfaceLaw:
    """:func:`~xfem_contact.mechanics.laws.make_law` with a crack's default LBB treatment,
    ``DEFAULT.crack_lbb`` (see :func:`interface_laws`), for a law that takes one."""
    if options.get("lbb") is None and "lbb" in LAW_OPTIONS.get(name, ()):
        options["lbb"] = DEFAULT.crack_lbb
    return make_law(name, **options)


def interface_laws(cut: CutMesh, interfaces) -> dict[str, InterfaceLaw]:
    """One law object per interface name of ``cut``. A crack's law given by name takes
    the vital-vertex restriction (``lbb="restriction"``): without an LBB treatment the
    lips' multiplier oscillates and K depends on the mesh, and the Barbosa-Hughes
    stabilisation squares the traction of the tip's singular stress along the lips
    (``1/r``, not integrable), so a crack refuses it."""
    names = cut.interface_names
    if not isinstance(interfaces, Mapping):
        interfaces = {name: interfaces for name in names}
    if set(interfaces) != set(names):
        raise ValueError(f"Give a law for each interface {list(names)}; got {sorted(interfaces)}")
    laws = {}
    union = None if cut.crack is None else cut.crack.union
    closed = () if union is None else union.interfaces  # interfaces among cracks
    for name in names:
        law = interfaces[name]
        crack = cut.crack is not None and name not in closed
        if isinstance(law, str):
            law = crack_law(law) if crack else make_law(law)
        laws[name] = law
        if not isinstance(laws[name], InterfaceLaw):
            raise ValueError(f"Interface {name!r}: {law!r} is not an interface law")
        if crack and law.lbb == "stabilized":
            raise ValueError(
                f"Crack {name!r}: lbb='stabilized' squares the tip's singular traction on "
                "the lips (K_I of a closed crack 30 % off); give the law lbb='restriction'"
            )
    return laws


class SideMaterials(typing.NamedTuple):
    """A problem's materials as its forms see them (see :func:`side_and_law_materials`)."""

    #: Per side, what the bulk uses: ``Moduli``, or a ``MaterialField`` on side -1
    #: when several interfaces have a material each
    bulk: dict[int, Moduli | MaterialField]
    #: Per interface name, ``{-1: Moduli, 1: Moduli}`` (the laws' view)
    laws: dict[str, dict[int, Moduli]]
    #: What a user sets: ``{-1: Moduli or {interface name: Moduli}, 1: Moduli}``
    user: dict


def side_and_law_materials(cut: CutMesh, materials: Materials) -> SideMaterials:
    """The :class:`Moduli` (Constants on ``cut.mesh``) of the materials given: one for
    side +1, and one for side -1 or, when side -1 maps interface names to materials,
    one per interface. Each is shared by the bulk and the laws, so that setting its
    ``E`` or ``nu`` changes every form that uses it, and no other material, even where
    the values given were equal. Collective (DG0 fields)."""
    if isinstance(materials, Material):
        materials = {-1: materials, 1: materials}
    if not isinstance(materials, Mapping):
        raise ValueError(
            f"materials: give a Material or {{-1: Material, 1: Material}}, got {materials!r}"
        )
    missing = [s for s in SIDES if s not in materials]
    if missing:
        raise ValueError(f"materials: give a Material for sides -1 and +1 (missing: {missing})")
    names = cut.interface_names
    inside = materials[-1]
    if isinstance(inside, Mapping):
        if set(inside) != set(names):
            raise ValueError(
                f"materials[-1] must name the interfaces {list(names)}; got {sorted(inside)}"
            )
        given = dict(inside)
    else:
        given = {-1: inside}
    for key, m in [*given.items(), (1, materials[1])]:
        if not isinstance(m, Material):
            raise ValueError(f"materials[{key!r}]: give a Material, got {m!r}")
    outside = Moduli(materials[1], cut.mesh)
    if isinstance(inside, Mapping):
        per_interface = {name: Moduli(inside[name], cut.mesh) for name in names}
        user_inside = per_interface
        side_minus = (
            MaterialField(cut.cell_regions(), [per_interface[n] for n in names])
            if len(names) > 1
            else per_interface[names[0]]
        )
    else:
        side_minus = user_inside = Moduli(inside, cut.mesh)
        per_interface = {name: side_minus for name in names}
    laws = {name: {-1: per_interface[name], 1: outside} for name in names}
    return SideMaterials({-1: side_minus, 1: outside}, laws, {-1: user_inside, 1: outside})
