"""The cut of a tetrahedron or hexahedron mesh as a :class:`~xfem_contact.fem.cut_state.CutState`.

The 3D counterpart of :func:`~xfem_contact.fem.cut_state.cut_state`, with the same level-set
front (named interfaces, their union, the shared level-set Function) and the same measure
ids, so that :class:`~xfem_contact.fem.cutmesh.CutMesh` serves both. The rules come from
:func:`~xfem_contact.quadrature.cut3d_rules.cut_rules_3d` on the nodal values of the
interpolated level set: exact sub-tetrahedra for P1 tetrahedra, Saye's rules for Q1/Q2
hexahedra and P2 tetrahedra. A level set given as a callable is interpolated as well (the
cut cells, Saye's boxes and axes are the interpolant's); with ``exact_zero_set`` and degree
2, Saye's rules take their roots and the interface's area vectors from the callable itself:
they follow its exact zero set. There are no sub-cells to keep: ``geometry`` is ``None``.
"""

from __future__ import annotations

import re

import dolfinx.mesh
import numpy as np

from xfem_contact._timers import phase, seconds
from xfem_contact.fem.cut_state import (
    INTERFACE,
    SIDE_MINUS,
    SIDE_PLUS,
    CutState,
    frozen_state,
    interpolate_named,
)
from xfem_contact.fem.interface_cells import cell_interfaces, without_slivers
from xfem_contact.geometry.levelset import CellMaps, named_interfaces
from xfem_contact.quadrature.cut3d_rules import classify_3d, cut_rules_3d
from xfem_contact.quadrature.rules import RuleSet

__all__ = ["cut_state_3d", "planar_cut_rules"]


def cut_state_3d(
    mesh: dolfinx.mesh.Mesh,
    levelset,
    degree: int,
    quadrature_degree: int,
    previous: CutState | None,
    exact_zero_set: bool = False,
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
    on_owned = maps.exact(owned) if exact_zero_set else None  # None for a Function too
    side = _collective(mesh, lambda: classify_3d(cell, degree, maps.nodal_values(owned), on_owned))
    cut_cells = owned[side == 0]
    cut_time, timer = seconds(timer), phase("cut rules")

    exact = maps.exact(cut_cells) if exact_zero_set else None  # None for a Function too

    def rules_of(rows: np.ndarray):
        return cut_rules_3d(
            cell,
            degree,
            maps.nodal_values(cut_cells[rows]),
            quadrature_degree,
            lambda r, X: maps.jacobian(cut_cells[rows][r], X),
            exact=None if exact is None else lambda r, X: exact(rows[r], X),
        )

    def rules_of_cut_cells():
        try:
            return rules_of(np.arange(cut_cells.size))
        except ValueError as error:
            raise ValueError(_located(str(error), rules_of, maps, cut_cells)) from None

    cut = _collective(mesh, rules_of_cut_cells)
    rules = {
        SIDE_MINUS: cut.minus,
        SIDE_PLUS: cut.plus,
        INTERFACE: without_slivers(mesh, cut_cells, cut.interface, maps),
    }
    cell_interface = cell_interfaces(maps, cut_cells, rules[INTERFACE], components)
    timings = {"cut": cut_time, "quadrature": seconds(timer)}
    fields = dict(levelset=phi, maps=maps, interface_names=names, components=components)
    return frozen_state(
        mesh.comm, previous, fields, side, cut_cells, rules, cell_interface, timings
    )


def planar_cut_rules(state: CutState, quadrature_degree: int) -> dict[int, RuleSet]:
    """The rules of a P1 tetrahedron cut ``state`` at another ``quadrature_degree``: the
    exact planar cut again, with Basix rules of that degree on the sub-tetrahedra and
    interface triangles, by measure id; the interface on the rows ``state`` keeps (no
    slivers). Not collective.

    On affine tetrahedra these have the moments of degree ``<= quadrature_degree`` of any
    rules of the cut of a higher degree (both are exact), with fewer points.
    """
    maps, cells = state.maps, state.cut_cells
    cut = cut_rules_3d(
        "tetrahedron",
        1,
        maps.nodal_values(cells),
        quadrature_degree,
        lambda rows, X: maps.jacobian(cells[rows], X),
    )
    kept = np.diff(state.rules[INTERFACE].offsets) > 0
    return {SIDE_MINUS: cut.minus, SIDE_PLUS: cut.plus, INTERFACE: cut.interface.select(kept)}


def _collective(mesh: dolfinx.mesh.Mesh, step):
    """``step()`` on every process; a ``ValueError`` on any of them is raised on all (the
    first rank's message), so that no process waits for the others. Collective."""
    try:
        result, message = step(), None
    except ValueError as error:
        result, message = None, str(error)
    messages = [m for m in mesh.comm.allgather(message) if m is not None]
    if messages:
        raise ValueError(messages[0])
    return result


def _located(message: str, rules_of, maps: CellMaps, cut_cells: np.ndarray) -> str:
    """A refusal of the rules of the cut cells, naming the first refused cell by its local
    index and its vertices' centroid (m), found by bisection (the kernels number the cells
    of their own batch; a P2 tetrahedron is four of them). ``rules_of(rows)`` makes the
    rules of ``cut_cells[rows]``."""
    lo, hi = 0, cut_cells.size  # a refused cell lies in rows lo .. hi - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        try:
            rules_of(np.arange(lo, mid))
            lo = mid
        except ValueError:
            hi = mid
    centre = maps.cell_nodes(cut_cells[lo : lo + 1])[0].mean(axis=0)
    where = ", ".join(f"{v:.6g}" for v in centre)
    found = re.match(r"(tetrahedron|hexahedron) \d+: ", message)  # the kernel's own row
    reason = message[found.end() :] if found else message
    cell = maps.mesh.topology.cell_name()
    return f"{cell} at ({where}) (local cell {cut_cells[lo]}): {reason}"
