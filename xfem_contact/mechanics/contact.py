"""Frictional contact on cut interfaces: mixed augmented-Lagrangian formulation.

Unknowns: the displacement of each side (``u_-``, ``u_+``, m) and the interface
multipliers (Pa): the normal pressure ``lambda_n`` and, with friction, the
tangential traction ``lambda_t``; ``lambda = lambda_n n + lambda_t t`` is the
traction ``sigma n`` on side -1 (``n`` from side -1 to +1, ``t`` = ``n`` turned by
+90 degrees), compression negative. With the jump ``[u] = u_+ - u_-``, gap
``g_n = [u].n`` and slip ``g_t = [u].t`` (sticking: tangential jump from the
reference state) or slip increment ``g_t = [u - u_old].t`` (Coulomb, path
dependent: ``u_old`` the last accepted load step, see
:meth:`ContactProblem.accept_step`; zero when the load is applied in one step),
the Alart-Curnier augmented multipliers are

    P_n = min(0, lambda_n + r g_n)
    P_t = lambda_t + r g_t                                 (sticking)
    P_t = clamp(lambda_t + r g_t, mu P_n, -mu P_n)          (Coulomb)

and the residual (Ben Dhia's mixed form, generalized Newton by ``ufl.derivative``):

    sum_s a_s(u_s, v_s) + int (P_n [v].n + P_t [v].t)
        - int (1/r) ((lambda_n - P_n) mu_n + (lambda_t - P_t) mu_t) = L(v)

``r = augmentation * E / h`` (``h`` the cell diameter). LBB: by default a
consistent Barbosa-Hughes stabilisation of the multiplier (see
:class:`~xfem_contact.mechanics.elasticity.ElasticityProblem`); ``lbb="restriction"``
instead reduces the multiplier space with vital vertices (:mod:`xfem_contact.mechanics.lbb`).
"""

from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import evaluate_at_rules, interface_points, rule_cells
from xfem_contact.fem.restriction import MultiplierProlongation, restriction_matrix
from xfem_contact.mechanics import lbb as lbb_module
from xfem_contact.mechanics.elasticity import ElasticityProblem
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.newton import NewtonReport, RestrictedNewton

CONTACT_LAWS = ("frictionless", "coulomb", "sticking")
LBB_OPTIONS = ("stabilized", "restriction", "none")


class ContactProblem(ElasticityProblem):
    """Two-sided elasticity with a contact law on the interface, solved by SNES.

    Args:
        cut: The cut mesh.
        degree: Displacement degree (1 or 2); multipliers are P1 on the
            vertices of cut cells (the paper's P2-P1 element for degree 2).
        materials: One :class:`Material` or one per side.
        law: ``"frictionless"``, ``"coulomb"`` or ``"sticking"``.
        friction: Coulomb coefficient (>= 0), required by ``"coulomb"``.
        augmentation: Dimensionless factor of ``r = augmentation * E / h`` (> 0).
        lbb: ``"stabilized"`` (default), ``"restriction"`` (vital vertices) or ``"none"``.
        multiplier_stabilization: Weight of the stabilisation (``lbb="stabilized"``).
        multiplier_extension: Weight of the normal-gradient term fixing the
            multiplier off the interface (see :class:`ElasticityProblem`; not with
            ``lbb="none"``).
        ghost_penalty: See :class:`ElasticityProblem`.
    """

    LAWS = CONTACT_LAWS

    @staticmethod
    def multiplier_components(law: str, gdim: int) -> int:
        return 1 if law == "frictionless" else gdim

    def __init__(
        self,
        cut: CutMesh,
        degree: int,
        materials: Material | dict[int, Material],
        law: str,
        friction: float | None = None,
        augmentation: float = 1.0,
        lbb: str = "stabilized",
        multiplier_stabilization: float = 0.1,
        multiplier_extension: float = 1e-12,
        ghost_penalty: float = 0.01,
    ):
        if law == "coulomb" and friction is None:
            raise ValueError("The 'coulomb' law needs a friction coefficient (friction=...)")
        if friction is not None and not friction >= 0.0:
            raise ValueError(f"The friction coefficient must be >= 0, got {friction}")
        if not augmentation > 0.0:
            raise ValueError(f"The augmentation parameter must be > 0, got {augmentation}")
        if lbb not in LBB_OPTIONS:
            raise ValueError(f"Unknown LBB treatment {lbb!r}; valid: {LBB_OPTIONS}")
        super().__init__(
            cut,
            degree,
            materials,
            law,
            ghost_penalty=ghost_penalty,
            multiplier_stabilization=multiplier_stabilization if lbb == "stabilized" else 0.0,
            multiplier_extension=multiplier_extension if lbb != "none" else 0.0,
        )
        self.law, self.friction, self.augmentation, self.lbb = law, friction, augmentation, lbb
        self.w = dolfinx.fem.Function(self.space.W, name="w")
        #: The last accepted load step (its jump is the origin of the slip increment)
        self.w_old = dolfinx.fem.Function(self.space.W, name="w_old")
        self._newton: RestrictedNewton | None = None

    # -- interface kinematics ----------------------------------------------------------
    def frame(self):
        """Unit normal ``n`` and tangent ``t`` of the interface (UFL)."""
        n = self.cut.normal
        return n, ufl.as_vector([-n[1], n[0]])

    def augmentation_field(self):
        """``r = augmentation * E / h`` (Pa/m), UFL."""
        E = 0.5 * (self.materials[-1].E + self.materials[1].E)
        return self.augmentation * E / self.cell_size

    def multipliers(self, fields):
        """(lambda_n, lambda_t or None) of a field tuple."""
        lam = fields[2]
        if self.law == "frictionless":
            return lam, None
        return lam[0], lam[1]

    def augmented(self, fields):
        """Augmented multipliers (P_n, P_t or None) of the current fields (UFL)."""
        n, t = self.frame()
        r = self.augmentation_field()
        jump = fields[1] - fields[0]
        lam_n, lam_t = self.multipliers(fields)
        P_n = ufl.min_value(0.0, lam_n + r * ufl.dot(jump, n))
        if lam_t is None:
            return P_n, None
        if self.incremental:
            old = ufl.split(self.w_old)
            jump = jump - (old[1] - old[0])
        trial_t = lam_t + r * ufl.dot(jump, t)
        if self.law == "sticking":
            return P_n, trial_t
        bound = -self.friction * P_n
        return P_n, ufl.max_value(-bound, ufl.min_value(bound, trial_t))

    def residual(self) -> ufl.Form:
        """The contact residual F(w; v) (UFL, linear in the test functions)."""
        u, v = ufl.split(self.w), self.space.test()
        n, t = self.frame()
        r = self.augmentation_field()
        P_n, P_t = self.augmented(u)
        lam_n, lam_t = self.multipliers(u)
        mu_n, mu_t = self.multipliers(v)
        jump_v = v[1] - v[0]
        interface = P_n * ufl.dot(jump_v, n) - (lam_n - P_n) * mu_n / r
        if P_t is not None:
            interface += P_t * ufl.dot(jump_v, t) - (lam_t - P_t) * mu_t / r
        F = self.bulk_form(u, v) + interface * self.cut.dGamma
        if self.multiplier_extension > 0:
            F -= self.multiplier_extension_form(u[2], v[2])
        if self.multiplier_stabilization > 0:
            F -= self.multiplier_stabilization_form(
                self.traction_vector(u), self.traction_vector(v), u, v
            )
            if self.incremental:
                # The tangential law is incremental (slip of the step): its share of the
                # stabilisation is measured from the last accepted step too, so that the
                # steps telescope (sticking in n steps = in one). Jacobian unchanged.
                old = ufl.split(self.w_old)
                _, old_t = self.multipliers(old)
                old_residual = old_t - ufl.dot(self.interface_traction(old), t)
                F += self.stabilization_scale() * old_residual * mu_t * self.cut.dGamma
        if self._rhs:
            F -= sum(self._rhs[1:], self._rhs[0])
        return F

    def traction_vector(self, fields):
        """Cartesian multiplier vector ``lambda_n n + lambda_t t``."""
        n, t = self.frame()
        lam_n, lam_t = self.multipliers(fields)
        return lam_n * n if lam_t is None else lam_n * n + lam_t * t

    # -- solve ---------------------------------------------------------------------------
    def _prolongation(self) -> MultiplierProlongation | None:
        if self.lbb != "restriction":
            return None
        return vital_vertex_prolongation(self.cut, self.space)

    def interface_state(self, w: dolfinx.fem.Function) -> dict[str, np.ndarray]:
        """Point values at this process's interface quadrature points.

        Returns arrays of shape ``(npoints,)``: ``gap``, ``slip`` and
        ``slip_increment`` (the slip the tangential law sees: of the load step for
        Coulomb, else the slip) (m), the
        multipliers ``lambda_n``, ``lambda_t`` and the augmented (applied)
        tractions ``P_n``, ``P_t`` (Pa; tangential ones zero when frictionless),
        and ``r`` (Pa/m).
        """
        cut = self.cut
        rules = cut.interface_rules
        jump = evaluate_at_rules(w.sub(1), cut, rules) - evaluate_at_rules(w.sub(0), cut, rules)
        lam = evaluate_at_rules(w.sub(2), cut, rules)
        normals = rules.normals
        tangents = np.c_[-normals[:, 1], normals[:, 0]]
        E = 0.5 * (self.materials[-1].E + self.materials[1].E)
        h = self.cell_size
        r = (
            self.augmentation
            * E
            / h.x.array[h.function_space.dofmap.list[rule_cells(cut, rules), 0]]
        )
        gap = np.sum(jump * normals, axis=1)
        slip = np.sum(jump * tangents, axis=1)
        if self.incremental:
            old = self.w_old
            jump_old = evaluate_at_rules(old.sub(1), cut, rules) - evaluate_at_rules(
                old.sub(0), cut, rules
            )
            slip_increment = slip - np.sum(jump_old * tangents, axis=1)
        else:
            slip_increment = slip
        lam_n = lam[:, 0]
        lam_t = lam[:, 1] if lam.shape[1] > 1 else np.zeros_like(lam_n)
        P_n = np.minimum(0.0, lam_n + r * gap)
        trial = lam_t + r * slip_increment
        if self.law == "frictionless":
            P_t = np.zeros_like(P_n)
        elif self.law == "sticking":
            P_t = trial
        else:
            P_t = np.clip(trial, self.friction * P_n, -self.friction * P_n)
        return {
            "gap": gap,
            "slip": slip,
            "slip_increment": slip_increment,
            "lambda_n": lam_n,
            "lambda_t": lam_t,
            "P_n": P_n,
            "P_t": P_t,
            "r": r,
            "trial_t": trial,
        }

    def interface_samples(self) -> dict[str, list[float]]:
        """The interface state of the solution at the quadrature points of all processes
        (for plots and summaries): ``x``, ``y``, ``gap``, ``slip`` (m), ``lambda_n``,
        ``lambda_t``, ``P_n``, ``P_t`` (Pa), each a list over the points. Collective."""
        state = self.interface_state(self.w)
        points = interface_points(self.cut)
        local = {"x": points[:, 0], "y": points[:, 1]}
        local |= {k: state[k] for k in ("gap", "slip", "lambda_n", "lambda_t", "P_n", "P_t")}
        comm = self.mesh.comm
        return {k: np.concatenate(comm.allgather(v)).tolist() for k, v in local.items()}

    def interface_status(self, w: dolfinx.fem.Function) -> dict:
        """Global counts of interface quadrature points in contact / stick / slip."""
        state = self.interface_state(w)
        contact = state["P_n"] < 0.0
        counts = {"contact": int(contact.sum())}
        if self.law != "frictionless":
            bound = np.inf if self.law == "sticking" else -self.friction * state["P_n"]
            stick = contact & (np.abs(state["trial_t"]) <= bound)
            counts |= {"stick": int(stick.sum()), "slip": int((contact & ~stick).sum())}
        comm = self.mesh.comm
        return {k: comm.allreduce(v, op=MPI.SUM) for k, v in counts.items()}

    @property
    def incremental(self) -> bool:
        """Whether the tangential law acts on the slip of the load step (Coulomb)."""
        return self.law == "coulomb"

    def accept_step(self) -> None:
        """Accept the current solution as the end of a load step: the Coulomb slip of
        the next step is measured from it (friction is path dependent)."""
        self.w.x.scatter_forward()
        self.w_old.x.array[:] = self.w.x.array

    def solve(
        self, petsc_options: dict | None = None, log: Callable[[str], None] | None = None
    ) -> NewtonReport:
        """Generalized Newton (SNES) on the active dofs; ``self.w`` holds the result.

        Raises:
            NewtonFailure: with the iteration history, if SNES does not converge.
        """
        if self._newton is None:
            R = restriction_matrix(self.space, self._prolongation())
            self._newton = RestrictedNewton(
                self.residual(),
                self.w,
                self._bcs,
                R,
                petsc_options,
                status=self.interface_status,
                log=log,
            )
        return self._newton.solve()

    @property
    def last_report(self) -> NewtonReport | None:
        """The report of the last :meth:`solve` (None before the first)."""
        return None if self._newton is None else self._newton.report


def vital_vertex_prolongation(cut: CutMesh, space) -> MultiplierProlongation:
    """Multiplier prolongation from the vital vertices of the cut edges. Collective.

    Cut edges (end vertices on opposite sides of the interpolated level set) of
    the cut cells are gathered globally, vital vertices chosen identically on
    every process (:func:`xfem_contact.mechanics.lbb.vital_vertices`), and each multiplier
    dof of a vertex on a cut edge expressed by :func:`xfem_contact.mechanics.lbb.prolongation`.
    Multiplier dofs of vertices on no cut edge stay free unknowns.
    """
    mesh = cut.mesh
    tdim = mesh.topology.dim
    comm = mesh.comm
    mesh.topology.create_connectivity(tdim, 1)
    mesh.topology.create_connectivity(1, 0)
    c2e = mesh.topology.connectivity(tdim, 1)
    e2v = mesh.topology.connectivity(1, 0)
    vmap = mesh.topology.index_map(0)
    # Vertex sides from the level set at vertices (0 counts as +1)
    phi = cut.levelset.function
    V = phi.function_space
    c2v = mesh.topology.connectivity(tdim, 0)
    nv_cell = c2v.offsets[1] - c2v.offsets[0]
    cell_vertices = c2v.array.reshape(-1, nv_cell)
    vertex_phi = np.zeros(vmap.size_local + vmap.num_ghosts)
    vertex_phi[cell_vertices] = phi.x.array[V.dofmap.list[:, :nv_cell]]
    vertex_side = np.where(vertex_phi < 0.0, -1, 1).astype(np.int8)
    ne_cell = c2e.offsets[1] - c2e.offsets[0]
    edges = np.unique(c2e.array.reshape(-1, ne_cell)[cut.cut_cells].ravel())
    ends = e2v.array.reshape(-1, 2)[edges]
    crossing = vertex_side[ends[:, 0]] != vertex_side[ends[:, 1]]
    ends = ends[crossing]
    global_ends = vmap.local_to_global(ends.ravel()).reshape(-1, 2)
    all_ends = np.concatenate(comm.allgather(global_ends))
    all_sides = np.concatenate(comm.allgather(vertex_side[ends]))
    vital = lbb_module.vital_vertices(all_ends, all_sides)
    rows, cols, vals, reduced = lbb_module.prolongation(all_ends, vital)
    # Vertices of cut cells on no cut edge (e.g. the far corner of a quadrilateral
    # cut near one vertex) take the mean of the prolongated rows of the cut-edge
    # vertices of their cut cells.
    cut_vertices = vmap.local_to_global(cell_vertices[cut.cut_cells].ravel()).reshape(-1, nv_cell)
    cut_vertices = np.concatenate(comm.allgather(cut_vertices)).reshape(-1, nv_cell)
    on_edge = np.isin(cut_vertices, rows)
    pairs = {
        (f, nb)
        for cell, mask in zip(cut_vertices, on_edge, strict=True)
        for f in cell[~mask]
        for nb in cell[mask]
    }
    if pairs:
        extra_rows, extra_cols, extra_vals = [], [], []
        neighbours: dict[int, list[int]] = {}
        for f, nb in sorted(pairs):
            neighbours.setdefault(int(f), []).append(int(nb))
        for f, nbs in neighbours.items():
            for nb in nbs:
                sel = rows == nb
                extra_rows.append(np.full(sel.sum(), f))
                extra_cols.append(cols[sel])
                extra_vals.append(vals[sel] / len(nbs))
        rows = np.concatenate([rows, *extra_rows])
        cols = np.concatenate([cols, *extra_cols])
        vals = np.concatenate([vals, *extra_vals])
    # Multiplier dofs per vertex (P1: cell-local dof i sits at cell vertex i)
    comps = space.multiplier_components
    mdofs = space.W.sub(2).dofmap.list.reshape(cell_vertices.shape[0], nv_cell, comps)
    dof_of_vertex = np.full((vertex_phi.size, comps), -1, dtype=np.int64)
    dof_of_vertex[cell_vertices] = mdofs
    # Reduced multiplier unknowns, numbered rank-major: each process owns the
    # unknowns of the vital vertices it owns, in increasing global id.
    owned_global = vmap.local_to_global(np.arange(vmap.size_local, dtype=np.int32))
    vital_owned = reduced[np.isin(reduced, owned_global)]
    rank_major = np.concatenate(comm.allgather(vital_owned))
    position = np.empty(rank_major.size, dtype=np.int64)
    position[np.searchsorted(reduced, rank_major)] = np.arange(rank_major.size)
    # Prolongation rows of owned vertices
    keep = np.isin(rows, owned_global)
    row_vertices, inverse = np.unique(rows[keep], return_inverse=True)
    local = row_vertices - vmap.local_range[0]  # owned vertices are numbered contiguously
    nrow = row_vertices.size
    dofs = np.concatenate([dof_of_vertex[local, c] for c in range(comps)])
    prow = np.concatenate([inverse.ravel() + c * nrow for c in range(comps)])
    pcol = np.concatenate([position[cols[keep]] * comps + c for c in range(comps)])
    pval = np.tile(vals[keep], comps)
    return MultiplierProlongation(dofs, prow, pcol, pval, num_owned=vital_owned.size * comps)
