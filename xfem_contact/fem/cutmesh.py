"""CutMesh: a mesh cut by a level-set interface, with UFL measures for its sides and interface."""

from __future__ import annotations

import hashlib
import itertools
import warnings
from collections.abc import Mapping

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import numpy.typing as npt
import ufl

from xfem_contact._deprecation import renamed_attribute
from xfem_contact.fem import cut_boundary
from xfem_contact.fem.crack_cut import Crack
from xfem_contact.fem.cut3d_state import cut_state_3d
from xfem_contact.fem.cut_options import cut_options
from xfem_contact.fem.cut_state import INTERFACE, SIDE_MINUS, SIDE_PLUS, CutState, cut_state
from xfem_contact.fem.degree_rules import DegreeRules
from xfem_contact.fem.interface_cells import trace_nullity
from xfem_contact.geometry import cut
from xfem_contact.geometry.crack_union import CrackUnion
from xfem_contact.geometry.levelset import CellMaps, LevelSet, LevelSetCallable
from xfem_contact.quadrature import rules as quadrature
from xfem_contact.quadrature.cell_rules import CellRules, IntegrationPart, marker_space

_SIDE_PARTS = {SIDE_MINUS: (4, 6), SIDE_PLUS: (5, 7)}  # side measure: uncut, cut cells parts
_INTERFACE0 = 10  # measure ids of cut.interface_measure(name): _INTERFACE0 + index
_BOUNDARY0 = 100  # measure ids of cut.ds(side, facets): _BOUNDARY0 + slot
_CUT_CELLS0 = 50  # measure ids of cut.dx_cut(name): _CUT_CELLS0 + index, _CUT_CELLS0 - 1 all
_counter = itertools.count()


class CutMesh:
    """A mesh cut by the zero line (in 3D: surface) of a level set.

    Side -1 is ``phi < 0``, side +1 is ``phi >= 0``; the interface normal points from side
    -1 to side +1. In 2D, cut cells are sub-triangulated into curved 6-node triangles on
    each side and a 3-node curved segment on the interface (straight for ``degree=1``).
    In 3D (:mod:`xfem_contact.fem.cut3d_state`), P1 tetrahedra are cut exactly into
    sub-tetrahedra and interface triangles, and Q1/Q2 hexahedra and P2 tetrahedra get
    Saye's rules. Cut cells are integrated with per-cell runtime rules; uncut cells use
    FFCx's standard rule.

    The cut is a frozen :class:`~xfem_contact.fem.cut_state.CutState` (:attr:`state`),
    built by the constructor; :meth:`update` installs the next one. The attributes
    :attr:`cut_cells`, :attr:`geometry`, :attr:`rules`, :attr:`crack`, ... read the
    current state.

    Args:
        mesh: A triangle, quadrilateral, tetrahedron or hexahedron mesh (affine,
            distorted or curved), of one cell kind.
        levelset: A callable ``phi(x)`` (``x`` of shape ``(3, n)``, read-only on a 3D
            mesh; one value per point) or a scalar DOLFINx Function. Either is
            interpolated in ``degree``, and the interpolant classifies the cells; the cut
            follows the callable's exact zero set or the interpolant's (see
            ``exact_zero_set``). Several interfaces: a mapping ``{name: callable}``, cut
            as one level set ``min_i phi_i`` (checked apart, see
            :func:`xfem_contact.geometry.levelset.union`), each with its own measure
            (:meth:`interface_measure`) and rules.
        degree: Lagrange degree (1 or 2) the level set is interpolated in (P1/P2 on
            simplices, Q1/Q2 on quadrilaterals and hexahedra).
        quadrature_degree: Polynomial degree of the rules on each curved sub-triangle and
            on each interface segment (3D: on each sub-tetrahedron and interface
            triangle; Saye's rules take ``ceil((q + 1) / 2)`` Gauss points per interval);
            default 6, and 16 for a crack (its branch functions vary steeply in the
            cells it cuts next to the tip).
        tangent: For a crack: its tangential level set ``psi`` (a callable or a Function,
            as ``levelset``); the crack is the zero line of ``levelset`` where
            ``psi < 0`` (see :mod:`xfem_contact.fem.crack_cut`), :attr:`crack` its data.
            Several disjoint cracks: ``levelset`` and ``tangent`` mappings ``{name: ...}``
            with the same names (``psi = None``: a closed interface), cut as one pair
            (:mod:`xfem_contact.geometry.crack_union`, ``crack.union``), each with its
            own measure. 2D only.
        tip_points: Gauss points per direction of a tip cell's Duffy rules.
        compression: Integrate the cut cells with compressed rules
            (:func:`~xfem_contact.quadrature.compression.compress_rules`): for an integrand
            of polynomial degree ``p`` (as FFCx takes it for the standard rule: the
            measure's ``quadrature_degree`` metadata or UFL's estimate), each side and
            interface rule of more than ``2 dim P_d`` points is replaced by at most
            ``dim P_d`` of its points with positive weights and the same moments of degree
            ``d = min(p, quadrature_degree)``, for ``dim P_d <= 20`` (``d <= 3`` in 3D,
            ``d <= 5`` in 2D: the cost grows as ``(dim P_d)^3`` per rule; higher degrees
            keep the full rules). On affine P1 tetrahedra the exact planar cut gives the
            rules of degree ``d`` directly (Basix rules on its sub-tetrahedra and
            triangles, the same moments, at any ``d``). Triangles and tetrahedra
            without a crack; default on for P2 and affine P1 tetrahedra, off otherwise.
            :attr:`rules` stay the full rules. A
            (measure, degree) is compressed once per cut, when a form first needs it,
            timed as DOLFINx's ``"xfem_contact: rule compression"``.
        exact_zero_set: With a callable level set, whether the cut follows its exact zero
            set (``True``) or its interpolant's (``False``, as for a Function). In 2D the
            interface nodes then lie on the callable's zero set; in 3D (``degree=2``),
            Saye's rules take the roots on their lines, the sides of their height
            intervals and the interface's area vectors from the callable, so they integrate
            its exact sides and zero set. The forms' :attr:`normal` and the enrichment stay
            the interpolant's, so that a surface integral of the exact zero set meets a
            normal of the interpolant's: on a 3D sphere under hydrostatic pressure the
            contact pressure is then no longer uniform to round-off. Default: ``True`` in
            2D, ``False`` in 3D. ``True`` needs a callable, and in 3D ``degree=2``.

    Example:
        >>> cut = CutMesh(mesh, lambda x: np.hypot(x[0], x[1]) - 0.5)
        >>> area = dolfinx.fem.assemble_scalar(xfem_contact.form(1 * cut.dx(-1)))
    """

    def __init__(
        self,
        mesh: dolfinx.mesh.Mesh,
        levelset: LevelSetCallable | dolfinx.fem.Function,
        degree: int = 2,
        quadrature_degree: int | None = None,
        tangent: LevelSetCallable | dolfinx.fem.Function | None = None,
        tip_points: int = 24,
        compression: bool | None = None,
        exact_zero_set: bool | None = None,
    ):
        options = cut_options(
            mesh, degree, quadrature_degree, tangent is not None, compression, exact_zero_set
        )
        #: Whether a callable level set is cut on its exact zero set (see the constructor)
        self.exact_zero_set = options.exact_zero_set
        self._exact_required = options.exact_required
        self._planar = options.planar
        #: Whether the cut cells are integrated with compressed rules (see the constructor)
        self.compression = options.compression
        self.mesh = mesh
        self.degree = degree
        self.quadrature_degree = options.quadrature_degree
        self.id = next(_counter)
        self.tip_points = int(tip_points)
        self._is_crack = options.crack
        self._boundary_sets: list[tuple[tuple[int, str], np.ndarray]] = []
        self._marker_space = marker_space(mesh)  # one for all the rules, all cuts
        self._install(self._next(levelset, tangent, previous=None))

    def update(
        self,
        levelset: LevelSetCallable | dolfinx.fem.Function | Mapping[str, LevelSetCallable],
        tangent: LevelSetCallable | dolfinx.fem.Function | None = None,
    ) -> CutState:
        """Cut the mesh with a new level set (collective): the next :attr:`state`
        (revision + 1) becomes the current one and is returned; the previous state
        object is left as it was. Compiled forms are reused: call
        :func:`xfem_contact.form` again to integrate on the new cut. With several
        interfaces, give the same names as at construction; a crack takes its new
        ``tangent`` too."""
        state = self._next(levelset, tangent, previous=self.state)
        self._install(state)
        return state

    def _next(self, levelset, tangent, previous: CutState | None) -> CutState:
        """The cut by ``levelset`` (and ``tangent``) following ``previous``. Collective."""
        if self._is_crack != (tangent is not None):
            raise ValueError(
                "tangent: a crack's cut takes its tangential level set psi (the crack "
                "is phi = 0 where psi < 0); an interface's none"
            )
        if self._exact_required and isinstance(levelset, dolfinx.fem.Function):
            raise ValueError(
                "exact_zero_set=True: the level set is a Function (nodal values, no exact "
                "zero set); valid: a callable level set, or exact_zero_set=False"
            )
        exact = self.exact_zero_set
        if self.mesh.topology.dim == 3:
            args3 = (self.degree, self.quadrature_degree)
            return cut_state_3d(
                self.mesh, levelset, *args3, previous=previous, exact_zero_set=exact
            )
        args = (self.degree, self.quadrature_degree, self.tip_points)
        return cut_state(
            self.mesh, levelset, tangent, *args, previous=previous, exact_zero_set=exact
        )

    def _install(self, state: CutState) -> None:
        """Make ``state`` the current cut and rebuild what is derived from it."""
        #: The current cut (a frozen :class:`~xfem_contact.fem.cut_state.CutState`)
        self.state = state
        owned = np.arange(state.cell_sides.size, dtype=np.int32)
        self._standard = {
            SIDE_MINUS: owned[state.cell_sides == -1],
            SIDE_PLUS: owned[state.cell_sides == 1],
        }
        self._cell_rules = {sid: self._rules(state.cut_cells, r) for sid, r in state.rules.items()}
        self._degree_rules = DegreeRules(state, self.quadrature_degree, self._planar, _INTERFACE0)
        self._compressed: dict[tuple[int, int], CellRules] = {}
        self._interface_rules: dict[int, quadrature.RuleSet] = {}
        self._boundary_parts: dict[int, list[IntegrationPart]] = {}

    # -- the current state --------------------------------------------------
    @property
    def revision(self) -> int:
        """Revision of the current cut: 0 at construction, + 1 per update."""
        return self.state.revision

    @property
    def levelset(self) -> LevelSet:
        """The interpolated level set of the current cut."""
        return self.state.levelset

    @property
    def maps(self) -> CellMaps:
        """Cell maps and level-set values of the current cut."""
        return self.state.maps

    @property
    def interface_names(self) -> tuple[str, ...]:
        """Names of the interfaces, in the order of their measure ids."""
        return self.state.interface_names

    @property
    def cell_sides(self) -> npt.NDArray[np.int8]:
        """Side of every owned cell (-1, +1, 0 when cut), ``(num_owned,)``."""
        return self.state.cell_sides

    @property
    def cut_cells(self) -> npt.NDArray[np.int32]:
        """Local indices of the owned cut cells, ``(ncut,)``."""
        return self.state.cut_cells

    @property
    def geometry(self) -> cut.CutGeometry:
        """Sub-triangulation of the cut cells (rows of :attr:`cut_cells`)."""
        return self.state.geometry

    @property
    def rules(self) -> Mapping[int, quadrature.RuleSet]:
        """Per-cut-cell rules of the current cut, by measure id (read-only)."""
        return self.state.rules

    @property
    def cell_interface(self) -> npt.NDArray[np.int64]:
        """Interface (index into :attr:`interface_names`) of every cut cell, ``(ncut,)``."""
        return self.state.cell_interface

    @property
    def crack(self) -> Crack | None:
        """The crack data of the current cut (``None`` for interfaces); several cracks
        cut as one: ``crack.union``."""
        return self.state.crack

    @property
    def cracks(self) -> CrackUnion | None:
        """Deprecated: ``crack.union``."""
        warnings.warn(
            "CutMesh.cracks is deprecated and will be removed in the next release: "
            "use cut.crack.union (cut.crack is the crack data of every cut by cracks)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self._union

    @property
    def _union(self) -> CrackUnion | None:
        return None if self.state.crack is None else self.state.crack.union

    @property
    def num_cut_cells_global(self) -> int:
        """Number of cut cells over all processes."""
        return self.state.num_cut_cells_global

    @property
    def timings(self) -> Mapping[str, float]:
        """Wall time (s) of the current cut: level set, classification and
        sub-triangulation (``"cut"``), per-cell rules (``"quadrature"``)."""
        return self.state.timings

    def side_indicator(self) -> dolfinx.fem.Function:
        """DG0 function of each cell's side (-1, 0 for cut, +1), ghosts included. Collective."""
        V0 = dolfinx.fem.functionspace(self.mesh, ("DG", 0))
        side = dolfinx.fem.Function(V0, name="side")
        side.x.array[V0.dofmap.list[: self.cell_sides.size, 0]] = self.cell_sides
        side.x.scatter_forward()
        return side

    def side_rules(self, side: int) -> quadrature.RuleSet:
        """Per-cut-cell rules of side -1 or +1 (reference points, weights)."""
        if side not in (-1, 1):
            raise ValueError(f"side must be -1 or +1, got {side!r}")
        return self.rules[SIDE_MINUS if side == -1 else SIDE_PLUS]

    @property
    def interface_rules(self) -> quadrature.RuleSet:
        """Per-cut-cell interface rules (weights ``ds / |det J|``, physical normals)."""
        return self.rules[INTERFACE]

    def _interface_index(self, name: str | None) -> int | None:
        """Index of an interface name; None for all of them (or the only one)."""
        if name is None or len(self.interface_names) == 1 and name == self.interface_names[0]:
            return None
        if name not in self.interface_names:
            raise ValueError(f"Unknown interface {name!r}; valid: {list(self.interface_names)}")
        return self.interface_names.index(name)

    def interface_rules_of(self, name: str | None = None) -> quadrature.RuleSet:
        """Interface rules of one interface (the rules of other interfaces' cut cells
        are empty, so rows keep indexing ``cut_cells``); all of them for ``None``."""
        k = self._interface_index(name)
        if k is None:
            return self.interface_rules
        if k not in self._interface_rules:
            self._interface_rules[k] = self.interface_rules.select(self.cell_interface == k)
        return self._interface_rules[k]

    def interface_cells(self, name: str | None = None) -> npt.NDArray[np.int32]:
        """Local indices of the (owned) cut cells of one interface, or of all."""
        k = self._interface_index(name)
        return self.cut_cells if k is None else self.cut_cells[self.cell_interface == k]

    def cell_regions(self) -> dolfinx.fem.Function:
        """DG0 function of the interface each cell belongs to (index into
        :attr:`interface_names`): its cut cells, and the cells inside it or nearest to
        it (owned and ghost cells). Collective."""
        V0 = dolfinx.fem.functionspace(self.mesh, ("DG", 0))
        regions = dolfinx.fem.Function(V0, name="region")
        owned = np.arange(self.cell_sides.size, dtype=np.int32)
        if self._union is not None and len(self.interface_names) > 1:  # of their side -1
            regions.x.array[V0.dofmap.list[owned, 0]] = self._union.cell_crack
        elif (components := self.state.components) is not None and len(components) > 1:
            x = dolfinx.mesh.compute_midpoints(self.mesh, self.mesh.topology.dim, owned).T
            phi = np.array([np.asarray(f(x), dtype=np.float64) for f in components.values()])
            index = np.argmin(phi, axis=0)
            index[self.cut_cells] = self.cell_interface
            regions.x.array[V0.dofmap.list[owned, 0]] = index
        regions.x.scatter_forward()
        return regions

    def interface_measure(self, name: str | None = None) -> ufl.Measure:
        """Measure of one interface (:attr:`dGamma` when there is only one)."""
        k = self._interface_index(name)
        if k is None:
            return self.dGamma
        return ufl.Measure(
            "dx", domain=self.mesh, subdomain_data=self, subdomain_id=_INTERFACE0 + k
        )

    def dx_cut(self, name: str | None = None) -> ufl.Measure:
        """Measure of the whole cut cells of interface ``name`` (of all interfaces for
        ``None``) with the standard rule: for terms that act on the cut cells only, so
        that the other cells are not assembled with a zero integrand."""
        k = self._interface_index(name)
        sid = _CUT_CELLS0 - 1 if k is None else _CUT_CELLS0 + k
        return ufl.Measure("dx", domain=self.mesh, subdomain_data=self, subdomain_id=sid)

    def trace_nullity(self, name: str | None = None) -> npt.NDArray[np.int32]:
        """Per cut cell of interface ``name`` (rows of ``cut_cells``): the nullity of the
        trace of its P1/Q1 vertex functions on its interface piece (see
        :func:`xfem_contact.fem.interface_cells.trace_nullity`); 0 on other cells."""
        rules = self.interface_rules_of(name)
        J = self.maps.jacobian(self.cut_cells[rules.point_rows], rules.points)
        return trace_nullity(self.mesh.topology.cell_name(), rules, np.linalg.det(J))

    def normal_at(self, rules: quadrature.RuleSet) -> npt.NDArray[np.float64]:
        """The unit normal :attr:`normal` (``grad phi_h / |grad phi_h|``) evaluated at
        every point of per-cut-cell ``rules``, shape ``(npoints, gdim)`` (local)."""
        cells = self.cut_cells[rules.point_rows]
        J = self.maps.jacobian(cells, rules.points)
        grad = np.linalg.solve(
            np.transpose(J, (0, 2, 1)), self.maps.grad_ref(cells, rules.points)[..., None]
        )[..., 0]
        return grad / np.linalg.norm(grad, axis=1)[:, None]

    # -- measures -----------------------------------------------------------
    def dx(self, side: int, metadata: dict | None = None) -> ufl.Measure:
        """Measure of side ``-1`` (phi < 0) or ``+1`` (phi >= 0): ``expr * cut.dx(-1)``.

        ``metadata`` (e.g. ``{"quadrature_degree": 4}``) applies to uncut cells, and with
        ``compression`` sets the degree of the cut cells' compressed rules.
        """
        if side not in (-1, 1):
            raise ValueError(f"side must be -1 or +1, got {side!r}")
        sid = SIDE_MINUS if side == -1 else SIDE_PLUS
        return ufl.Measure(
            "dx", domain=self.mesh, subdomain_data=self, subdomain_id=sid, metadata=metadata or {}
        )

    def side_measure_ids(self, subdomain_id: int) -> tuple[int, int] | None:
        """For the id of a side measure (:meth:`dx`): the ids of its two parts, the
        uncut cells (standard rule) and the cut cells (runtime rules), whose sum it is;
        ``None`` for other ids. For :func:`xfem_contact.fem.field_blocks.uncut_field_blocks`."""
        return _SIDE_PARTS.get(subdomain_id)

    split_side_measure = renamed_attribute("CutMesh", "split_side_measure", "side_measure_ids")

    @property
    def dGamma(self) -> ufl.Measure:
        """Measure of the interface (arc length in physical units): ``expr * cut.dGamma``."""
        return ufl.Measure("dx", domain=self.mesh, subdomain_data=self, subdomain_id=INTERFACE)

    @property
    def normal(self) -> ufl.core.expr.Expr:
        """Unit normal of the interface, from side -1 to side +1 (UFL expression)."""
        g = ufl.grad(self.levelset.function)
        return g / ufl.sqrt(ufl.inner(g, g))

    def ds(self, side: int, facets, value: int | None = None) -> ufl.Measure:
        """Measure of the part of exterior facets lying on one side of the interface.

        Args:
            side: -1 or +1.
            facets: Local indices of exterior facets (array), or a facet
                ``MeshTags`` together with ``value``.
            value: The tag value when ``facets`` is a ``MeshTags``.

        Uncut cells' facets use FFCx's standard facet rule; pieces of facets of
        cut cells are runtime rules with ``ufl.FacetNormal`` available. Collective: the
        measure id (in the form's signature) is the same on every process, found by the
        side and a hash of the part's global facet indices, never by local arrays.
        """
        if side not in (-1, 1):
            raise ValueError(f"side must be -1 or +1, got {side!r}")
        facets = self._facet_array(facets, value)
        imap = self.mesh.topology.index_map(self.mesh.topology.dim - 1)
        part = np.concatenate(self.mesh.comm.allgather(imap.local_to_global(facets)))
        key = (side, hashlib.sha256(np.sort(part).astype(np.int64).tobytes()).hexdigest())
        keys = [k for k, _ in self._boundary_sets]
        if key not in keys:
            self._boundary_sets.append((key, facets))
            keys.append(key)
        slot = keys.index(key)
        return ufl.Measure(
            "ds", domain=self.mesh, subdomain_data=self, subdomain_id=_BOUNDARY0 + slot
        )

    def _rules(self, cells, rule) -> CellRules:
        """``rule`` (points, weights, offsets) on ``cells`` as :class:`CellRules`."""
        args = (rule.points, rule.weights, rule.offsets)
        return CellRules(self.mesh, cells, *args, marker_space=self._marker_space)

    def _facet_array(self, facets, value) -> np.ndarray:
        return cut_boundary.facet_array(self.mesh, facets, value)

    def _boundary(self, slot: int) -> list[IntegrationPart]:
        """Standard and runtime parts of boundary set ``slot`` on the current cut."""
        if slot not in self._boundary_parts:
            (side, _), facets = self._boundary_sets[slot]
            self._boundary_parts[slot] = cut_boundary.boundary_parts(self, side, facets)
        return self._boundary_parts[slot]

    def integration_parts(
        self, subdomain_id: int, degree: int | None = None
    ) -> list[IntegrationPart]:
        """Standard and runtime parts of a measure id (for :func:`xfem_contact.form`), the
        runtime rules for an integrand of polynomial ``degree`` (``None``: the full
        rules; see ``compression``)."""
        if subdomain_id >= _BOUNDARY0:
            return self._boundary(subdomain_id - _BOUNDARY0)
        if subdomain_id >= _CUT_CELLS0 - 1:
            k = subdomain_id - _CUT_CELLS0
            name = None if k < 0 else self.interface_names[k]
            return [IntegrationPart("cell", entities=self.interface_cells(name))]
        if subdomain_id >= _INTERFACE0:
            k = subdomain_id - _INTERFACE0
            if subdomain_id not in self._cell_rules:
                r = self.interface_rules_of(self.interface_names[k])
                self._cell_rules[k + _INTERFACE0] = self._rules(self.cut_cells, r)
            return [IntegrationPart("cell", rules=self._runtime_rules(subdomain_id, degree))]
        for side, (uncut, cut_part) in _SIDE_PARTS.items():  # a part of a side measure
            if subdomain_id == uncut:
                return [IntegrationPart("cell", entities=self._standard[side])]
            if subdomain_id == cut_part:
                return [IntegrationPart("cell", rules=self._runtime_rules(side, degree))]
        if subdomain_id not in self._cell_rules:
            raise ValueError(f"Unknown CutMesh measure id {subdomain_id}")
        parts = []
        if subdomain_id in self._standard:
            parts.append(IntegrationPart("cell", entities=self._standard[subdomain_id]))
        parts.append(IntegrationPart("cell", rules=self._runtime_rules(subdomain_id, degree)))
        return parts

    def _runtime_rules(self, sid: int, degree: int | None) -> CellRules:
        """The runtime rules of measure id ``sid`` (a side, the interface or a named
        interface) for an integrand of polynomial ``degree``: with :attr:`compression`,
        those of :mod:`~xfem_contact.fem.degree_rules`, once per state."""
        if not self.compression or degree is None:
            return self._cell_rules[sid]
        rules = self._degree_rules.rules(sid, degree)
        if rules is None:
            return self._cell_rules[sid]
        key = (sid, min(degree, self.quadrature_degree))
        if key not in self._compressed:
            self._compressed[key] = self._rules(self.cut_cells, rules)
        return self._compressed[key]
