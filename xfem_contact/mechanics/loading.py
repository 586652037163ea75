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

from xfem_contact.fem.subspaces import collapse

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


#: A load: a number, a UFL expression, or a callable of the UFL coordinate ``x``
Load = float | ufl.core.expr.Expr | Callable


class Loads:
    """Dirichlet data and loads of a problem on an enriched space (both sides' fields).

    Holds the Dirichlet conditions (``_bcs``), the load terms of the residual
    (``_rhs``) and the :class:`LoadFactor` that scales all of them.

    Args:
        mesh: The mesh.
        space: The :class:`~xfem_contact.fem.enrichment.EnrichedSpace` (fields 0, 1:
            the displacements of sides -1, +1).
    """

    def __init__(self, mesh: dolfinx.mesh.Mesh, space):
        self.mesh, self.space = mesh, space
        self._bcs: list[dolfinx.fem.DirichletBC] = []
        self._rhs: list = []
        self._x = ufl.SpatialCoordinate(mesh)
        #: Scales every load and prescribed displacement
        self.load_factor = LoadFactor(mesh)
        #: Incremented by every load or Dirichlet condition added (solvers built for an
        #: older revision are rebuilt)
        self.loads_revision = 0

    def facets(self, part: Facets) -> np.ndarray:
        """Local exterior facet indices of a boundary part; error if it is empty."""
        return boundary_facets(self.mesh, part)

    def _ufl(self, value: Load):
        if isinstance(value, ufl.core.expr.Expr) or not callable(value):
            return ufl.as_ufl(value)
        return value(self._x)

    def add_displacement(self, part: Facets, value, component: int | None = None) -> None:
        """Prescribe the displacement (m) on a boundary part, on both sides' fields.

        ``value``: a number or a callable of ``x`` (shape ``(3, n)``) returning
        ``(n,)`` for one component or ``(gdim, n)`` for the vector.
        """
        fdim = self.mesh.topology.dim - 1
        facets = self.facets(part)
        for field in (0, 1):
            sub = self.space.W.sub(field)
            if component is not None:
                sub = sub.sub(component)
            V, _ = collapse(sub)
            g = dolfinx.fem.Function(V)
            if callable(value):
                g.interpolate(value)
            else:
                g.x.array[:] = value
            self.load_factor.track(g)
            dofs = dolfinx.fem.locate_dofs_topological((sub, V), fdim, facets)
            self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))
            self.loads_revision += 1

    def add_point_displacement(self, point, value: float, component: int) -> None:
        """Fix one displacement component at a mesh node (e.g. to remove rigid modes)."""
        point = np.asarray(point, dtype=float)

        def at_point(x):
            return np.isclose(x[0], point[0]) & np.isclose(x[1], point[1])

        found = 0
        for field in (0, 1):
            sub = self.space.W.sub(field).sub(component)
            V, _ = sub.collapse()
            dofs = dolfinx.fem.locate_dofs_geometrical((sub, V), at_point)
            found += self.mesh.comm.allreduce(dofs[0].size, op=MPI.SUM)
            g = dolfinx.fem.Function(V)
            g.x.array[:] = value
            self.load_factor.track(g)
            self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))
            self.loads_revision += 1
        if found == 0:
            raise ValueError(f"No mesh node at {point.tolist()} to fix")

    def add_traction(self, part: Facets, traction: Load, side: int | None = None) -> None:
        """Surface traction (Pa) on a boundary part; ``side`` restricts it to one side.

        Scaled by the load factor, as every load."""
        facets = self.facets(part)
        t = self.load_factor.scaled(self._ufl(traction))
        for s in (-1, 1) if side is None else (side,):
            v = self.space.test()[0 if s == -1 else 1]
            self._rhs.append(ufl.inner(t, v) * self.space.cut.ds(s, facets))
            self.loads_revision += 1

    def add_pressure(self, part: Facets, pressure: Load, side: int | None = None) -> None:
        """Pressure (Pa, positive pushes into the body) on a boundary part: t = -p n."""
        n = ufl.FacetNormal(self.mesh)
        p = self._ufl(pressure)
        self.add_traction(part, -p * n, side)

    def add_body_force(self, force: Load, side: int | None = None) -> None:
        """Body force density (N/m^3) on one side or both."""
        f = self.load_factor.scaled(self._ufl(force))
        for s in (-1, 1) if side is None else (side,):
            v = self.space.test()[0 if s == -1 else 1]
            self._rhs.append(ufl.inner(f, v) * self.space.cut.dx(s))
            self.loads_revision += 1

    def linear_form(self) -> ufl.Form:
        if not self._rhs:
            return ufl.ZeroBaseForm((ufl.TestFunction(self.space.W),))
        return sum(self._rhs[1:], self._rhs[0])
