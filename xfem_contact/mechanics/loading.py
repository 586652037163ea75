"""Where loads go and how much of them: boundary parts, load factors, load steps.

A :class:`LoadFactor` is the dimensionless parameter ``t`` that scales every
load of a problem (tractions, pressures, body forces through a UFL constant;
prescribed displacements by rescaling their interpolated values). Problems own
one; :func:`load_steps` gives the factors ``t_k = k / n`` of ``n`` steps.
"""

from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

#: A boundary part: local facet indices, or a locator ``x -> bool`` of shape (3, n) -> (n,)
Facets = np.ndarray | Callable[[np.ndarray], np.ndarray]


def boundary_facets(mesh: dolfinx.mesh.Mesh, part: Facets) -> np.ndarray:
    """Local exterior facet indices (int32) of a boundary part. Collective.

    Raises:
        ValueError: if the part holds no facet on any process.
    """
    fdim = mesh.topology.dim - 1
    if callable(part):
        facets = dolfinx.mesh.locate_entities_boundary(mesh, fdim, part)
    else:
        facets = np.asarray(part, dtype=np.int32)
    if mesh.comm.allreduce(facets.size, op=MPI.SUM) == 0:
        raise ValueError("The boundary part holds no boundary facet (does it exist?)")
    return facets


class LoadFactor:
    """The load factor ``t`` (dimensionless) of one problem; ``t = 1`` by default.

    Neumann data and body forces enter the forms multiplied by :attr:`constant`;
    Dirichlet values registered with :meth:`track` are set to ``t`` times their
    full value by :meth:`set`.
    """

    def __init__(self, mesh: dolfinx.mesh.Mesh):
        self.constant = dolfinx.fem.Constant(mesh, dolfinx.default_scalar_type(1.0))
        self._dirichlet: list[tuple[dolfinx.fem.Function, np.ndarray]] = []

    @property
    def value(self) -> float:
        return float(self.constant.value)

    def scaled(self, load: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """``t * load`` (UFL), for loads that enter a form."""
        return self.constant * load

    def track(self, g: dolfinx.fem.Function) -> None:
        """Register the values of a Dirichlet function, taken as their full (t = 1) value.

        ``g`` is rescaled to ``t`` times those values when the factor is set.
        """
        self._dirichlet.append((g, g.x.array.copy()))
        g.x.array[:] *= self.value

    def set(self, t: float) -> None:
        """Set the factor ``t`` (finite) for the next solve."""
        if not np.isfinite(t):
            raise ValueError(f"The load factor must be finite, got {t}")
        self.constant.value = t
        for g, full in self._dirichlet:
            g.x.array[:] = t * full


def load_steps(n: int) -> np.ndarray:
    """The factors ``t_k = k / n``, k = 1..n, of ``n`` equal load steps (n >= 1)."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"The number of load steps must be an integer >= 1, got {n!r}")
    return np.arange(1, n + 1) / n
