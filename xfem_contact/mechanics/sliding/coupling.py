"""The hybrid elements of one interface, assembled into the Newton system.

:class:`SlidingCoupling` is what a large-sliding law hands the Newton solver
(:meth:`~xfem_contact.mechanics.laws.base.InterfaceLaw.coupling`): at every residual
evaluation it breaks the slave pieces at the master-piece ends their feet cross
(:mod:`~xfem_contact.mechanics.sliding.segments`), pairs the sub-segments' Gauss
points with the deformed master lip
(:mod:`~xfem_contact.mechanics.sliding.projection`) and adds the hybrid element terms
(:mod:`~xfem_contact.mechanics.sliding.element`) to the residual of the mixed space,
by global dof (a master dof may live on another process: PETSc sends it there); at
every Jacobian it adds their matrix, in the reduced numbering, through a COO matrix
whose pattern (slave cell x master cell pairs) is merged into the Jacobian's when a
pair appears that the Jacobian has not held yet
(:mod:`~xfem_contact.mechanics.sliding.blocks`), with the motion of the breakpoints.
SI units (m, Pa).
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact._deprecation import renamed_attribute
from xfem_contact.fem.evaluation import rule_cells
from xfem_contact.mechanics.sliding.blocks import BlockMatrix, cell_pairs, role
from xfem_contact.mechanics.sliding.element import PairTerms, frictionless_terms
from xfem_contact.mechanics.sliding.friction import PointData
from xfem_contact.mechanics.sliding.friction import residual as friction_residual
from xfem_contact.mechanics.sliding.friction import terms as friction_terms
from xfem_contact.mechanics.sliding.lips import MasterLip, global_dofs
from xfem_contact.mechanics.sliding.points import PointMaker, SlavePoints, positions
from xfem_contact.mechanics.sliding.projection import Pairing, closest_points
from xfem_contact.mechanics.sliding.segments import (
    Segments,
    SlavePieces,
    break_pieces,
    breakpoint_gradient,
)

#: When the master lip is paired: at every Newton iterate, or once per load step
PAIRING_UPDATES = ("iterate", "step")


class SlidingCoupling:
    """Slave points of one interface, their pairing and their hybrid elements.

    The state (:meth:`evaluate`: gaps, multipliers, pairing counts) is at the points
    of the interface's rule. The terms added to the Newton system are integrated, when
    the law's ``segments`` is true, by segment-to-segment rules
    (:mod:`~xfem_contact.mechanics.sliding.segments`): the slave pieces broken where
    their feet cross master-piece ends, the breakpoints taken at the iterate and
    held fixed in its Jacobian (their motion enters only through the discontinuity of
    the integrand at a breakpoint, which vanishes with the master's kink); else by the
    rule's own points.

    Args:
        ctx: The interface's :class:`~xfem_contact.mechanics.laws.base.InterfaceContext`.
        W: The problem's mixed space.
        law: The large-sliding law (its ``augmentation_coefficient``, ``friction``
            and ``segments``, read at every evaluation).
        slave: Slave side (-1 or +1); the master is the other.
        radius: Search radius (m); default the largest cut-cell size of the
            interface.
        update: ``"iterate"`` (pair at every Newton iterate) or ``"step"`` (pair at
            the start of each solve and keep the master pieces, and the breakpoints;
            the feet still move along them).

    Construction is collective; the solver then calls :meth:`bind`.
    """

    def __init__(
        self,
        ctx,
        W,
        law,
        slave: int = -1,
        radius: float | None = None,
        update: str = "iterate",
    ):
        if slave not in (-1, 1):
            raise ValueError(f"slave must be -1 or +1 (a side), got {slave!r}")
        if update not in PAIRING_UPDATES:
            raise ValueError(f"pairing update must be one of {PAIRING_UPDATES}, got {update!r}")
        cut = ctx.cut
        # not the context itself: it caches this object (a reference cycle)
        self.cut, self.W, self.law, self.update_mode = cut, W, law, update
        self.slave_field, self.master_field = (0, 1) if slave == -1 else (1, 0)
        self.comm = cut.mesh.comm
        rules = ctx.rules
        cells = rule_cells(cut, rules)
        self.rows = np.flatnonzero(np.diff(rules.offsets) > 0)  # cut-cell rows with a rule
        J = cut.maps.jacobian(cells, rules.points)
        V_s = W.sub(self.slave_field)
        self._points = PointMaker(cut.maps, V_s, W.sub(ctx.field), ctx.cell_size)
        #: The rule's points (where the state is reported)
        self.points = self._points(cells, rules.points, rules.weights * np.abs(np.linalg.det(J)))
        self.pieces = SlavePieces(cut, V_s, self.rows, cut.quadrature_degree)
        _, X, _ = self.pieces.rule(self.pieces.whole())
        # the rule's points are the pieces' Gauss points in order: their feet help break
        self._ordered = X.shape == rules.points.shape and np.allclose(X, rules.points, atol=1e-12)
        self._paired: tuple | None = None
        self._materials = ctx.materials
        h = self.points.h
        self.radius = radius or self.comm.allreduce(float(h.max(initial=0.0)), op=MPI.MAX)
        self.lip: MasterLip | None = None
        self._evaluated: tuple[np.ndarray, Pairing, PairTerms] | None = None
        self._integrated: tuple | None = None
        self._frozen: np.ndarray | None = None
        self._frozen_segments: Segments | None = None
        self._accepted_cells: np.ndarray | None = None
        self._blocks = BlockMatrix()
        self._cells = cut.mesh.topology.index_map(cut.mesh.topology.dim).size_global
        #: Linearise the motion of the breakpoints (iterate pairing): the jump of
        #: the integrand at each breakpoint times the point's derivative
        self.breakpoint_linearisation = True
        #: Frictionless through the complex-step element too (a cross-check)
        self.complex_step = False
        #: ``(slip increment (m), lambda_t, P_t (Pa))`` at the points (Coulomb)
        self.tangential = None
        self._old_w = self._old_master = None
        #: Pairing counts of the last evaluation (global): paired, unpaired, changed
        self.counts: dict[str, int] = {}

    @property
    def x_ref(self) -> np.ndarray:
        """Reference positions (m) of the rule's points, ``(npoints, 2)``."""
        return self.points.x_ref

    @property
    def weights(self) -> np.ndarray:
        """Reference arc-length weights (m) of the rule's points, ``(npoints,)``."""
        return self.points.weights

    @property
    def r(self) -> np.ndarray:
        """The augmentation ``r`` (Pa/m) at the rule's points, ``(npoints,)``, from the
        law's current parameters."""
        return self.law.augmentation_coefficient(self._materials, self.points.h)

    @property
    def segments(self) -> bool:
        """Whether the Newton system gets segment-to-segment integration (the law's)."""
        return self.law.segments

    @property
    def friction(self) -> float | None:
        """The law's current Coulomb coefficient (None: frictionless, analytic Jacobian)."""
        return self.law.friction if self.law.tangential else None

    # -- set-up ----------------------------------------------------------------------
    def bind(self, columns: np.ndarray, bcs: list) -> None:
        """Number the unknowns: ``columns`` the reduced column of every local dof of
        ``W`` (-1: inactive); Dirichlet dofs of ``bcs`` are no unknowns either.
        Collective."""
        columns = np.array(columns, dtype=np.int64)
        for bc in bcs:
            columns[bc.dof_indices()[0]] = -1
        self.lip = MasterLip(self.cut, self.W, self.master_field, self.rows, columns)
        if self._old_master is None or self._old_master.shape != self.lip.dofs.shape:
            self._old_w = np.zeros(columns.size)
            self._old_master = np.zeros(self.lip.dofs.shape)
        self._columns = columns
        self._blocks.reset()
        self._integrated = self._paired = None

    split_linearisation = renamed_attribute(
        "SlidingCoupling", "split_linearisation", "breakpoint_linearisation"
    )

    # -- evaluation ------------------------------------------------------------------
    def evaluate(self, w, jacobian: bool = True) -> tuple[Pairing, PairTerms]:
        """Pair and evaluate at the state ``w`` (a Function on ``W``) at the rule's
        points (``jacobian`` False: its ``jacobian`` may be None); cached for the same
        values. Collective."""
        cached = self._evaluated
        if cached is not None and np.array_equal(cached[0], w.x.array):
            if cached[2].jacobian is not None or not jacobian:
                return cached[1], cached[2]
        lip = self.lip
        x_s, pairing = self._pair(w)
        terms, self.tangential = self._terms(w, self.points, x_s, pairing, jacobian)
        self._evaluated = (w.x.array.copy(), pairing, terms)
        paired = int(pairing.paired.sum())
        changed = 0
        if self._accepted_cells is not None:
            pieces = np.where(pairing.paired, pairing.piece, 0)
            cells = np.where(pairing.paired, lip.cells[pieces], -1)
            changed = int(np.sum(cells != self._accepted_cells))
        counts = np.array([paired, pairing.piece.size - paired, changed])
        counts = self.comm.allreduce(counts, op=MPI.SUM)
        self.counts = dict(zip(("paired", "unpaired", "changed"), map(int, counts), strict=True))
        return pairing, terms

    def _pair(self, w) -> tuple[np.ndarray, Pairing]:
        """The rule's points at ``w`` and their pairing (cached for the same values;
        the lip refreshed). Collective."""
        self.lip.refresh(w)
        cached = self._paired
        if cached is not None and np.array_equal(cached[0], w.x.array):
            return cached[1:]
        x_s = positions(w, self.points)
        pairing = closest_points(self.lip, x_s, self.radius, only=self._frozen)
        self._paired = (w.x.array.copy(), x_s, pairing)
        return x_s, pairing

    def integrate(self, w) -> tuple[SlavePoints, Pairing, PairTerms]:
        """The points, pairing and terms the Newton system gets at ``w``: the
        segment-to-segment ones, or the rule's (:meth:`evaluate`). Collective."""
        if not self.segments:
            return (self.points, *self.evaluate(w))
        cached = self._integrated
        if cached is not None and np.array_equal(cached[0], w.x.array):
            return cached[1:4]
        segments = self._frozen_segments
        if segments is None:
            feet = None
            if self._ordered:
                piece, count = self._pair(w)[1].piece, self.pieces.size  # none on a process
                feet = piece.reshape(count, piece.size // max(count, 1))
            self.lip.refresh(w)
            segments = break_pieces(self.pieces, w.x.array, self.lip, self.radius, feet)
        self.lip.refresh(w)
        segment, X, weights = self.pieces.rule(segments)
        points = self._points(self.pieces.cells[segments.piece[segment]], X, weights)
        x_s = positions(w, points)
        pairing = closest_points(self.lip, x_s, self.radius, only=segments.master[segment])
        terms, _ = self._terms(w, points, x_s, pairing)
        motion = None
        if self._frozen_segments is None and self.breakpoint_linearisation:
            motion = self._breakpoint_terms(w, segments)
        self._integrated = (w.x.array.copy(), points, pairing, terms, motion)
        return points, pairing, terms

    def _breakpoint_terms(self, w, segments: Segments):
        """The Jacobian block of the breakpoints' motion: at each breakpoint, the
        integrand's jump (left sub-segment's minus right's, per unit ``t``) times the
        point's derivative. ``(rows (b, 2 nz), cols (b, nc), values (b, 2 nz, nc),
        the (row, column) pairs of cells it couples
        (:func:`~xfem_contact.mechanics.sliding.blocks.cell_pairs`)``, None without
        breakpoints."""
        lip = self.lip
        k, grad = breakpoint_gradient(self.pieces, w.x.array, lip, segments)
        if k.size == 0:
            return None
        piece = segments.piece[k]
        X, speed = self.pieces.at(piece, segments.t0[k])
        cells = self.pieces.cells[piece]
        points = self._points(np.tile(cells, 2), np.tile(X, (2, 1)), np.tile(speed, 2))
        x_s = positions(w, points)
        sides = np.concatenate([segments.master[k - 1], segments.master[k]])
        pairing = closest_points(lip, x_s, self.radius, only=sides)
        terms, _ = self._terms(w, points, x_s, pairing, jacobian=False)
        b = k.size
        index = np.concatenate(
            [self._columns[self._local(points)], self._indices(pairing, lip.columns)], axis=1
        )
        rows = np.concatenate([index[:b], index[b:]], axis=1)
        jump = np.concatenate([terms.residual[:b], -terms.residual[b:]], axis=1)
        source = segments.start_master[k]
        cols = np.concatenate([self._columns[points.slave_dofs[:b]], lip.columns[source]], axis=1)
        masters = np.where(sides >= 0, lip.cells[np.maximum(sides, 0)], -1)
        tdim = self.cut.mesh.topology.dim
        slave = self.cut.mesh.topology.index_map(tdim).local_to_global(cells)
        slave, masters = role(slave, False), role(masters, True)
        row_cells = np.tile(np.concatenate([slave, masters[:b], masters[b:]]), 2)
        col_cells = np.repeat([slave, role(lip.cells[source], True)], 3, axis=0).ravel()
        pairs = cell_pairs(self._cells, row_cells, col_cells)
        return rows, cols, jump[:, :, None] * grad[:, None, :], pairs

    def _terms(self, w, points: SlavePoints, x_s, pairing: Pairing, jacobian: bool = True):
        """The hybrid element's terms at ``points`` (``jacobian`` False: without their
        Jacobian) and the tangential state (None when frictionless)."""
        lip = self.lip
        pieces = np.where(pairing.paired, pairing.piece, 0)
        curve = lip.curve(pieces, pairing.s)
        r = self.law.augmentation_coefficient(self._materials, points.h)
        if self.friction is None and not self.complex_step:
            terms = frictionless_terms(
                x_s,
                points.phi_s,
                points.lam_basis,
                w.x.array[points.lam_dofs],
                curve,
                lip.orientation[pieces],
                points.weights,
                r,
                pairing.paired,
                jacobian,
            )
            return terms, None
        X3, dddphi = lip.third_derivatives(pieces, pairing.s)
        data = PointData(
            points.x_ref,
            points.phi_s,
            points.lam_basis,
            points.weights,
            r,
            lip.orientation[pieces],
            ((*curve.geometry, X3), (curve.phi, curve.dphi, curve.ddphi, dddphi)),
            (self._old_w[points.slave_dofs], self._old_master[pieces]),
            pairing.paired,
        )
        z = np.concatenate(
            [w.x.array[points.slave_dofs], w.x.array[points.lam_dofs], lip.values[pieces]],
            axis=1,
        )
        if jacobian:
            return friction_terms(z, data, self.friction)
        R, (g, s_t, lam_n, lam_t, P_n, P_t) = friction_residual(z, data, self.friction)
        terms = PairTerms(R, None, np.where(pairing.paired, g, np.nan), lam_n, P_n)
        return terms, (s_t, lam_t, P_t)

    def begin_step(self, w) -> None:
        """At the start of a solve: with ``update="step"``, pair (and break the slave
        pieces) now and keep the master pieces (and breakpoints) over the solve.
        Collective."""
        if self.update_mode == "step":
            self._frozen = self._frozen_segments = None
            self._paired = None
            pairing, _ = self.evaluate(w, jacobian=False)
            self._frozen = pairing.piece.copy()
            self._evaluated = self._integrated = self._paired = None
            if self.segments:
                self.lip.refresh(w)
                self._frozen_segments = break_pieces(self.pieces, w.x.array, self.lip, self.radius)

    def accept(self, w) -> None:
        """The end of an accepted load step: pairs whose master cell changes are
        counted from here. Collective."""
        pairing, _ = self.evaluate(w, jacobian=False)
        pieces = np.where(pairing.paired, pairing.piece, 0)
        self._accepted_cells = np.where(pairing.paired, self.lip.cells[pieces], -1)
        self._old_w = w.x.array.copy()  # slips are measured from here
        self._old_master = self.lip.gather(w)
        self._integrated = self._paired = None

    def unpaired_points(self, w) -> np.ndarray:
        """Reference coordinates (m) of the unpaired slave points of all processes,
        ``(k, 2)``. Collective."""
        pairing, _ = self.evaluate(w, jacobian=False)
        return np.concatenate(self.comm.allgather(self.x_ref[~pairing.paired]))

    # -- assembly --------------------------------------------------------------------
    def _indices(self, pairing: Pairing, master) -> np.ndarray:
        """Per-piece indices ``master`` (``(P, k)``) at each point's foot, -1 where
        unpaired (PETSc drops negative indices)."""
        pieces = np.where(pairing.paired, pairing.piece, 0)
        return np.where(pairing.paired[:, None], master[pieces], -1)

    def _local(self, points: SlavePoints) -> np.ndarray:
        """Local dofs of ``W`` of each point's slave cell: displacement, multiplier."""
        return np.concatenate([points.slave_dofs, points.lam_dofs], axis=1)

    def add_residual(self, w, b: PETSc.Vec) -> None:
        """Add the hybrid elements' residual at ``w`` to ``b`` (a vector of ``W``,
        global numbering; before the Dirichlet rows are set). Collective."""
        points, pairing, terms = self.integrate(w)
        slave = global_dofs(self.W, self._local(points))
        rows = np.concatenate([slave, self._indices(pairing, self.lip.dofs)], axis=1)
        keep = rows >= 0
        b.setValues(
            rows[keep].astype(PETSc.IntType), terms.residual[keep], addv=PETSc.InsertMode.ADD_VALUES
        )
        b.assemblyBegin()
        b.assemblyEnd()

    def add_jacobian(self, w, J: PETSc.Mat) -> None:
        """Add the hybrid elements' Jacobian at ``w`` to ``J`` (reduced numbering, not
        yet scaled), merging new slave-master pairs into its pattern. Collective."""
        points, pairing, terms = self.integrate(w)
        cols = np.concatenate(
            [self._columns[self._local(points)], self._indices(pairing, self.lip.columns)], axis=1
        )
        blocks = [(cols, cols, terms.jacobian)]
        tdim = self.cut.mesh.topology.dim
        to_global = self.cut.mesh.topology.index_map(tdim).local_to_global
        slave_cells = to_global(points.cells)
        pieces = np.where(pairing.paired, pairing.piece, 0)
        paired = pairing.paired
        a, b = role(slave_cells[paired], False), role(self.lip.cells[pieces][paired], True)
        # each point couples {slave, master} x {slave, master}
        pairs = [cell_pairs(self._cells, np.r_[a, a, b, b], np.r_[a, b, a, b])]
        motion = self._integrated[-1] if self.segments else None
        if motion is not None:
            blocks.append(motion[:3])
            pairs.append(motion[3])
        pairs = np.unique(np.concatenate(pairs))
        self._blocks.add_to(J, blocks, pairs)

    def destroy(self) -> None:
        """Release the point blocks' storage. Collective."""
        self._blocks.destroy()
