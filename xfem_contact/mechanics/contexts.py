"""The interfaces as the laws see them: one :class:`InterfaceContext` per interface of
the current cut (rules, measure, materials, cell indicators). A problem builds them
at construction and again when its interfaces move."""

from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import interface_points
from xfem_contact.mechanics.laws import InterfaceContext, InterfaceLaw


def interface_context(
    cut: CutMesh,
    name: str,
    materials: dict,
    field: int | None,
    side_indicator: dolfinx.fem.Function,
    cell_size: dolfinx.fem.Function,
    w_old: dolfinx.fem.Function,
    degree: int,
    split: Callable = ufl.split,
    ramp: dolfinx.fem.Function | None = None,
    interpolants: dict | None = None,
    ghost_penalty: float = 0.0,
    ghost_penalty_higher: float = 1.0,
) -> InterfaceContext:
    """The context of interface ``name`` on the current cut of ``cut``.

    Args:
        cut: The cut mesh.
        name: The interface (one of ``cut.interface_names``).
        materials: ``{-1: Moduli, 1: Moduli}`` on its two sides.
        field: Index of its law's multiplier field in ``W`` (None without).
        side_indicator: DG0 side of each cell (-1, 0 cut, +1).
        cell_size: DG0 cell diameters (m).
        w_old: The last accepted state.
        degree: The displacements' Lagrange degree.
        split: The fields of a Function on ``W`` (the space's ``split``).
        ramp: The ramp of a crack's branch functions (the space's), None without.
        interpolants: The interpolants subtracted from them (the space's), None without.
        ghost_penalty: The ghost penalty's weight (the patch trace lengths' credit).
        ghost_penalty_higher: Its factor of the jumps of second and higher derivatives.

    Collective.
    """
    if len(cut.interface_names) == 1:
        on_cut_cells = 1.0 - abs(side_indicator)  # 1 on cut cells, 0 elsewhere
    else:
        on_cut_cells = _indicator(side_indicator.function_space, cut.interface_cells(name))
    return InterfaceContext(
        aligned_cells=aligned_cells(cut, name, side_indicator.function_space),
        cut=cut,
        name=name,
        measure=cut.interface_measure(name),
        rules=cut.interface_rules_of(name),
        materials=materials,
        cell_size=cell_size,
        cut_cells=on_cut_cells,
        field=field,
        w_old=w_old,
        degree=degree,
        split=split,
        ramp=ramp,
        interpolants=interpolants,
        ghost_penalty=ghost_penalty,
        ghost_penalty_higher=ghost_penalty_higher,
    )


def aligned_cells(
    cut: CutMesh, name: str, V0: dolfinx.fem.FunctionSpace
) -> dolfinx.fem.Function | None:
    """DG0 indicator (on ``V0``) of the cut cells of interface ``name`` whose piece
    follows a line of the reference coordinates; None when no process has one.
    Collective."""
    local = cut.cut_cells[cut.trace_nullity(name) >= 2]
    if cut.mesh.comm.allreduce(local.size, op=MPI.SUM) == 0:
        return None
    return _indicator(V0, local, name="aligned")


def _indicator(V0: dolfinx.fem.FunctionSpace, cells, name: str | None = None):
    """DG0 function, 1 on the local ``cells`` (ghosts updated), 0 elsewhere."""
    f = dolfinx.fem.Function(V0, name=name)
    f.x.array[V0.dofmap.list[cells, 0]] = 1.0
    f.x.scatter_forward()
    return f


def status_counts(
    laws: dict[str, InterfaceLaw], contexts: dict[str, InterfaceContext], w
) -> dict[str, int]:
    """Global counts of interface rule points by status (contact / stick / slip) for
    the state ``w``, prefixed by the interface name when there are several.
    Collective."""
    counts = {}
    for name, law in laws.items():
        local = law.status(law.state(contexts[name], w))
        prefix = f"{name} " if len(laws) > 1 else ""
        counts |= {prefix + k: v for k, v in local.items()}
    comm = next(iter(contexts.values())).cut.mesh.comm
    return {k: comm.allreduce(v, op=MPI.SUM) for k, v in counts.items()}


def samples(law: InterfaceLaw, ctx: InterfaceContext, w) -> dict[str, list[float]]:
    """The law's state for ``w`` at the rule points of all processes: ``x``, ``y`` (and
    ``z`` in 3D) (m) and ``gap``, ``slip``, ``lambda_n``, ``lambda_t`` and, for contact
    laws, ``P_n``, ``P_t``, each a list over the points (the tangential ones scalars
    along ``t`` in 2D, Cartesian vectors ``[x, y, z]`` in 3D). Collective."""
    state = law.state(ctx, w)
    points = interface_points(ctx.cut, ctx.rules)
    gdim = ctx.cut.mesh.geometry.dim
    local = {name: points[:, k] for k, name in enumerate("xyz"[:gdim])}
    keys = ("gap", "slip", "lambda_n", "lambda_t", "P_n", "P_t")
    local |= {k: state[k] for k in keys if k in state}
    comm = ctx.cut.mesh.comm
    return {k: np.concatenate(comm.allgather(v)).tolist() for k, v in local.items()}
