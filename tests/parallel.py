"""Helpers of the parallel-equals-serial tests: fields gathered and sorted by position."""

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI


def _by_position(points: np.ndarray) -> np.ndarray:
    """Order of points ``(n, gdim)``, sorted by rounded coordinates (x, then y, then z)."""
    rounded = np.round(np.asarray(points, dtype=np.float64), 7)
    return np.lexsort([rounded[:, k] for k in reversed(range(rounded.shape[1]))])


def gathered_fields(problem) -> dict[str, np.ndarray]:
    """The fields of a solved cut problem on every process, sorted by position.
    Collective.

    Returns ``lambda_n``, ``lambda_t`` at the interface rule points (Pa) and
    ``u_minus``, ``u_plus`` at the displacement nodes (m, shape ``(n, gdim)``): the dofs
    of each side's field, or with a crack (:func:`crack_side_values`) the displacement
    of each side, branch functions included, at the nodes on that side.
    """
    comm = problem.mesh.comm
    gdim = problem.mesh.geometry.dim
    samples = problem.interface_samples(problem.w)
    order = _by_position(np.stack([samples[k] for k in "xyz"[:gdim]], axis=1))
    fields = {k: np.asarray(samples[k])[order] for k in ("lambda_n", "lambda_t")}
    for field, name in ((0, "u_minus"), (1, "u_plus")):
        V, dofs = problem.space.field_space(field)
        owned = V.dofmap.index_map.size_local
        x = V.tabulate_dof_coordinates()[:owned, :gdim]
        if problem.space.branch_field is None:
            values = problem.w.x.array[np.asarray(dofs)].reshape(-1, gdim)[:owned]
        else:
            values, on_side = crack_side_values(problem, field)
            x, values = x[on_side], values[on_side]
        x, values = (np.concatenate(comm.allgather(a)) for a in (x, values))
        fields[name] = values[_by_position(x)]
    return fields


def crack_side_values(problem, field: int) -> tuple[np.ndarray, np.ndarray]:
    """The displacement of side ``-1`` (``field`` 0) or ``+1`` (1) of a cracked problem,
    ``u_s + sum_k F_k b_k`` (:meth:`~xfem_contact.fem.enrichment.EnrichedSpace.split`),
    at the owned nodes of the field's space (m, ``(owned, gdim)``), and whether each
    node lies on that side or on the crack's line (the field there, not its extension).
    The raw dofs of an enriched field are not the field: a combination of standard and
    branch dofs of tiny energy is set by round-off. Collective."""
    space, gdim = problem.space, problem.mesh.geometry.dim
    V = space.field_space(field)[0]
    owned = V.dofmap.index_map.size_local
    points = V.element.interpolation_points
    phi = space.cut.levelset.function
    out = []
    for expression in (space.split(problem.w)[field], ufl.as_vector([phi] * gdim)):
        f = dolfinx.fem.Function(V)
        f.interpolate(dolfinx.fem.Expression(expression, points))
        out.append(f.x.array.reshape(-1, gdim)[:owned])
    side = -1 if field == 0 else 1
    return out[0], side * out[1][:, 0] >= -space.round_off


def max_relative_difference(a: dict, b: dict) -> dict[str, float]:
    """Per field: max |a - b| over max |b| (the multipliers share the scale of
    ``lambda_n``, the displacements that of both sides)."""
    scales = {
        "lambda": np.abs(b["lambda_n"]).max(),
        "u": max(np.abs(b["u_minus"]).max(), np.abs(b["u_plus"]).max()),
    }
    return {k: float(np.abs(a[k] - b[k]).max() / scales[k.split("_")[0]]) for k in b}


def all_ranks_against_one(build) -> dict[str, float]:
    """:func:`max_relative_difference` of the problem ``build(comm)`` solved on all
    processes against the same problem solved on each process alone
    (``MPI.COMM_SELF``), the fields gathered and sorted by position. Collective."""
    fields = []
    for comm in (MPI.COMM_WORLD, MPI.COMM_SELF):
        problem = build(comm)
        problem.solve()
        fields.append(gathered_fields(problem))
    return max_relative_difference(*fields)
