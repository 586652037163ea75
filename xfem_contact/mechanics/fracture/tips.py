"""Stress intensity factors of the tips of a cracked problem: one interaction integral per tip.

:class:`TipIntegrals` builds, for every tip of ``problem.cut.crack``, an
:class:`~xfem_contact.mechanics.fracture.interaction.InteractionIntegral` on the two
sides' enriched displacements (``problem.space.split``) with the side measures of the
cut (graded Duffy rules in the tip cells), and the lip terms of a crack law that
carries tractions (contact, friction). Forms are compiled once; :meth:`evaluate`
reads the current solution. SI units (m, Pa, K in Pa m^1/2).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from xfem_contact.mechanics.fracture.interaction import InteractionIntegral, Lip, Piece, RingResult
from xfem_contact.mechanics.fracture.rings import Ring

__all__ = ["TipIntegrals", "lip_tractions"]


def lip_tractions(problem, upper: int = 1, name: str | None = None) -> list[Lip]:
    """The tractions ``sigma n`` on the two lips of the crack of ``problem`` (UFL), from
    its law's multipliers: none for a law without (``free``). The law's term
    ``int lambda . [v]`` makes the multiplier vector ``lambda`` the traction on side
    -1's lip (``sigma_- n``, ``n`` from side -1 to +1); side +1's lip carries
    ``-lambda``. ``upper``: the side (+1 or -1) that is the upper lip (``theta = pi``)
    in the frame of the tip at hand; ``name``: the tip's crack (default the first)."""
    name = problem.cut.interface_names[0] if name is None else name
    law, ctx = problem.laws[name], problem.contexts[name]
    if ctx.field is None:
        return []
    traction = law.traction_vector(ctx, fields := ctx.fields(problem.space.split(problem.w)))
    measure = ctx.measure
    return [
        Lip(traction, fields.minus, measure, -upper),
        Lip(-traction, fields.plus, measure, upper),
    ]


class TipIntegrals:
    """K_I, K_II, J and G of every crack tip of a problem, on rings around each tip.

    Args:
        problem: A :class:`~xfem_contact.mechanics.problem.Problem` on a cut with a
            crack (``CutMesh(..., tangent=psi)``), homogeneous material around the tips.
        rings: The rings of the q-functions, :class:`Ring` or ``(r_inf, r_sup)`` (m),
            the same for every tip; ``r_inf`` at least the tip cells' size.
        quadrature_degree: Quadrature degree of the uncut cells (default: that of the
            cut cells, ``cut.quadrature_degree``).

    Collective. Raises ValueError without a crack or for a ring the mesh cannot hold.
    """

    def __init__(
        self,
        problem,
        rings: Sequence[Ring | tuple[float, float]],
        quadrature_degree: int | None = None,
    ):
        crack = problem.cut.crack
        if crack is None:
            raise ValueError("TipIntegrals: the problem's cut has no crack (CutMesh tangent=psi)")
        self.problem = problem
        if quadrature_degree is None:
            quadrature_degree = problem.cut.quadrature_degree
        u = problem.space.split(problem.w)
        cut = problem.cut
        pieces = [Piece(u[0], cut.dx(-1)), Piece(u[1], cut.dx(1))]
        material = problem.bulk.materials[1]
        cracks = cut.crack.union
        if cracks is not None and cracks.pair is not None:  # several: no ring holds two
            wide = max((r.r_sup if isinstance(r, Ring) else r[1] for r in rings), default=0.0)
            if wide >= cracks.gap:
                raise ValueError(
                    f"rings: r_sup = {wide:.4g} m reaches another crack (cracks "
                    f"{cracks.pair[0]!r} and {cracks.pair[1]!r} lie {cracks.gap:.4g} m apart)"
                )
        names = crack.tip_names or (cut.interface_names[0],) * len(crack.tips)
        self._names = tuple(names)
        #: One interaction integral per tip, in the order of ``cut.crack.tips``
        self.integrals = [
            InteractionIntegral(
                pieces,
                material,
                tip,
                direction,
                rings,
                lip_tractions(problem, upper, name),
                quadrature_degree=quadrature_degree,
            )
            for tip, direction, upper, name in zip(
                crack.tips, crack.directions, crack.upper_sides, names, strict=True
            )
        ]

    @property
    def tips(self) -> np.ndarray:
        """Tip positions (m), ``(ntips, gdim)``."""
        return self.problem.cut.crack.tips

    def evaluate(self) -> list[list[RingResult]]:
        """Per tip, per ring: K_I, K_II (Pa m^1/2), J and G (J/m^2) of the current
        solution. Collective; the same on every process.

        Raises:
            ValueError: the two sides' materials differ (each side owns its moduli: the
                interaction integral here is that of one homogeneous material).
        """
        for name in dict.fromkeys(self._names):
            sides = self.problem.contexts[name].materials  # the crack's two sides
            if (sides[-1].E, sides[-1].nu) != (sides[1].E, sides[1].nu):
                raise ValueError(
                    f"K, J and G need one material around the tips, but the sides of crack "
                    f"{name!r} differ: side -1 E = {sides[-1].E:.6g} Pa, nu = "
                    f"{sides[-1].nu:.6g}; side +1 E = {sides[1].E:.6g} Pa, nu = "
                    f"{sides[1].nu:.6g}. Set the same E and nu on both sides' materials"
                )
        return [integral.evaluate() for integral in self.integrals]
