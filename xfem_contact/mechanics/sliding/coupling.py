"""The hybrid elements of one interface, assembled into the Newton system.

:class:`SlidingCoupling` is what a large-sliding law hands the Newton solver
(:meth:`~xfem_contact.mechanics.laws.base.InterfaceLaw.coupling`): at every residual
evaluation it pairs the slave points with the deformed master lip
(:mod:`~xfem_contact.mechanics.sliding.projection`) and adds the hybrid element terms
(:mod:`~xfem_contact.mechanics.sliding.element`) to the residual of the mixed space,
by global dof (a master dof may live on another process: PETSc sends it there); at
every Jacobian it adds their matrix, in the reduced numbering, through a COO matrix
whose pattern (slave cell x master cell pairs) is merged into the Jacobian's when a
pair appears that the Jacobian has not held yet. SI units (m, Pa).
"""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.fem.evaluation import cell_dofs, lagrange_element, rule_cells
from xfem_contact.mechanics.sliding.element import PairTerms, frictionless_terms
from xfem_contact.mechanics.sliding.friction import PointData
from xfem_contact.mechanics.sliding.friction import terms as friction_terms
from xfem_contact.mechanics.sliding.lips import MasterLip, global_dofs
from xfem_contact.mechanics.sliding.projection import Pairing, closest_points

#: When the master lip is paired: at every Newton iterate, or once per load step
PAIRING_UPDATES = ("iterate", "step")


class SlidingCoupling:
    """Slave points of one interface, their pairing and their hybrid elements.

    Args:
        ctx: The interface's :class:`~xfem_contact.mechanics.laws.base.InterfaceContext`.
        W: The problem's mixed space.
        law: The large-sliding law (its ``augmentation_coefficient``).
        slave: Slave side (-1 or +1); the master is the other.
        radius: Search radius (m); default the largest cut-cell size of the
            interface.
        update: ``"iterate"`` (pair at every Newton iterate) or ``"step"`` (pair at
            the start of each solve and keep the master pieces; the feet still move
            along them).

    Construction is collective; the solver then calls :meth:`bind`.
    """

    def __init__(
        self, ctx, W, law, slave: int = -1, radius: float | None = None, update: str = "iterate"
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
        X = rules.points
        self.rows = np.flatnonzero(np.diff(rules.offsets) > 0)  # cut-cell rows with a rule
        J = cut.maps.jacobian(cells, X)
        self.weights = rules.weights * np.abs(np.linalg.det(J))
        self.x_ref = cut.maps.push_forward(cells, X)
        V_s, V_l = W.sub(self.slave_field), W.sub(ctx.field)
        self.phi_s = lagrange_element(V_s).tabulate(0, X)[0, :, :, 0]
        self.lam_basis = lagrange_element(V_l).tabulate(0, X)[0, :, :, 0]
        self.slave_dofs = _flat(cell_dofs(V_s, cells))  # (m, nodes x components)
        self.lam_dofs = _flat(cell_dofs(V_l, cells))
        h = ctx.cell_size_at()
        self._materials, self._h = ctx.materials, h
        self.radius = radius or self.comm.allreduce(float(h.max(initial=0.0)), op=MPI.MAX)
        tdim = cut.mesh.topology.dim
        self.slave_cells = cut.mesh.topology.index_map(tdim).local_to_global(cells)
        self.lip: MasterLip | None = None
        self._evaluated: tuple[np.ndarray, Pairing, PairTerms] | None = None
        self._frozen: np.ndarray | None = None
        self._accepted_cells: np.ndarray | None = None
        self._merged: set = set()
        #: Frictionless through the complex-step element too (a cross-check)
        self.complex_step = False
        #: ``(slip increment (m), lambda_t, P_t (Pa))`` at the points (Coulomb)
        self.tangential = None
        self._old_slave = self._old_master = None
        self._coo: tuple | None = None
        #: Pairing counts of the last evaluation (global): paired, unpaired, changed
        self.counts: dict[str, int] = {}

    @property
    def r(self) -> np.ndarray:
        """The augmentation ``r`` (Pa/m) at the slave points, ``(npoints,)``, from the
        law's current parameters."""
        return self.law.augmentation_coefficient(self._materials, self._h)

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
            self._old_slave = np.zeros(self.slave_dofs.shape)
            self._old_master = np.zeros(self.lip.dofs.shape)
        local = np.concatenate([self.slave_dofs, self.lam_dofs], axis=1)
        self._rows_local = global_dofs(self.W, local)
        self._columns_local = columns[local]
        self._merged.clear()
        self._coo = None

    # -- evaluation ------------------------------------------------------------------
    def evaluate(self, w) -> tuple[Pairing, PairTerms]:
        """Pair and evaluate at the state ``w`` (a Function on ``W``); cached for the
        same values. Collective."""
        if self._evaluated is not None and np.array_equal(self._evaluated[0], w.x.array):
            return self._evaluated[1], self._evaluated[2]
        lip = self.lip
        lip.refresh(w)
        m, n = self.slave_dofs.shape
        u_s = w.x.array[self.slave_dofs].reshape(m, n // 2, 2)
        x_s = self.x_ref + np.einsum("mi,mid->md", self.phi_s, u_s)
        pairing = closest_points(lip, x_s, self.radius, only=self._frozen)
        pieces = np.where(pairing.paired, pairing.piece, 0)
        curve = lip.curve(pieces, pairing.s)
        if self.friction is None and not self.complex_step:
            terms = frictionless_terms(
                x_s,
                self.phi_s,
                self.lam_basis,
                w.x.array[self.lam_dofs],
                curve,
                lip.orientation[pieces],
                self.weights,
                self.r,
                pairing.paired,
            )
        else:
            terms, self.tangential = self._complex_step_terms(w, pairing, pieces, curve)
        self._evaluated = (w.x.array.copy(), pairing, terms)
        paired = int(pairing.paired.sum())
        changed = 0
        if self._accepted_cells is not None:
            cells = np.where(pairing.paired, lip.cells[pieces], -1)
            changed = int(np.sum(cells != self._accepted_cells))
        counts = np.array([paired, pairing.piece.size - paired, changed])
        counts = self.comm.allreduce(counts, op=MPI.SUM)
        self.counts = dict(zip(("paired", "unpaired", "changed"), map(int, counts), strict=True))
        return pairing, terms

    def _complex_step_terms(self, w, pairing, pieces, curve):
        """The element of :mod:`~xfem_contact.mechanics.sliding.friction` (Coulomb,
        or frictionless with ``complex_step``): terms and ``(slip increment,
        lambda_t, P_t)``."""
        X3, dddphi = self.lip.third_derivatives(pieces, pairing.s)
        data = PointData(
            self.x_ref,
            self.phi_s,
            self.lam_basis,
            self.weights,
            self.r,
            self.lip.orientation[pieces],
            ((*curve.geometry, X3), (curve.phi, curve.dphi, curve.ddphi, dddphi)),
            (self._old_slave, self._old_master[pieces]),
            pairing.paired,
        )
        z = np.concatenate(
            [w.x.array[self.slave_dofs], w.x.array[self.lam_dofs], self.lip.values[pieces]],
            axis=1,
        )
        return friction_terms(z, data, self.friction)

    def begin_step(self, w) -> None:
        """At the start of a solve: with ``update="step"``, pair now and keep the
        master pieces over the solve. Collective."""
        if self.update_mode == "step":
            self._frozen = None
            pairing, _ = self.evaluate(w)
            self._frozen = pairing.piece.copy()
            self._evaluated = None

    def accept(self, w) -> None:
        """The end of an accepted load step: pairs whose master cell changes are
        counted from here. Collective."""
        pairing, _ = self.evaluate(w)
        pieces = np.where(pairing.paired, pairing.piece, 0)
        self._accepted_cells = np.where(pairing.paired, self.lip.cells[pieces], -1)
        self._old_slave = w.x.array[self.slave_dofs]  # slips are measured from here
        self._old_master = self.lip.gather(w)

    def unpaired_points(self, w) -> np.ndarray:
        """Reference coordinates (m) of the unpaired slave points of all processes,
        ``(k, 2)``. Collective."""
        pairing, _ = self.evaluate(w)
        return np.concatenate(self.comm.allgather(self.x_ref[~pairing.paired]))

    # -- assembly --------------------------------------------------------------------
    def _indices(self, pairing: Pairing, master) -> np.ndarray:
        """Per-piece indices ``master`` (``(P, k)``) at each point's foot, -1 where
        unpaired (PETSc drops negative indices)."""
        pieces = np.where(pairing.paired, pairing.piece, 0)
        return np.where(pairing.paired[:, None], master[pieces], -1)

    def add_residual(self, w, b: PETSc.Vec) -> None:
        """Add the hybrid elements' residual at ``w`` to ``b`` (a vector of ``W``,
        global numbering; before the Dirichlet rows are set). Collective."""
        pairing, terms = self.evaluate(w)
        rows = np.concatenate([self._rows_local, self._indices(pairing, self.lip.dofs)], axis=1)
        keep = rows >= 0
        b.setValues(
            rows[keep].astype(PETSc.IntType), terms.residual[keep], addv=PETSc.InsertMode.ADD_VALUES
        )
        b.assemblyBegin()
        b.assemblyEnd()

    def add_jacobian(self, w, J: PETSc.Mat) -> None:
        """Add the hybrid elements' Jacobian at ``w`` to ``J`` (reduced numbering, not
        yet scaled), merging new slave-master pairs into its pattern. Collective."""
        pairing, terms = self.evaluate(w)
        cols = np.concatenate(
            [self._columns_local, self._indices(pairing, self.lip.columns)], axis=1
        )
        key = tuple(np.where(pairing.paired, pairing.piece, -1))
        if self._coo is None or self._coo[0] != key:
            if self._coo is not None:
                self._coo[1].destroy()
            nz = cols.shape[1]
            Ic = np.repeat(cols, nz, axis=1).ravel().astype(PETSc.IntType)
            Jc = np.tile(cols, (1, nz)).ravel().astype(PETSc.IntType)
            C = PETSc.Mat().create(comm=J.getComm())
            C.setSizes(J.getSizes())
            C.setType(PETSc.Mat.Type.AIJ)
            C.setPreallocationCOO(Ic, Jc)
            self._coo = (key, C)
        C = self._coo[1]
        C.setValuesCOO(terms.jacobian.ravel(), addv=PETSc.InsertMode.INSERT_VALUES)
        C.assemble()
        pieces = np.where(pairing.paired, pairing.piece, 0)
        pairs = set(
            zip(
                self.slave_cells[pairing.paired].tolist(),
                self.lip.cells[pieces][pairing.paired].tolist(),
                strict=True,
            )
        )
        new = not pairs <= self._merged
        if self.comm.allreduce(new, op=MPI.LOR):
            self._merged |= pairs
            J.axpy(1.0, C, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
        else:
            J.axpy(1.0, C, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def destroy(self) -> None:
        """Destroy the COO matrix. Collective."""
        if self._coo is not None:
            self._coo[1].destroy()
            self._coo = None


def _flat(dofs: np.ndarray) -> np.ndarray:
    """``(m, nodes, components)`` dofs as ``(m, nodes x components)``, node by node
    (explicit sizes: a process may hold no point of the interface)."""
    return dofs.reshape(dofs.shape[0], dofs.shape[1] * dofs.shape[2])
