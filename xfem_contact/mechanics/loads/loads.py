"""The loads, supports and prescribed displacements of one problem.

:class:`Loads` holds the Dirichlet conditions (:attr:`Loads.bcs`), the load terms of
the residual, the tangential springs and the rotations, each with its own load path
(:mod:`~xfem_contact.mechanics.loads.load_path`), and the pseudo-time ``t``
(:meth:`Loads.set_time`). It works on both sides of a cut mesh or on one plain field
(:mod:`~xfem_contact.mechanics.loads.fields`). SI units (Pa, N/m^3, m, rad).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.subspaces import collapse
from xfem_contact.mechanics.loads.handles import (
    DirichletLoad,
    FormLoad,
    Load,
    RotationLoad,
    TangentialSpring,
    rotation_angle,
)
from xfem_contact.mechanics.loads.load_path import LoadPath, check_stage, stage_path
from xfem_contact.mechanics.loads.parts import Part, boundary_facets, named_parts
from xfem_contact.mechanics.loads.values import finite_number, form_magnitude
from xfem_contact.mechanics.parameters import Parameter

#: A load path: None (factor = t), ``[(t, factor), ...]``, or a stage name
Path = None | str | Sequence[Sequence[float]]
#: The pseudo-time: from 0 (no load) on; a negative time would flip every load of the
#: default path ``f = t``
TIME = Parameter(minimum=0.0)


class Loads:
    """Loads, supports and Dirichlet data of a problem, and its pseudo-time.

    Args:
        fields: The fields loads act on (:class:`~xfem_contact.mechanics.loads.fields.SideFields`
            or :class:`~xfem_contact.mechanics.loads.fields.PlainFields`).
        parts: Named boundary parts (name -> locator or facet indices); default: the
            mesh's built-in names (:func:`~xfem_contact.mechanics.loads.parts.named_parts`).

    Every ``add_*`` is collective, takes a part by name, facet indices or locator,
    and returns a :class:`~xfem_contact.mechanics.loads.handles.Load` handle whose
    ``value`` can be set later without compiling anything. Every ``add_*`` but the
    tangential spring takes ``path=``, its load path (None: factor ``t``;
    ``[(t, f), ...]``; a stage name); ``history=`` is its deprecated name.
    """

    def __init__(self, fields, parts: Mapping[str, Part] | None = None):
        self.fields, self.mesh = fields, fields.mesh
        self._parts = None if parts is None else dict(parts)
        #: The Dirichlet conditions (on the problem's whole space)
        self.bcs: list[dolfinx.fem.DirichletBC] = []
        #: Every load and support added, in order
        self.items: list[Load] = []
        #: Named stages: name -> (start, end) pseudo-times
        self.stages: dict[str, tuple[float, float]] = {}
        self._terms: list = []
        self._time = 1.0
        self._collapsed: dict[tuple, dolfinx.fem.FunctionSpace] = {}  # (component, element)
        #: Incremented by every load, support or condition added (solvers built for an
        #: older revision are rebuilt); setting values does not change it
        self.revision = 0

    # -- parts, stages, time ---------------------------------------------------------
    @property
    def parts(self) -> dict[str, Part]:
        """Named boundary parts (name -> locator or facet indices); add or replace
        entries freely. Collective on first use (the built-in names are found then)."""
        if self._parts is None:
            self._parts = named_parts(self.mesh)
        return self._parts

    @parts.setter
    def parts(self, parts: Mapping[str, Part]) -> None:
        self._parts = dict(parts)

    def facets(self, part: Part) -> np.ndarray:
        """Local exterior facet indices of a part (name, facets or locator). Collective."""
        return boundary_facets(self.mesh, part, self.parts if isinstance(part, str) else None)

    def add_stage(self, name: str, start: float, end: float) -> None:
        """Name the pseudo-time interval ``[start, end]``: a load with ``path=name``
        ramps from 0 at ``start`` to 1 at ``end`` (0 before, 1 after)."""
        self.stages[name] = check_stage(name, start, end)

    @property
    def time(self) -> float:
        """The pseudo-time ``t`` (1 until set)."""
        return self._time

    def set_time(self, t: float) -> None:
        """Set the pseudo-time ``t`` (>= 0; the unloaded state is ``t = 0``): every load
        takes its value ``path(t)`` times its magnitude. Not collective (sets local
        data)."""
        t = TIME.check(t, "pseudo-time t")
        self._time = t
        for load in self.items:
            load.apply(t)

    @property
    def end_time(self) -> float:
        """The last time of every load's path and stage (at least 1)."""
        ends = [load.path.end for load in self.items if load.kind != "tangential spring"]
        return max([1.0, *ends, *(end for _, end in self.stages.values())])

    def _load_path(self, path: Path, history: Path = None) -> LoadPath:
        """The :class:`LoadPath` of ``path`` (or of ``history``, its deprecated name)."""
        if history is not None:
            warnings.warn(
                "history= is deprecated and will be removed in the next release: "
                "use path= (the load path)",
                DeprecationWarning,
                stacklevel=3,
            )
            if path is not None:
                raise ValueError("give the load path once: path= (history= is its old name)")
            path = history
        if isinstance(path, str):
            return stage_path(path, self.stages)
        if isinstance(path, LoadPath):
            return path
        return LoadPath(path)

    def _add(self, load: Load) -> Load:
        load.apply(self._time)
        self.items.append(load)
        self.revision += 1
        return load

    def _sides(self, side) -> tuple:
        sides = self.fields.sides
        if side is None:
            return sides
        if side not in sides:
            valid = [None] + [s for s in sides if s is not None]
            raise ValueError(f"side must be one of {valid} (None: every side), got {side!r}")
        return (side,)

    # -- prescribed displacements ----------------------------------------------------
    def _dirichlet(self, sub, dofs_of: Callable) -> dolfinx.fem.Function:
        """A Dirichlet condition on sub-space ``sub`` at ``dofs_of(spaces)``; its function."""
        if sub.component():
            key = (tuple(sub.component()), sub.ufl_element())
            if key not in self._collapsed:  # one space per component (made collectively)
                self._collapsed[key] = collapse(sub)[0]
            V = self._collapsed[key]
            g = dolfinx.fem.Function(V)
            self.bcs.append(dolfinx.fem.dirichletbc(g, dofs_of((sub, V)), sub))
        else:
            g = dolfinx.fem.Function(sub)
            self.bcs.append(dolfinx.fem.dirichletbc(g, dofs_of(sub)))
        return g

    def dirichlet_dofs(self) -> np.ndarray:
        """The local dofs of the problem's space ``W`` that carry a Dirichlet condition
        (owned and ghost, with repeats), shape ``(m,)``. Not collective."""
        return np.concatenate(
            [np.zeros(0, np.int64)] + [bc.dof_indices()[0].astype(np.int64) for bc in self.bcs]
        )

    def _subspace(self, side, component: int | None):
        sub = self.fields.subspace(side)
        if component is None:
            return sub
        if component not in range(self.mesh.geometry.dim):
            valid = list(range(self.mesh.geometry.dim))
            raise ValueError(f"component must be None or one of {valid}, got {component!r}")
        return sub.sub(component)

    def add_displacement(
        self,
        part: Part,
        value,
        component: int | None = None,
        *,
        path: Path = None,
        history: Path = None,
    ) -> DirichletLoad:
        """Prescribe the displacement (m) on a boundary part, on every side's field.

        Args:
            part: A part name (see :attr:`parts`), facet indices or a locator.
            value: A number, a tuple (the vector, without ``component``) or a callable
                of ``x`` (shape (3, n)) returning (n,) for one component, (gdim, n) else;
                or ``{-1: value, 1: value}``, each side's own.
            component: The one component prescribed (None: all).
            path: The load path (None: factor ``t``; ``[(t, f), ...]``; a stage name).
            history: Deprecated name of ``path``.
        """
        fdim, facets = self.mesh.topology.dim - 1, self.facets(part)
        path = self._load_path(path, history)
        functions = [
            self._dirichlet(
                self._subspace(side, component),
                lambda V: dolfinx.fem.locate_dofs_topological(V, fdim, facets),
            )
            for side in self.fields.sides
        ]
        load = DirichletLoad("displacement", part, path, functions, value, self.fields.sides)
        return self._add(load)

    def add_point_displacement(
        self, point, value: float, component: int, *, path: Path = None, history: Path = None
    ) -> DirichletLoad:
        """Prescribe one displacement component (m) at a mesh node (e.g. to remove
        rigid modes), on every side's field. ``point``: ``[x, y]`` (or ``[x, y, 0]``) on
        a 2D mesh, ``[x, y, z]`` on a 3D one."""
        gdim = self.mesh.geometry.dim
        shapes = ((2,), (3,)) if gdim == 2 else ((3,),)
        try:
            point = np.asarray(point, dtype=float)
        except (TypeError, ValueError):
            point = np.zeros(0)
        if point.shape not in shapes or not np.isfinite(point).all():
            names = "[x, y]" if gdim == 2 else "[x, y, z]"
            raise ValueError(f"point must be {gdim} finite numbers {names} (m), got {point!r}")

        def at_point(x):
            return np.all([np.isclose(x[k], point[k]) for k in range(gdim)], axis=0)

        path = self._load_path(path, history)
        functions, found = [], 0
        for side in self.fields.sides:
            sub = self._subspace(side, component)
            functions.append(
                self._dirichlet(sub, lambda V: dolfinx.fem.locate_dofs_geometrical(V, at_point))
            )
            owned = self.bcs[-1].dof_indices()[1]
            found += self.mesh.comm.allreduce(owned, op=MPI.SUM)
        if found == 0:
            del self.bcs[-len(functions) :]
            raise ValueError(f"point: no mesh node at {point.tolist()} to fix")
        return self._add(DirichletLoad("point displacement", None, path, functions, value))

    def add_rotation(
        self,
        part: Part,
        *,
        angle: float | None = None,
        angle_deg: float | None = None,
        centre=(0.0, 0.0),
        path: Path = None,
        history: Path = None,
    ) -> RotationLoad:
        """Rotate a boundary part rigidly by ``angle`` (rad) or ``angle_deg`` (degrees),
        counter-clockwise about ``centre`` (m), times the factor ``path(t)`` (2D meshes):
        ``u = (Q - I)(X - c)`` on every side's field. Warns for ``angle`` outside
        [-2 pi, 2 pi] (degrees given as radians?)."""
        if self.mesh.geometry.dim != 2:
            raise ValueError(
                "add_rotation turns a part in the plane (2D meshes); on a 3D mesh prescribe "
                "the rotation's displacement with add_displacement(part, callable)"
            )
        if (angle is None) == (angle_deg is None):
            raise ValueError("Give the rotation as angle= (rad) or angle_deg= (degrees), once")
        if angle_deg is not None:
            angle = np.deg2rad(finite_number(angle_deg, "angle_deg"))
        else:
            angle = rotation_angle(angle)
        try:
            centre = np.asarray(centre, dtype=float)
        except (TypeError, ValueError):
            centre = np.zeros(0)
        if centre.shape not in ((2,), (3,)) or not np.isfinite(centre).all():
            raise ValueError(f"centre must be 2 finite numbers [x, y] (m), got {centre!r}")
        centre = centre[:2]
        fdim, facets = self.mesh.topology.dim - 1, self.facets(part)
        functions, arms = [], []
        for side in self.fields.sides:
            g = self._dirichlet(
                self.fields.subspace(side),
                lambda V: dolfinx.fem.locate_dofs_topological(V, fdim, facets),
            )
            functions.append(g)
            arms.append(g.function_space.tabulate_dof_coordinates()[:, :2] - centre)
        nodes = self.fields.rotated_nodes(facets)
        path = self._load_path(path, history)
        return self._add(RotationLoad(part, path, functions, arms, angle, centre, nodes))

    def rotate_bodies(self, w: dolfinx.fem.Function, t_from: float, t_to: float) -> None:
        """Predictor of a load step: turn the bodies each rotation drives by its angle
        between pseudo-times ``t_from`` and ``t_to``. Collective."""
        for load in self.items:
            if isinstance(load, RotationLoad):
                load.rotate(w, t_from, t_to)
        w.x.scatter_forward()

    # -- loads of the residual -------------------------------------------------------
    def _form_load(self, kind, part, magnitude, constant, path, terms) -> FormLoad:
        load = FormLoad(kind, part, path, magnitude, constant, self.mesh)
        for term in terms(load.factor):
            self._terms.append(term)
        return self._add(load)

    def add_traction(
        self,
        part: Part,
        traction,
        side: int | None = None,
        *,
        path: Path = None,
        history: Path = None,
    ):
        """Surface traction (Pa, a vector: tuple, UFL or callable of the UFL ``x``) on a
        boundary part, on every side or ``side``. Returns its handle."""
        facets, sides = self.facets(part), self._sides(side)
        gdim = self.mesh.geometry.dim
        t, constant = form_magnitude(self.mesh, traction, (gdim,), "traction")
        return self._form_load(
            "traction",
            part,
            t,
            constant,
            self._load_path(path, history),
            lambda f: [
                ufl.inner(f * t, self.fields.test(s)) * self.fields.ds(s, facets) for s in sides
            ],
        )

    def add_pressure(
        self,
        part: Part,
        pressure,
        side: int | None = None,
        *,
        path: Path = None,
        history: Path = None,
    ):
        """Pressure (Pa; positive pushes into the body: ``t = -p n``) on a boundary part:
        a number, UFL or a callable of the UFL ``x``. Returns its handle."""
        facets, sides = self.facets(part), self._sides(side)
        p, constant = form_magnitude(self.mesh, pressure, (), "pressure")
        n = ufl.FacetNormal(self.mesh)
        return self._form_load(
            "pressure",
            part,
            p,
            constant,
            self._load_path(path, history),
            lambda f: [
                ufl.inner(-f * p * n, self.fields.test(s)) * self.fields.ds(s, facets)
                for s in sides
            ],
        )

    def add_body_force(
        self, force, side: int | None = None, *, path: Path = None, history: Path = None
    ):
        """Body force density (N/m^3, a vector) on every side or ``side``."""
        sides = self._sides(side)
        gdim = self.mesh.geometry.dim
        b, constant = form_magnitude(self.mesh, force, (gdim,), "force")
        return self._form_load(
            "body force",
            None,
            b,
            constant,
            self._load_path(path, history),
            lambda f: [ufl.inner(f * b, self.fields.test(s)) * self.fields.dx(s) for s in sides],
        )

    def linear_form(self) -> ufl.Form:
        """The loads' terms ``L(v)`` (UFL, linear in the test functions)."""
        if not self._terms:
            return self.fields.zero_form()
        return sum(self._terms[1:], self._terms[0])

    @property
    def has_terms(self) -> bool:
        """Whether any load enters the residual (tractions, pressures, body forces)."""
        return bool(self._terms)

    # -- supports --------------------------------------------------------------------
    def add_tangential_spring(self, part: Part, stiffness: float) -> TangentialSpring:
        """Hold the tangential displacement of a boundary part by a spring of stiffness
        ``k`` (Pa/m): ``int k (u . t)(v . t) ds`` on every side's field (``t`` the
        boundary's tangent): ``u_t = 0`` along a curved boundary while the normal
        motion stays free. Not ramped (a support)."""
        facets = self.facets(part)
        k = dolfinx.fem.Constant(self.mesh, dolfinx.default_scalar_type(1.0))
        spring = TangentialSpring(part, facets, k)
        spring.value = stiffness
        return self._add(spring)

    def spring_terms(self, u: Sequence, v: Sequence):
        """The springs' terms (UFL, bilinear in ``u``, ``v``: the displacement of each
        side, in the order of the fields' sides), or None."""
        n = ufl.FacetNormal(self.mesh)
        t = ufl.as_vector([-n[1], n[0]])
        terms = [
            s.stiffness * ufl.dot(u[i], t) * ufl.dot(v[i], t) * self.fields.ds(side, s.facets)
            for s in self.items
            if isinstance(s, TangentialSpring)
            for i, side in enumerate(self.fields.sides)
        ]
        return sum(terms[1:], terms[0]) if terms else None
