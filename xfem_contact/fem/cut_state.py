"""One cut of a mesh as a value: the level set, the cut cells, their geometry and rules.

A :class:`~xfem_contact.fem.cutmesh.CutMesh` holds a sequence of :class:`CutState`
values: its constructor builds the first (:func:`cut_state` with no ``previous``), each
``update`` the next (revision + 1). A state is frozen: what was built on it (an enriched
space, a problem's contexts) is stale exactly when the mesh's current state is another
object. The level-set Functions (``levelset.function``, ``crack.tangent.function``) are
the mesh's own and shared by its states, so that compiled forms keep their signature:
their values are those of the current cut.

Measure ids of the rules (``rules`` keys): :data:`SIDE_MINUS`, :data:`SIDE_PLUS`,
:data:`INTERFACE`.
"""

from __future__ import annotations

import dataclasses
import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import numpy.typing as npt
from mpi4py import MPI

from xfem_contact._timers import phase, seconds
from xfem_contact.fem.crack_cut import Crack, crack_rules
from xfem_contact.fem.interface_cells import cell_interfaces, without_slivers
from xfem_contact.geometry import cut
from xfem_contact.geometry.crack_union import crack_union, interpolate_tangent
from xfem_contact.geometry.levelset import (
    CellMaps,
    InterfaceError,
    LevelSet,
    interpolate,
    named_interfaces,
)
from xfem_contact.quadrature import rules as quadrature

__all__ = ["INTERFACE", "SIDE_MINUS", "SIDE_PLUS", "CutState", "cut_state", "interpolate_named"]

SIDE_MINUS, SIDE_PLUS, INTERFACE = 1, 2, 3


@dataclass(frozen=True)
class CutState:
    """The cut of a mesh by one level set (owned cells of this process).

    Attributes:
        revision: 0 for the constructor's cut, + 1 for every update.
        levelset: The interpolated level set ``phi_h`` and its callable.
        maps: The cell maps (reference to physical) and ``phi_h`` on each cell.
        interface_names: Names of the interfaces, in the order of their measure ids.
        components: The callables of several named interfaces (``None`` for one
            interface, for a Function and for cracks).
        cell_sides: Side of every owned cell: -1, +1, 0 when cut, ``(num_owned,)`` int8.
        cut_cells: Local indices of the owned cut cells, ``(ncut,)`` int32.
        geometry: The sub-triangulation of the cut cells (rows of ``cut_cells``); ``None``
            for a 3D mesh (:mod:`xfem_contact.fem.cut3d_state`: rules without sub-cells).
        rules: Per-cut-cell rules by measure id (:data:`SIDE_MINUS`,
            :data:`SIDE_PLUS`, :data:`INTERFACE`), rows of ``cut_cells``; read-only.
        cell_interface: Interface (index into ``interface_names``) of every cut cell,
            ``(ncut,)``.
        crack: The crack data of a cut by cracks (``None`` for interfaces).
        num_cut_cells_global: Number of cut cells over all processes.
        timings: Wall time (s) of this cut: level set, classification and
            sub-triangulation (``"cut"``), per-cell rules (``"quadrature"``).
    """

    revision: int
    levelset: LevelSet
    maps: CellMaps
    interface_names: tuple[str, ...]
    components: Mapping[str, Callable] | None
    cell_sides: npt.NDArray[np.int8]
    cut_cells: npt.NDArray[np.int32]
    geometry: cut.CutGeometry | None
    rules: Mapping[int, quadrature.RuleSet]
    cell_interface: npt.NDArray[np.int64]
    crack: Crack | None
    num_cut_cells_global: int
    timings: Mapping[str, float]


def interpolate_named(
    mesh: dolfinx.mesh.Mesh, levelset, degree: int, names: tuple[str, ...], previous
) -> LevelSet:
    """The level set of the interfaces ``names`` interpolated in degree ``degree``, into
    the Function of the ``previous`` state if any (compiled forms keep their
    signature); a refusal names the interface when there is one. Collective."""
    into = None if previous is None else previous.levelset.function
    try:
        return interpolate(mesh, levelset, degree, into=into)
    except ValueError as error:
        if len(names) > 1:  # the union: each interface was checked by name
            raise
        raise InterfaceError(names[0], str(error)) from None


def cut_state(
    mesh: dolfinx.mesh.Mesh,
    levelset,
    tangent,
    degree: int,
    quadrature_degree: int,
    tip_points: int,
    previous: CutState | None,
    exact_zero_set: bool = True,
) -> CutState:
    """The cut of ``mesh`` by ``levelset`` (and a crack's ``tangent``), following
    ``previous`` (its interface names, its level-set Functions, its revision + 1);
    the first cut for ``previous=None``. Arguments as :class:`CutMesh`'s. Collective."""
    tdim = mesh.topology.dim
    cell_name = mesh.topology.cell_name()
    timer = phase("cut")
    known = None if previous is None else previous.interface_names
    union = None
    if tangent is not None and isinstance(levelset, Mapping):
        union = crack_union(mesh, levelset, tangent, degree, known)
        names, components = union.names, None
        levelset, tangent = union.phi, union.psi
    else:
        names, components, levelset = named_interfaces(mesh, levelset, degree, known)
    phi = interpolate_named(mesh, levelset, degree, names, previous)
    maps = CellMaps(mesh, phi)
    owned = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    side = cut.classify(cell_name, degree, maps.nodal_values(owned))
    cut_cells = owned[side == 0]
    ncut = cut_cells.size
    geometry = cut.subtriangulate(
        cell_name,
        degree,
        maps.nodal_values(cut_cells),
        exact=maps.exact(cut_cells) if exact_zero_set else None,
    )
    cut_time, timer = seconds(timer), phase("cut rules")
    q = quadrature_degree
    rules = {
        SIDE_MINUS: quadrature.side_rules(geometry, -1, q, ncut),
        SIDE_PLUS: quadrature.side_rules(geometry, +1, q, ncut),
        INTERFACE: quadrature.interface_rule(
            geometry,
            q,
            ncut,
            lambda rows, X: maps.jacobian(cut_cells[rows], X),
            lambda rows, X: maps.grad_ref(cut_cells[rows], X),
        ),
    }
    rules[INTERFACE] = without_slivers(mesh, cut_cells, rules[INTERFACE], maps)
    crack = None
    if tangent is not None:
        previous_psi = None if previous is None else previous.crack.tangent.function
        psi = interpolate_tangent(mesh, tangent, degree, into=previous_psi)
        keys = {"minus": SIDE_MINUS, "plus": SIDE_PLUS, "interface": INTERFACE}
        named = {key: rules[sid] for key, sid in keys.items()}
        named, crack = crack_rules(cut_cells, named, maps, psi, geometry, tip_points)
        at = np.zeros(len(crack.tips), dtype=int)
        if union is not None and len(names) > 1:  # the crack of each tip
            at = union.nearest(crack.tips)
        tip_names = tuple(names[k] for k in at)
        crack = dataclasses.replace(crack, tip_names=tip_names, union=union)
        rules = {sid: named[key] for key, sid in keys.items()}
    cell_interface = cell_interfaces(maps, cut_cells, rules[INTERFACE], components)
    if union is not None and len(names) > 1:
        cell_interface = union.cell_crack[cut_cells]
    timings = {"cut": cut_time, "quadrature": seconds(timer)}
    return frozen_state(
        mesh.comm,
        previous,
        dict(levelset=phi, maps=maps, interface_names=names, components=components),
        side,
        cut_cells,
        rules,
        cell_interface,
        timings,
        geometry=geometry,
        crack=crack,
    )


def frozen_state(
    comm: MPI.Comm,
    previous: CutState | None,
    fields: dict,
    side: np.ndarray,
    cut_cells: np.ndarray,
    rules: dict,
    cell_interface: np.ndarray,
    timings: dict,
    geometry=None,
    crack: Crack | None = None,
) -> CutState:
    """The :class:`CutState` after ``previous`` (None: revision 0): ``fields`` (its
    ``levelset``, ``maps``, ``interface_names``, ``components``), the arrays ``side``,
    ``cut_cells`` and ``cell_interface`` made read-only, ``rules`` and ``timings`` (s) as
    read-only mappings. Collective (the global count of cut cells)."""
    for array in (side, cut_cells, cell_interface):
        array.setflags(write=False)
    return CutState(
        revision=0 if previous is None else previous.revision + 1,
        **fields,
        cell_sides=side,
        cut_cells=cut_cells,
        geometry=geometry,
        rules=types.MappingProxyType(rules),
        cell_interface=cell_interface,
        crack=crack,
        num_cut_cells_global=comm.allreduce(cut_cells.size, op=MPI.SUM),
        timings=types.MappingProxyType(timings),
    )
