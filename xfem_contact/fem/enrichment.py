"""Heaviside-enriched displacement spaces as mixed function spaces.

``u = sum_i N_i u_i + sum_{i in cut supports} N_i (H - H(x_i)) a_i`` is the same
field as one displacement per side, ``u = u_-`` on side -1 and ``u = u_+`` on
side +1, each living on the cells its side touches. We use the latter: a mixed
space ``(u_-, u_+[, lambda])`` whose dofs outside the support of their side (or,
for the multiplier, outside the cut cells) are *inactive* and removed from every
solve by the prolongation of :mod:`xfem_contact.fem.prolongation`: the
system has exactly standard + enriched dofs.
"""

from __future__ import annotations

import logging
import typing
from collections.abc import Sequence

import basix.ufl
import dolfinx.fem
import dolfinx.la
import numpy as np
import numpy.typing as npt
import ufl
from mpi4py import MPI

from xfem_contact.fem.aggregation import (
    Aggregation,
    abs_det_at,
    aggregate,
    cell_areas,
    check_threshold,
    side_areas,
)
from xfem_contact.fem.branch import (
    ROUND_OFF,
    UFL,
    branch_values,
    checked_tip_basis,
    side_values,
    tied_values,
)
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.subspaces import collapse
from xfem_contact.fem.tip_dofs import branch_support, checked_tip_dofs, ramp_degree
from xfem_contact.fem.tip_scale import default_tip_radius
from xfem_contact.geometry.crack import CROSSED

_logger = logging.getLogger(__name__)


class DofCounts(typing.NamedTuple):
    """Global numbers of active dofs (scalar components)."""

    standard: int  # dofs of the standard (unenriched) displacement space
    enriched: int  # extra dofs of nodes whose support is cut
    multiplier: int  # interface multiplier dofs (0 without multiplier)

    @property
    def total(self) -> int:
        return self.standard + self.enriched + self.multiplier


class EnrichedSpace:
    """Displacement per side (Lagrange ``degree``, vector) and an optional
    interface multiplier (Lagrange on the nodes of cut cells, scalar or vector).

    Args:
        cut: The cut mesh.
        degree: Displacement degree, 1 or 2 (P1/P2 on triangles, Q1/Q2 on quads).
        multiplier: Number of multiplier components: 0 (none), 1 (a scalar,
            e.g. the normal contact pressure) or ``gdim`` (a vector: the
            interface traction, Cartesian or normal/tangential).
        min_support_fraction: A side's dofs whose support holds less than this
            fraction of the support's area on that side are dropped (set
            inactive) to keep the operator well conditioned; 0 keeps all.
        multipliers: Instead of ``multiplier``, one multiplier field per entry
            ``(components, interface name)`` or ``(components, interface name, degree)``
            (fields 2, 3, ... of ``W``; Lagrange of ``degree``, 1 or 2, default 1), each
            active on the cut cells of its interface only (``None``: all).
        tip_radius: For a cut by a crack (``cut.crack``): the tip enrichment's radius
            (m): the vertices within it of a tip carry the four branch functions
            (geometric enrichment, with the ramp below); ``"auto"``: a fixed fraction
            of the tips' crack length (:func:`~xfem_contact.fem.tip_scale.default_tip_radius`,
            None without a crack); ``None``: the tip cells' nodes. A radius below the tip
            cells' diameter takes the ramp 1 on the tip cells' vertices instead, with a
            logged warning.
        aggregation: Cell aggregation (:mod:`~xfem_contact.fem.aggregation`): a cut cell
            whose part on a side is below this fraction of its area is badly cut, and the
            dofs of that side's displacement in badly cut cells alone are extended from a
            root cell's (:attr:`aggregation`); the multipliers likewise, by the interface's
            measure in a cell; None: off.
        tip_basis: The functions of a crack's branch dofs: ``"plain"``, ``R F_k``;
            ``"shifted"``, ``R F_k - I(R F_k)`` with ``I`` the interpolant on the
            vertices (the same space for degree 2, where ``N_i I(R F_k)`` is a standard
            function; degree 1 and cell aggregation take ``"plain"`` only); ``"auto"``
            (default): ``"shifted"`` for degree 2 without aggregation, else ``"plain"``.
        tip_dofs: ``"nodal"`` (default): every vertex of the zone carries its own branch
            unknowns; ``"gathered"``: one unknown per tip, branch function and component,
            with a smooth cut-off for the ramp (:mod:`~xfem_contact.fem.tip_dofs`; needs
            a tip radius).

    A crack's multipliers live on the nodes of the cells it crosses (none on a tip
    cell's own: the lips' traction there oscillates, ``docs/crack_enrichment.md``). A crack
    (see :mod:`xfem_contact.fem.crack_cut`) adds a last field, the branch
    dofs ``b`` (Lagrange ``degree``, ``4 gdim`` components), and ties the two sides'
    dofs of every node whose support the crack does not cut completely (it holds a tip
    or the crack's extension): one unknown for both in the reduced system
    (:attr:`ties`). The displacement of side ``s`` is then ``u_s + R sum_k F_k b_k``
    (:meth:`displacements`), with the branch functions ``F_k`` of
    :mod:`xfem_contact.fem.branch` at ``r = sqrt(phi^2 + psi^2)``,
    ``theta = s |atan2(phi, psi)|`` (``phi``, ``psi``: the crack's level sets, signed
    distances). With a ``tip_radius``, ``R`` is the :attr:`ramp` (corrected X-FEM, Fries
    2008): the P1 function 1 on the vertices within the radius, 0 on the others; every
    node of the cells where ``R > 0`` has branch dofs, so ``R F_k`` is in the space and
    no cell blends. ``R = 1``
    without a radius (topological). With ``tip_basis="shifted"`` the branch dofs'
    functions are ``R F_k - I(R F_k)`` (:attr:`interpolants`: per side, ``I`` on the
    vertices; at a vertex whose two sides share one unknown, both sides take the
    functions of the side the vertex lies on, so the tied sides stay continuous): they
    vanish at the vertices and, far from a tip, are ``O(h^2)`` where ``R F_k`` is
    ``O(1)``, so the stiffness is assembled without the cancellation of ``R F_k``
    against the standard functions (the stable GFEM shift, Babuška and Banerjee 2012).
    """

    def __init__(
        self,
        cut: CutMesh,
        degree: int,
        multiplier: int = 0,
        min_support_fraction: float = 0.0,
        multipliers: Sequence[tuple[int, str | None]] | None = None,
        tip_radius: float | str | None = None,
        aggregation: float | None = None,
        tip_basis: str = "auto",
        tip_dofs: str = "nodal",
    ):
        if degree not in (1, 2):
            raise ValueError(f"Displacement degree must be 1 or 2, got {degree}")
        if not 0.0 <= min_support_fraction < 1.0:
            raise ValueError(f"min_support_fraction must be in [0, 1), got {min_support_fraction}")
        mesh = cut.mesh
        self.cut, self.degree = cut, degree
        gdim = mesh.geometry.dim
        cell = mesh.basix_cell()
        displacement = basix.ufl.element("Lagrange", cell, degree, shape=(gdim,))
        elements = [displacement, displacement]
        if multipliers is None:
            multipliers = [(multiplier, None)] if multiplier else []
        multipliers = [(int(m[0]), m[1], int(m[2]) if len(m) > 2 else 1) for m in multipliers]
        for components, _, multiplier_degree in multipliers:
            if components not in (1, gdim):
                raise ValueError(f"A multiplier must have 1 or {gdim} components, got {components}")
            if multiplier_degree not in (1, 2):
                raise ValueError(f"A multiplier's degree must be 1 or 2, got {multiplier_degree}")
            shape = () if components == 1 else (gdim,)
            elements.append(basix.ufl.element("Lagrange", cell, multiplier_degree, shape=shape))
        if multiplier not in (0, 1, gdim):
            raise ValueError(f"multiplier must have 0, 1 or {gdim} components, got {multiplier}")
        #: ``(field, components, interface name)`` of each multiplier field
        self.multiplier_fields = [(2 + k, c, name) for k, (c, name, _) in enumerate(multipliers)]
        #: The Lagrange degree of each multiplier field, by field
        self.multiplier_degrees = {2 + k: d for k, (_, _, d) in enumerate(multipliers)}
        self.multiplier_components = multipliers[0][0] if multipliers else 0
        self.has_multiplier = bool(multipliers)
        #: The field of the branch dofs (None without a crack)
        self.branch_field: int | None = None
        if isinstance(tip_radius, str):
            if tip_radius != "auto":
                raise ValueError(
                    f"tip_radius must be a length (m), 'auto' or None, got {tip_radius!r}"
                )
            tip_radius = None if cut.crack is None else default_tip_radius(cut)
        if cut.crack is not None:
            elements.append(basix.ufl.element("Lagrange", cell, 1, shape=(4 * gdim,)))
            self.branch_field = len(elements) - 1
        elif tip_radius is not None:
            raise ValueError("tip_radius: the cut has no crack (CutMesh(..., tangent=psi))")
        if tip_radius is not None and not (np.isfinite(tip_radius) and tip_radius > 0):
            raise ValueError(f"tip_radius must be a positive length (m), got {tip_radius!r}")
        if cut.crack is not None and cut.crack.union is not None:  # several cracks
            cut.crack.union.check_tip_radius(tip_radius)  # each tip zone within its crack's
        self.tip_radius = tip_radius
        self.tip_dofs = checked_tip_dofs(tip_dofs, tip_radius if cut.crack is not None else 0)
        #: The ramp ``R`` of the branch functions (Lagrange of :func:`ramp_degree`, set
        #: with the active dofs), or None
        self.ramp: dolfinx.fem.Function | None = None
        if self.branch_field is not None and tip_radius is not None:
            R = ("Lagrange", ramp_degree(self.tip_dofs, degree, aggregation is not None))
            self.ramp = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, R))
        self.W = dolfinx.fem.functionspace(mesh, basix.ufl.mixed_element(elements))
        extent = mesh.comm.allreduce(float(np.abs(mesh.geometry.x).max()), op=MPI.MAX)
        #: Level set values (m) taken for 0: a node on a crack's line
        self.round_off = ROUND_OFF * extent
        self.tip_basis = checked_tip_basis(tip_basis, degree, aggregation is not None)
        #: Per side, ``I(R F_k)`` (four P1 functions, set with the active dofs) with
        #: ``tip_basis="shifted"``, else None
        self.interpolants: dict[int, tuple[dolfinx.fem.Function, ...]] | None = None
        if self.branch_field is not None and self.tip_basis == "shifted":
            P1 = dolfinx.fem.functionspace(mesh, ("Lagrange", 1))
            self.interpolants = {
                s: tuple(dolfinx.fem.Function(P1) for _ in range(4)) for s in (-1, 1)
            }
        self.min_support_fraction = min_support_fraction
        check_threshold(aggregation)
        self.aggregation_threshold = aggregation
        self._aggregation: Aggregation | None = None
        self._collapsed: dict[int, tuple[dolfinx.fem.FunctionSpace, npt.NDArray]] = {}
        self._active = self._active_dofs()
        self._scalar: tuple | None = None  # one displacement component, its nodes

    # -- fields -------------------------------------------------------------
    def field_names(self) -> list[str]:
        """Output names of the fields: ``u_minus``, ``u_plus``, then ``multiplier``
        (``multiplier_NAME`` per interface when several have one)."""
        names = ["u_minus", "u_plus"]
        one = len(self.multiplier_fields) == 1
        names += [
            "multiplier" if one else f"multiplier_{name}" for _, _, name in self.multiplier_fields
        ]
        return names + ([] if self.branch_field is None else ["branch"])

    def displacement_sides(self) -> list[tuple[str, int]]:
        """``(label, side)`` of the displacement fields 0 and 1."""
        return [("minus", -1), ("plus", 1)]

    def trial(self) -> tuple:
        """``(u_minus, u_plus[, lambda])`` trial functions (:meth:`split`)."""
        return self.split(ufl.TrialFunction(self.W))

    def test(self) -> tuple:
        """``(v_minus, v_plus[, mu])`` test functions (:meth:`split`)."""
        return self.split(ufl.TestFunction(self.W))

    def split(self, w) -> tuple:
        """The fields of ``w`` (a Function, trial or test function on ``W``), the
        displacements of both sides enriched by the branch functions with a crack."""
        return self.displacements(ufl.split(w))

    def displacements(self, fields: Sequence) -> tuple:
        """``fields`` (of ``ufl.split``) with fields 0 and 1 the displacements of sides
        -1 and +1: ``u_s + sum_k F_k(s) b_k`` with a crack, else unchanged."""
        if self.branch_field is None:
            return tuple(fields)
        b, gdim = fields[self.branch_field], self.cut.mesh.geometry.dim
        out = list(fields)
        for i, side in ((0, -1), (1, 1)):
            F = self.branch_functions(side)
            out[i] = fields[i] + ufl.as_vector(
                [sum(F[k] * b[gdim * k + c] for k in range(4)) for c in range(gdim)]
            )
        return tuple(out)

    def branch_functions(self, side: int) -> tuple:
        """The functions of the four branch dofs (m^1/2, UFL) on side ``side`` of the
        crack: the branch functions, times the :attr:`ramp` with a tip radius, minus
        their :attr:`interpolants` with ``tip_basis="shifted"``."""
        phi, psi = self.cut.levelset.function, self.cut.crack.tangent.function
        theta = side * abs(ufl.atan2(phi, psi))
        F = branch_values(ufl.sqrt(phi**2 + psi**2), theta, UFL)
        if self.ramp is not None:
            F = tuple(self.ramp * f for f in F)
        if self.interpolants is not None:
            F = tuple(f - g for f, g in zip(F, self.interpolants[side], strict=True))
        return F

    def subspace(self, field: int) -> dolfinx.fem.FunctionSpace:
        """Sub-space of field 0 (side -1), 1 (side +1) or 2 (multiplier)."""
        return self.W.sub(field)

    def field_space(self, field: int) -> tuple[dolfinx.fem.FunctionSpace, npt.NDArray]:
        """Field ``field`` as a space of its own and the dof of ``W`` behind each of its
        local dofs (:func:`~xfem_contact.fem.subspaces.collapse`), made once per field.
        Collective the first time for a field."""
        if field not in self._collapsed:
            self._collapsed[field] = collapse(self.W.sub(field))
        return self._collapsed[field]

    def field(self, w: dolfinx.fem.Function, field: int, name: str | None = None):
        """A copy of field ``field`` of ``w`` (a Function on ``W``) on its own space
        (owned and ghost values copied; no communication after the first call)."""
        V, parent = self.field_space(field)
        u = dolfinx.fem.Function(V, name=name or f"field_{field}")
        u.x.array[:] = w.x.array[parent]
        return u

    # -- active dofs ----------------------------------------------------------
    def _mark(self, field: int, cells: np.ndarray, weights: np.ndarray | None = None):
        """Sum, over ``cells``, a per-cell weight into the dofs of ``field`` (parallel-safe)."""
        imap, bs = self.W.dofmap.index_map, self.W.dofmap.index_map_bs
        vec = dolfinx.la.vector(imap, bs)
        dofs = self.W.sub(field).dofmap.list[cells]
        w = np.ones(cells.size) if weights is None else weights
        np.add.at(vec.array, dofs.ravel(), np.repeat(w, dofs.shape[1]))
        vec.scatter_reverse(dolfinx.la.InsertMode.add)
        vec.scatter_forward()
        return vec.array

    def _active_dofs(self) -> npt.NDArray[np.bool_]:
        cut = self.cut
        sides = cut.cell_sides
        areas = cell_areas(cut) if self.min_support_fraction > 0.0 else None
        owned = np.arange(sides.size, dtype=np.int32)
        active = np.zeros(
            self.W.dofmap.index_map.size_local + self.W.dofmap.index_map.num_ghosts, dtype=bool
        )
        active = np.repeat(active, self.W.dofmap.index_map_bs)
        for field, side in ((0, -1), (1, 1)):
            touched = owned[(sides == side) | (sides == 0)]
            support = self._mark(field, touched) > 0
            if self.min_support_fraction > 0.0:
                fraction = self._side_fraction(field, side, areas)
                support &= fraction >= self.min_support_fraction
            active |= support
        for field, _, name in self.multiplier_fields:
            rules = cut.interface_rules_of(name)
            length = rules.sums(rules.weights * abs_det_at(cut, rules))
            if cut.crack is not None:  # a crack's: the crossed cells' vertices only
                length = np.where(cut.crack.kind == CROSSED, length, 0.0)
            carrying = cut.cut_cells[length > 0.0]
            active |= self._mark(field, carrying) > 0
        if self.branch_field is not None:
            active |= branch_support(self)
        self._ties = self._tied(active)
        if self.interpolants is not None:
            self._interpolate(active)
        if self.aggregation_threshold is not None:
            self._aggregation = aggregate(self, self.aggregation_threshold, active)
        return active

    def _tied_nodes(self, active: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
        """Per local dof of field 0's own space (:meth:`field_space`): whether it and
        field 1's at its node and component are both active and the crack does not cut
        their support completely (a crack's)."""
        crack = self.cut.crack
        cut_cells = self.cut.cut_cells
        crossed = cut_cells[crack.kind == CROSSED]
        ends = cut_cells[crack.kind != CROSSED]  # tip cells and the crack's extension
        heaviside = (self._mark(0, crossed) > 0) & ~(self._mark(0, ends) > 0)
        minus, plus = (self.field_space(i)[1] for i in (0, 1))
        return active[minus] & active[plus] & ~heaviside[minus]

    def _interpolate(self, active: npt.NDArray[np.bool_]) -> None:
        """Set :attr:`interpolants`: per side ``s``, ``R F_k`` of side ``s`` at each
        vertex, of the side the vertex lies on where the two sides share one unknown
        (:func:`~xfem_contact.fem.branch.tied_values`). Collective."""
        P1 = self.interpolants[1][0].function_space
        nodes = P1.dofmap.index_map.size_local + P1.dofmap.index_map.num_ghosts
        values = []
        for g in (self.cut.levelset.function, self.cut.crack.tangent.function, self.ramp):
            f = dolfinx.fem.Function(P1)
            if g is None:  # no ramp: R = 1
                f.x.array[:] = 1.0
            else:
                f.interpolate(g)
            values.append(f.x.array[:nodes])
        phi, psi, ramp = values
        V0 = self.field_space(0)[0]
        gdim, vertices = V0.dofmap.index_map_bs, P1.dofmap.list.shape[1]
        tied = np.zeros(nodes, dtype=bool)  # the vertex nodes come first in each cell
        tied[P1.dofmap.list] = self._tied_nodes(active).reshape(-1, gdim)[
            V0.dofmap.list[:, :vertices], 0
        ]
        at = tied_values(side_values(phi, psi, ramp, self.round_off), tied, phi, self.round_off)
        for s, functions in self.interpolants.items():
            for k, f in enumerate(functions):
                f.x.array[:] = at[s][k]
                f.x.scatter_forward()

    def _tied(self, active: npt.NDArray[np.bool_]) -> npt.NDArray[np.int64]:
        """``(kept, follower)`` owned dofs of fields 0 and 1 at the same node and
        component, both active, whose support the crack does not cut completely."""
        if self.cut.crack is None:
            return np.zeros((0, 2), dtype=np.int64)
        minus, plus = (self.field_space(i)[1] for i in (0, 1))
        both = self._tied_nodes(active)
        n_owned = self.W.dofmap.index_map.size_local * self.W.dofmap.index_map_bs
        pairs = np.stack([minus[both], plus[both]], axis=1).astype(np.int64)
        owned = pairs[:, 0] < n_owned
        if np.any(owned != (pairs[:, 1] < n_owned)):
            raise RuntimeError("the two sides' dofs of a node have different owners")
        return pairs[owned]

    @property
    def aggregation(self) -> Aggregation | None:
        """The dofs of badly cut cells extended from their roots (owned rows, see
        :class:`~xfem_contact.fem.aggregation.Aggregation`); None without aggregation."""
        return self._aggregation

    @property
    def ties(self) -> npt.NDArray[np.int64]:
        """Owned dofs ``(kept, follower)``, shape ``(m, 2)``: the follower (side +1) is
        the kept dof (side -1) in the reduced system (nodes a crack does not cut
        completely; none without a crack)."""
        return self._ties

    def _side_fraction(self, field: int, side: int, areas: np.ndarray) -> np.ndarray:
        """Per dof: (area of its support on ``side``) / (area of its support)."""
        side_area = side_areas(self.cut, side, areas)
        on_side = self._mark(field, np.arange(areas.size, dtype=np.int32), side_area)
        total = self._mark(field, np.arange(areas.size, dtype=np.int32), areas)
        return np.divide(on_side, total, out=np.zeros_like(total), where=total > 0)

    def refresh(self) -> None:
        """Recompute the active dofs after the cut was updated (``W`` is kept).
        Collective."""
        self._active = self._active_dofs()

    def carry(self, w: dolfinx.fem.Function, before: npt.NDArray[np.bool_]) -> None:
        """Carry ``w`` (on ``W``) from the active dofs ``before`` (a copy of
        :attr:`active` taken before a :meth:`refresh`) onto the current ones: a side's
        dof that became active takes the other side's value at its node where that one
        was active (the field continued across the old interface); then, where both
        sides are active, the side a node does not lie on (by the sign of the new level
        set there) takes the value of the side it lies on, so the carried displacement
        is one continuous field with no jump across the new interface (the two sides'
        extensions differ there by a spurious gap and slip that would set wrong contact
        states); multipliers restart at 0 and inactive dofs are zeroed. Collective
        (ghost update)."""
        active = self._active
        minus, plus = (self.field_space(i)[1] for i in (0, 1))
        for mine, other in ((minus, plus), (plus, minus)):
            take = active[mine] & ~before[mine] & before[other]
            w.x.array[mine[take]] = w.x.array[other[take]]
        both = active[minus] & active[plus]
        on_plus = self._levelset_at_dofs() > 0
        w.x.array[minus[both & on_plus]] = w.x.array[plus[both & on_plus]]
        w.x.array[plus[both & ~on_plus]] = w.x.array[minus[both & ~on_plus]]
        for field, _, _ in self.multiplier_fields:
            w.x.array[self.field_space(field)[1]] = 0.0
        w.x.array[~active] = 0.0
        w.x.scatter_forward()

    def _levelset_at_dofs(self) -> npt.NDArray[np.float64]:
        """The level set at the node of each local dof of the displacement field's own
        space (:meth:`field_space`, owned and ghost). Collective the first time."""
        if self._scalar is None:
            V = self.field_space(0)[0]
            S, dofs = V.sub(0).collapse()  # dofs: the component-0 dof of V of each node
            self._scalar = (S, np.asarray(dofs).ravel() // V.dofmap.index_map_bs)
        S, nodes = self._scalar
        phi = dolfinx.fem.Function(S)
        phi.interpolate(self.cut.levelset.function)
        at_node = np.empty(nodes.size)
        at_node[nodes] = phi.x.array[: nodes.size]
        return np.repeat(at_node, self.field_space(0)[0].dofmap.index_map_bs)

    @property
    def active(self) -> npt.NDArray[np.bool_]:
        """Active flags of the local (owned + ghost) dofs of ``W``."""
        return self._active

    def dof_counts(self) -> DofCounts:
        """Global active dof counts: standard, enriched and multiplier."""
        imap, bs = self.W.dofmap.index_map, self.W.dofmap.index_map_bs
        nowned = imap.size_local * bs
        comm = self.cut.mesh.comm
        counts = []
        for field in range(self.W.num_sub_spaces):
            of_field = np.zeros(nowned, dtype=bool)
            dofs = self.W.sub(field).dofmap.list.ravel()
            of_field[dofs[dofs < nowned]] = True
            if field == 0:  # a displacement field: the whole mesh's Lagrange space
                standard = comm.allreduce(int(of_field.sum()), op=MPI.SUM)
            counts.append(comm.allreduce(int(self._active[:nowned][of_field].sum()), op=MPI.SUM))
        fields = [f for f, _, _ in self.multiplier_fields]
        multiplier = sum(counts[f] for f in fields)
        ties = comm.allreduce(len(self._ties), op=MPI.SUM)
        branch = 0 if self.branch_field is None else counts[self.branch_field]
        return DofCounts(standard, counts[0] + counts[1] - standard - ties + branch, multiplier)
