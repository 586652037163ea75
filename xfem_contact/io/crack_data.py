"""What a crack's outputs show: each side's displacement with the tip's branch functions,
and the opening and slip of the lips.

With a crack, the displacement of side ``s`` is ``u_s + sum_k F_k(s) b_k``
(:meth:`~xfem_contact.fem.enrichment.EnrichedSpace.displacements`): the nodal fields
alone miss the tip's ``sqrt(r)`` opening. :class:`EnrichedDisplacements` interpolates
the whole of it into each side's output Function (VTX, ``result.vtu``);
:func:`lip_samples` gives the jump ``[u] = u_+ - u_-`` at the lips' rule points
(:meth:`~xfem_contact.mechanics.laws.base.InterfaceContext.jump_at`, branch functions
included), opening ``[u].n`` and slip ``[u].t`` (m), with the law's multipliers (Pa)
and status.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np

from xfem_contact.fem.evaluation import interface_points


class EnrichedDisplacements:
    """Each side's enriched displacement interpolated into its output Function.

    Args:
        problem: A :class:`~xfem_contact.mechanics.problem.Problem` whose cut has a crack.
        fields: The output Functions of sides -1 and +1 (Lagrange vector spaces), the
            nodal values copied in already; :meth:`update` overwrites them on the
            side's cells (uncut cells of that side and cut cells, ghosts included).

    Expressions are compiled once here; :meth:`update` is not collective.
    """

    def __init__(self, problem, fields):
        u = problem.space.split(problem.w)
        side = problem.side_indicator
        cell_side = side.x.array[side.function_space.dofmap.list[:, 0]]
        self._targets = []
        for i, s in ((0, -1), (1, 1)):
            points = fields[i].function_space.element.interpolation_points
            cells = np.flatnonzero(np.isin(cell_side, (s, 0))).astype(np.int32)
            self._targets.append((fields[i], dolfinx.fem.Expression(u[i], points), cells))

    def update(self) -> None:
        """Interpolate the current enriched displacements (local, owned and ghost cells)."""
        for target, expression, cells in self._targets:
            target.interpolate(expression, cells0=cells)


def lip_samples(problem, name: str) -> dict[str, list]:
    """The lips of crack ``name`` at the rule points of all processes: ``x``, ``y`` (m),
    ``opening`` ``[u].n`` and ``slip`` ``[u].t`` (m, branch functions included) and, for
    a law with a multiplier, ``lambda_n``, ``lambda_t`` (Pa) and ``status`` (0 open, 1
    stick, 2 slip; from the law's own state). Collective."""
    ctx, law = problem.contexts[name], problem.laws[name]
    n, t = ctx.frame_at()
    jump = ctx.jump_at(problem.w)  # with the branch functions' jump
    points = interface_points(problem.cut, ctx.rules)
    local = {"x": points[:, 0], "y": points[:, 1]}
    local |= {"opening": np.sum(jump * n, axis=1), "slip": np.sum(jump * t, axis=1)}
    if ctx.field is not None:
        state = law.state(ctx, problem.w)
        local |= {key: state[key] for key in ("lambda_n", "lambda_t") if key in state}
        local["status"] = law.point_status(state, points.shape[0])
    comm = problem.mesh.comm
    return {key: np.concatenate(comm.allgather(v)).tolist() for key, v in local.items()}
