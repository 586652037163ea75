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

from xfem_contact.fem.evaluation import cell_dofs, lagrange_element
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
        self._dirichlet: list[tuple[dolfinx.fem.Function, Callable[[float], np.ndarray]]] = []

    @property
    def value(self) -> float:
        return float(self.constant.value)

    def scaled(self, load: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
        """``t * load`` (UFL), for loads that enter a form."""
        return self.constant * load

    def track(
        self, g: dolfinx.fem.Function, at: Callable[[float], np.ndarray] | None = None
    ) -> None:
        """Register a Dirichlet function: by default its values are the full (t = 1)
        ones and ``g`` is rescaled to ``t`` times them whenever the factor is set;
        ``at(t)`` instead gives its whole array at factor ``t`` (a prescribed motion
        that is not proportional to ``t``, e.g. a rotation by ``t alpha``)."""
        if at is None:
            full = g.x.array.copy()

            def at(t: float, full=full) -> np.ndarray:
                return t * full

        self._dirichlet.append((g, at))
        g.x.array[:] = at(self.value)

    def set(self, t: float) -> None:
        """Set the factor ``t`` (finite) for the next solve."""
        if not np.isfinite(t):
            raise ValueError(f"The load factor must be finite, got {t}")
        self.constant.value = t
        for g, at in self._dirichlet:
            g.x.array[:] = at(t)


def load_steps(n: int) -> np.ndarray:
    """The factors ``t_k = k / n``, k = 1..n, of ``n`` equal load steps (n >= 1)."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"The number of load steps must be an integer >= 1, got {n!r}")
    return np.arange(1, n + 1) / n


def rotated_nodes(space, facets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The displacement nodes of the bodies touching boundary ``facets``: the local
    dofs of ``W`` (one row per node, ``(k, 2)``) and the nodes' reference positions
    (m), ``(k, 2)``, over the local cells (owned and ghost) of each side whose cells
    hold those facets, in the same regions (the inclusion, for side -1). Collective."""
    cut = space.cut
    mesh, tdim = cut.mesh, cut.mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f2c = mesh.topology.connectivity(tdim - 1, tdim)
    touching = np.unique(np.concatenate([f2c.links(f) for f in facets] or [[]])).astype(np.int32)
    side = cut.side_indicator()
    sides = np.rint(side.x.array[side.function_space.dofmap.list[:, 0]]).astype(np.int64)
    regions = cut.cell_regions()
    region = np.rint(regions.x.array[regions.function_space.dofmap.list[:, 0]]).astype(np.int64)
    comm = mesh.comm
    dofs, nodes = [np.zeros((0, 2), dtype=np.int32)], [np.zeros((0, 2))]
    for field, s in ((0, -1), (1, 1)):
        here = touching[(sides[touching] == s) | (sides[touching] == 0)]
        held = np.unique(np.concatenate(comm.allgather(region[here] if s == -1 else here[:0])))
        if comm.allreduce(here.size, op=MPI.SUM) == 0:
            continue
        body = (sides == s) | (sides == 0)
        if s == -1:
            body &= np.isin(region, held)
        cells = np.flatnonzero(body).astype(np.int32)
        V = space.W.sub(field)
        points = lagrange_element(V).points
        X = cut.maps.push_forward_lattice(cells, points)[:, :2]
        d = cell_dofs(V, cells).reshape(-1, 2)
        d, first = np.unique(d, axis=0, return_index=True)
        dofs.append(d)
        nodes.append(X[first])
    return np.concatenate(dofs), np.concatenate(nodes)


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
        #: Rotation conditions: ((dofs (k, 2), reference nodes (k, 2)), angle, centre)
        self._rotations: list = []
        #: Tangential springs: (facets, stiffness in Pa/m)
        self._springs: list[tuple[np.ndarray, float]] = []
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

    def add_rotation(self, part: Facets, angle: float, centre=(0.0, 0.0)) -> None:
        """Rotate a boundary part rigidly: ``u = (Q(t angle) - I)(X - c)`` on both sides'
        fields, ``Q`` the rotation by ``t angle`` (rad, counter-clockwise), ``c`` the
        centre (m), ``t`` the load factor (the angle is ramped, not the displacement:
        each load step is an exact rotation)."""
        if not np.isfinite(angle):
            raise ValueError(f"The rotation angle must be finite, got {angle}")
        fdim = self.mesh.topology.dim - 1
        facets = self.facets(part)
        centre = np.asarray(centre, dtype=float)[:2]
        for field in (0, 1):
            sub = self.space.W.sub(field)
            V, _ = collapse(sub)
            g = dolfinx.fem.Function(V)
            arm = V.tabulate_dof_coordinates()[:, :2] - centre  # (nodes, 2)

            def at(t: float, arm=arm) -> np.ndarray:
                c, s = np.cos(t * angle), np.sin(t * angle)
                return np.column_stack(
                    [(c - 1) * arm[:, 0] - s * arm[:, 1], s * arm[:, 0] + (c - 1) * arm[:, 1]]
                ).ravel()

            self.load_factor.track(g, at)
            dofs = dolfinx.fem.locate_dofs_topological((sub, V), fdim, facets)
            self._bcs.append(dolfinx.fem.dirichletbc(g, dofs, sub))
            self.loads_revision += 1
        self._rotations.append((rotated_nodes(self.space, facets), angle, centre))

    def rotate_bodies(self, w: dolfinx.fem.Function, t_from: float, t_to: float) -> None:
        """Predictor of a load step: rotate the deformed configuration of each body a
        rotation condition drives by its angle times ``t_to - t_from`` (exact for a
        rigidly turning body, and objective laws keep its stresses). Collective."""
        for (dofs, X), angle, centre in self._rotations:
            delta = (t_to - t_from) * angle
            if delta == 0.0:
                continue
            Q = np.array([[np.cos(delta), -np.sin(delta)], [np.sin(delta), np.cos(delta)]])
            x = X + w.x.array[dofs]
            w.x.array[dofs] = (x - centre) @ Q.T + centre - X
        w.x.scatter_forward()

    def add_tangential_spring(self, part: Facets, stiffness: float) -> None:
        """Hold the tangential displacement of a boundary part at zero by a stiff
        spring, ``int k (u . t)(v . t) ds`` on both sides' fields (``t`` the boundary's
        tangent, ``k`` in Pa/m): ``u_t = 0`` along a curved boundary (e.g. to stop a
        ring from spinning while its radial motion stays free). Not scaled by the load
        factor (it is a support, not a load)."""
        if not stiffness > 0.0:
            raise ValueError(f"The spring stiffness must be > 0 Pa/m, got {stiffness}")
        self._springs.append((self.facets(part), float(stiffness)))
        self.loads_revision += 1

    def spring_terms(self, u, v):
        """The springs' terms of the residual (UFL, bilinear in ``u``, ``v``: split
        unknowns and tests of both sides), or None."""
        n = ufl.FacetNormal(self.mesh)
        t = ufl.as_vector([-n[1], n[0]])
        terms = [
            k * ufl.dot(u[i], t) * ufl.dot(v[i], t) * self.space.cut.ds(side, facets)
            for facets, k in self._springs
            for i, side in enumerate((-1, 1))
        ]
        return sum(terms[1:], terms[0]) if terms else None

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
