"""Helpers of the parallel-equals-serial tests: fields gathered and sorted by position."""

import numpy as np


def _by_position(points: np.ndarray) -> np.ndarray:
    """Order of points ``(n, gdim)``, sorted by rounded coordinates (x, then y, then z)."""
    rounded = np.round(np.asarray(points, dtype=np.float64), 7)
    return np.lexsort([rounded[:, k] for k in reversed(range(rounded.shape[1]))])


def gathered_fields(problem) -> dict[str, np.ndarray]:
    """The fields of a solved cut problem on every process, sorted by position.
    Collective.

    Returns ``lambda_n``, ``lambda_t`` at the interface rule points (Pa) and
    ``u_minus``, ``u_plus`` at the displacement dofs (m, shape ``(n, gdim)``).
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
        values = problem.w.x.array[np.asarray(dofs)].reshape(-1, gdim)[:owned]
        x, values = (np.concatenate(comm.allgather(a)) for a in (x, values))
        fields[name] = values[_by_position(x)]
    return fields


def max_relative_difference(a: dict, b: dict) -> dict[str, float]:
    """Per field: max |a - b| over max |b| (the multipliers share the scale of
    ``lambda_n``, the displacements that of both sides)."""
    scales = {
        "lambda": np.abs(b["lambda_n"]).max(),
        "u": max(np.abs(b["u_minus"]).max(), np.abs(b["u_plus"]).max()),
    }
    return {k: float(np.abs(a[k] - b[k]).max() / scales[k.split("_")[0]]) for k in b}
