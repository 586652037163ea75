"""The cut of a tetrahedron or hexahedron mesh as a :class:`~xfem_contact.fem.cut_state.CutState`.

The 3D counterpart of :func:`~xfem_contact.fem.cut_state.cut_state`, with the same level-set
front (named interfaces, their union, the shared level-set Function) and the same measure
ids, so that :class:`~xfem_contact.fem.cutmesh.CutMesh` serves both. The rules come from
:func:`~xfem_contact.quadrature.cut3d_rules.cut_rules_3d` on the nodal values of the
interpolated level set: exact sub-tetrahedra for P1 tetrahedra, Saye's rules for Q1/Q2
hexahedra and P2 tetrahedra. There are no sub-cells to keep: ``geometry`` is ``None``.
"""

from __future__ import annotations

import re
import types

import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact._timers import phase, seconds
from xfem_contact.fem.cut_state import (
    INTERFACE,
    SIDE_MINUS,
    SIDE_PLUS,
    CutState,
    interpolate_named,
)
from xfem_contact.fem.interface_cells import cell_interfaces, without_slivers
from xfem_contact.geometry.levelset import CellMaps, named_interfaces
from xfem_contact.quadrature.cut3d_rules import classify_3d, cut_rules_3d

__all__ = ["cut_state_3d"]


def cut_state_3d(
    mesh: dolfinx.mesh.Mesh,
    levelset,
    degree: int,
    quadrature_degree: int,
    previous: CutState | None,
) -> CutState:
    """The cut of a 3D ``mesh`` by ``levelset`` following ``previous`` (the first cut for
    ``None``). Arguments as :class:`~xfem_contact.fem.cutmesh.CutMesh`'s. Collective.

    Raises:
        ValueError: a level set the cut refuses (see
            :func:`~xfem_contact.geometry.levelset.interpolate`), or a cell whose zero set
            has a singular point (naming the cell, from Saye's rules).
    """
    tdim = mesh.topology.dim
    cell = mesh.topology.cell_name()
    timer = phase("cut")
    known = None if previous is None else previous.interface_names
    names, components, levelset = named_interfaces(mesh, levelset, degree, known)
    phi = interpolate_named(mesh, levelset, degree, names, previous)
    maps = CellMaps(mesh, phi)
    owned = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    side = classify_3d(cell, degree, maps.nodal_values(owned))
    cut_cells = owned[side == 0]
    cut_time, timer = seconds(timer), phase("cut rules")
    try:
        cut = cut_rules_3d(
            cell,
            degree,
            maps.nodal_values(cut_cells),
            quadrature_degree,
            lambda rows, X: maps.jacobian(cut_cells[rows], X),
        )
    except ValueError as error:  # a row of the cut cells -> the cell's position
        raise ValueError(_located(str(error), cell, degree, maps, cut_cells)) from None
    rules = {
        SIDE_MINUS: cut.minus,
        SIDE_PLUS: cut.plus,
        INTERFACE: without_slivers(mesh, cut_cells, cut.interface, maps),
    }
    cell_interface = cell_interfaces(maps, cut_cells, rules[INTERFACE], components)
    for array in (side, cut_cells, cell_interface):
        array.setflags(write=False)
    return CutState(
        revision=0 if previous is None else previous.revision + 1,
        levelset=phi,
        maps=maps,
        interface_names=names,
        components=components,
        cell_sides=side,
        cut_cells=cut_cells,
        geometry=None,
        rules=types.MappingProxyType(rules),
        cell_interface=cell_interface,
        crack=None,
        num_cut_cells_global=mesh.comm.allreduce(cut_cells.size, op=MPI.SUM),
        timings=types.MappingProxyType({"cut": cut_time, "quadrature": seconds(timer)}),
    )


def _located(message: str, cell: str, degree: int, maps: CellMaps, cut_cells) -> str:
    """A kernel's refusal naming a row of the cut cells, with that cell's centroid (m)."""
    found = re.match(r"(tetrahedron|hexahedron) (\d+):", message)
    if found is None:
        return message
    row = int(found[2])
    if cell == "tetrahedron" and degree == 2:  # rows of the four hexahedra of each cell
        row //= 4
    centre = maps.cell_nodes(cut_cells[row : row + 1])[0].mean(axis=0)
    where = ", ".join(f"{v:.6g}" for v in centre)
    return f"{cell} cut at ({where}) (local cell {cut_cells[row]}): {message}"
