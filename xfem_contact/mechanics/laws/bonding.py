"""Linear interface laws: ``free`` (traction-free lips) and ``bonded`` (no jump).

``bonded`` enforces ``[u] = 0`` by a vector multiplier ``lambda`` (the traction
``sigma n`` on side -1, Pa, Cartesian components) with the residual terms
``int lambda.[v] + mu.[u]``, minus the LBB terms of
:class:`~xfem_contact.mechanics.laws.multiplier.MultiplierLaw`.
"""

from __future__ import annotations

import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.mechanics.laws.base import Fields, InterfaceContext, InterfaceLaw
from xfem_contact.mechanics.laws.multiplier import MultiplierLaw


class Free(InterfaceLaw):
    """Traction-free lips (an open crack or gap): no interface terms."""

    name = "free"
    linear = True
    symmetric = True

    @property
    def transmits(self) -> str:
        return "none"


class Bonded(MultiplierLaw):
    """Displacement continuity by a vector multiplier (see the module docstring)."""

    name = "bonded"
    linear = True
    symmetric = True

    def multiplier_components(self, gdim: int) -> int:
        return gdim

    def residual(self, ctx: InterfaceContext, u: Fields, v: Fields) -> ufl.Form:
        lam, mu = u.multiplier, v.multiplier
        F = (ufl.inner(lam, v.jump) + ufl.inner(mu, u.jump)) * ctx.measure
        lbb = self.lbb_terms(ctx, lam, mu, u, v)
        return F if lbb is None else F - lbb

    def state(self, ctx: InterfaceContext, w: dolfinx.fem.Function) -> dict[str, np.ndarray]:
        """``gap``, ``slip`` (m), ``lambda_n``, ``lambda_t`` (Pa) at the rule points
        (``slip`` and ``lambda_t`` tangential parts: ``(npoints, 3)`` in 3D)."""
        n = ctx.normal_at()
        jump, lam = ctx.jump_at(w), ctx.values_at(w, ctx.field)
        return {
            "gap": np.sum(jump * n, axis=1),
            "slip": ctx.tangential_at(jump),
            "lambda_n": np.sum(lam * n, axis=1),
            "lambda_t": ctx.tangential_at(lam),
        }
