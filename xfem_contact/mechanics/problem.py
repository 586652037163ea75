"""A mechanics problem on a cut mesh: one bulk model composed with one law per interface.

:class:`Problem` owns the enriched space (a displacement per side, one multiplier
field per law that needs one), the bulk model of each side, the loads and the
Dirichlet data, and composes the interface laws (:mod:`xfem_contact.mechanics.laws`):
the residual is the bulk's plus each law's terms minus the loads. Linear laws: one KSP
solve; contact laws: generalized Newton (SNES), on the active dofs of the prolongation
``R`` (:mod:`xfem_contact.fem.prolongation`). SI units (Pa, m)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping

import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.fem.cut_state import CutState
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.enrichment import EnrichedSpace
from xfem_contact.fem.prolongation import prolongation_matrix
from xfem_contact.mechanics.augmentation_restarts import solve_restarting
from xfem_contact.mechanics.bulk import BULK_MODELS, KINEMATICS, cell_size, check_ghosts
from xfem_contact.mechanics.composition import Materials, interface_laws, side_and_law_materials
from xfem_contact.mechanics.contexts import interface_context, samples, status_counts
from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.laws import InterfaceLaw, large_sliding
from xfem_contact.mechanics.loads import Loads, SideFields
from xfem_contact.mechanics.parameters import bound_copy
from xfem_contact.mechanics.rigid_modes import check_support
from xfem_contact.mechanics.solving import linear_solve, newton_solver, prolongation_parts
from xfem_contact.solvers.log_lines import lines_to
from xfem_contact.solvers.newton import NewtonFailure, ReducedNewton
from xfem_contact.solvers.options import (
    Facts,
    checked_prefix,
    problem_options,
)
from xfem_contact.solvers.report import LinearSolveFailure, SolveReport


class Problem:
    """Elasticity of the two sides of a cut mesh with a law on each interface.

    Args:
        cut: The cut mesh.
        degree: Displacement degree (1 or 2); multipliers are Lagrange of each law's
            ``multiplier_degree`` on the cut cells: P1 on their vertices (default; the
            paper's P2-P1 element for degree 2) or P2 on their vertices and edge nodes.
        materials: One :class:`Material`, or ``{-1: inside, 1: outside}``; with several
            interfaces ``inside`` may be ``{interface name: Material}``.
        law: A law (object or name) for every interface, or ``{interface name: law}``
            (names of ``cut.interface_names``).
        ghost_penalty: Weight of the ghost penalty (see :class:`SmallStrain`); None:
            the default's, 0 for a crack (it spoils the tip's field: energy error x3).
        ghost_penalty_higher: Factor of the ghost penalty's jumps of second and higher
            derivatives relative to the gradient's (see :class:`SmallStrain`).
        min_support_fraction: See :class:`EnrichedSpace`. Default: every dof with the
            ghost penalty (it extends the field), else those with support on their side.
        aggregation: Cell aggregation (see :class:`EnrichedSpace`): the side volume
            fraction below which a cut cell's dofs are extended from a root cell; None:
            off. Dirichlet dofs stay unknowns; a dof extended from Dirichlet dofs takes
            their prescribed values
            (:func:`~xfem_contact.mechanics.solving.prescribed_extension`).
        kinematics: ``"small"`` (linear elasticity, small sliding) or ``"large"`` (Saint
            Venant-Kirchhoff bulk, contact laws in large sliding: the slave/master hybrid
            element of :mod:`xfem_contact.mechanics.sliding`).
        slave, pairing: See :class:`~xfem_contact.mechanics.laws.sliding.SlidingFrictionless`
            (``kinematics="large"`` only): the slave side, when pairs are searched.
        tip_radius: A crack's tip enrichment radius (m), ``"auto"`` (default: a fixed
            fraction of the tips' crack length, not of the mesh) or None (the tip cells'
            nodes), see :class:`EnrichedSpace`.
        tip_basis: The functions of a crack's branch dofs, ``"auto"`` (default:
            ``"shifted"`` for degree 2 without ``aggregation``, else ``"plain"``),
            ``"plain"`` or ``"shifted"``, see :class:`EnrichedSpace`.
        tip_dofs: A crack's branch unknowns, ``"nodal"`` (default: each vertex of the
            zone its own) or ``"gathered"`` (one per tip, function and component, with a
            smooth cut-off), see :class:`EnrichedSpace`.
        petsc_options: PETSc options (names without prefix) of the solver, over the
            defaults and presets of :mod:`xfem_contact.solvers.options` (see
            :meth:`solver_options`); change them later with :attr:`petsc_options`.
        petsc_options_prefix: The options prefix of the solver's PETSc objects (the SNES
            or KSP, its PC). ``None``: a prefix unique in the process
            (``"xfem_problem_3_"``); an empty one is refused. The same on every process.

    Collective.
    """

    def __init__(
        self,
        cut: CutMesh,
        degree: int,
        materials: Materials,
        law: InterfaceLaw | str | Mapping[str, InterfaceLaw | str] = DEFAULT.law,
        *,
        ghost_penalty: float | None = None,
        ghost_penalty_higher: float = DEFAULT.ghost_penalty_higher,
        min_support_fraction: float | None = DEFAULT.min_support_fraction,
        aggregation: float | None = DEFAULT.aggregation,
        kinematics: str = DEFAULT.kinematics,
        slave: int = DEFAULT.slave,
        pairing: str = DEFAULT.pairing,
        tip_radius: float | str | None = "auto",
        tip_basis: str = "auto",
        tip_dofs: str = "nodal",
        petsc_options: dict | None = None,
        petsc_options_prefix: str | None = None,
    ):
        if kinematics not in KINEMATICS:
            raise ValueError(f"Unknown kinematics {kinematics!r}; valid: {KINEMATICS}")
        #: The options prefix of the solver's PETSc objects
        self.petsc_options_prefix = checked_prefix(petsc_options_prefix, "xfem_problem_")
        self._petsc_options = dict(petsc_options or {})
        self.cut, self.mesh = cut, cut.mesh
        self.kinematics = kinematics
        self.laws = interface_laws(cut, law)
        if kinematics == "large":
            self.laws = {n: large_sliding(law, slave, pairing) for n, law in self.laws.items()}
        # the laws' parameters become Constants of these forms (copied if bound elsewhere)
        self.laws = {n: bound_copy(law, self.mesh) for n, law in self.laws.items()}
        side_materials = side_and_law_materials(cut, materials)
        if ghost_penalty is None:
            ghost_penalty = DEFAULT.ghost_penalty if cut.crack is None else 0.0
        if min_support_fraction is None:
            min_support_fraction = 0.0 if ghost_penalty > 0 else 1e-12
        gdim = self.mesh.geometry.dim
        multipliers = [
            (law.multiplier_components(gdim), name, law.multiplier_degree)
            for name, law in self.laws.items()
        ]
        self.space = EnrichedSpace(
            cut,
            degree,
            multipliers=[m for m in multipliers if m[0] > 0],
            min_support_fraction=min_support_fraction,
            tip_radius=tip_radius,
            aggregation=aggregation,
            tip_basis=tip_basis,
            tip_dofs=tip_dofs,
        )
        check_ghosts(self.mesh)
        #: Loads, supports and Dirichlet data (``loads.bcs``), and the pseudo-time
        self.loads = Loads(SideFields(self.space))
        self.cell_size = cell_size(self.mesh)
        bulk = BULK_MODELS[kinematics]
        self.bulk = bulk(
            self.space,
            side_materials.bulk,
            degree,
            self.cell_size,
            ghost_penalty,
            ghost_penalty_higher,
        )
        #: The materials as Constants of the forms (``Moduli`` per side, per interface
        #: name on side -1 when given so): set ``E`` or ``nu`` on them (no new compile)
        self.materials = side_materials.user
        self.w = dolfinx.fem.Function(self.space.W, name="w")
        #: The last accepted load step (its jump is the origin of incremental slips)
        self.w_old = dolfinx.fem.Function(self.space.W, name="w_old")
        self._law_materials = side_materials.laws
        self._newton: ReducedNewton | None = None
        self._newton_loads: int | None = None
        self._options_changed = False
        self._last_report: SolveReport | None = None
        #: Pseudo-time of the rotations that the bodies of ``w`` have turned by
        self._rotated_at = 0.0
        #: Side of each cell on the cut the problem is attached to (DG0, see
        #: :meth:`~xfem_contact.fem.cutmesh.CutMesh.side_indicator`); the same Function
        #: on every cut, so that the forms keep their signature
        self.side_indicator = cut.side_indicator()
        self._attach(cut.state)

    def _attach(self, state: CutState) -> None:
        """Build what follows the cut ``state`` (the current one of :attr:`cut`): side
        indicator, the laws' contexts and couplings; the Newton solver is rebuilt at the
        next solve. Collective."""
        assert state is self.cut.state, "a problem attaches to its cut's current state"
        self.side_indicator.x.array[:] = self.cut.side_indicator().x.array
        fields = {name: field for field, _, name in self.space.multiplier_fields}
        self.contexts = {
            name: interface_context(
                self.cut,
                name,
                self._law_materials[name],
                fields.get(name),
                self.side_indicator,
                self.cell_size,
                self.w_old,
                self.space.degree,
                self.space.split,
                self.space.ramp,
                self.space.interpolants,
                float(self.bulk.ghost_penalty),
                float(self.bulk.ghost_penalty_higher),
            )
            for name in self.laws
        }
        #: Terms of laws coupling two cells (large sliding), assembled outside UFL
        self.couplings = {
            name: c
            for name, law in self.laws.items()
            if (c := law.coupling(self.contexts[name])) is not None
        }
        if self._newton is not None:
            self._newton.destroy()
            self._newton = None
        self._checked_loads: int | None = None
        #: The cut state the space, contexts and forms were built on
        self.cut_state = state

    def update_interface(self, levelset, tangent=None) -> None:
        """Move the interfaces: cut the mesh with ``levelset`` (as
        :meth:`~xfem_contact.fem.cutmesh.CutMesh.update`, the same interface names;
        a crack with its new ``tangent`` level set too),
        keeping the loads, supports, laws, parameters and ``W``; forms are re-created
        from the compiled ones. The next solve starts from the solution carried onto
        the new active dofs (:meth:`~xfem_contact.fem.enrichment.EnrichedSpace.carry`:
        one continuous displacement, no jump across the new interface; multipliers
        restart at 0), and so does Coulomb's last accepted state ``w_old``: its slip
        history restarts at the new interface. Collective.
        """
        before = self.space.active.copy()
        state = self.cut.update(levelset, tangent)
        self.space.refresh()
        self._attach(state)
        for w in (self.w, self.w_old):
            self.space.carry(w, before)

    @property
    def ghost_penalty(self) -> float:
        """Weight of the ghost penalty (a Constant of the forms: settable, see
        :class:`~xfem_contact.mechanics.bulk.SmallStrain`; the laws may refuse a value)."""
        return self.bulk.ghost_penalty

    @ghost_penalty.setter
    def ghost_penalty(self, value: float) -> None:
        for name, law in self.laws.items():
            law.check_ghost_penalty(self.contexts[name], "ghost_penalty", value)
        self.bulk.ghost_penalty = value

    @property
    def ghost_penalty_higher(self) -> float:
        """Factor of the ghost penalty's jumps of second and higher derivatives (a
        Constant of the forms: settable, see
        :class:`~xfem_contact.mechanics.bulk.SmallStrain`; the laws may refuse a value)."""
        return self.bulk.ghost_penalty_higher

    @ghost_penalty_higher.setter
    def ghost_penalty_higher(self, value: float) -> None:
        for name, law in self.laws.items():
            law.check_ghost_penalty(self.contexts[name], "ghost_penalty_higher", value)
        self.bulk.ghost_penalty_higher = value

    @property
    def linear(self) -> bool:
        """Whether the problem is linear (small kinematics and linear laws: one KSP
        solve instead of Newton)."""
        return self.kinematics == "small" and all(law.linear for law in self.laws.values())

    @property
    def symmetric(self) -> bool:
        """Whether the Jacobian is symmetric (small kinematics, symmetric laws): the
        solves then factor LDL^T (:mod:`xfem_contact.solvers.symmetry`)."""
        small = self.kinematics == "small" and not self.couplings
        return small and all(law.symmetric for law in self.laws.values())

    @property
    def petsc_options(self) -> dict:
        """The PETSc options the user gave (names without prefix; a copy). Setting them
        rebuilds the Newton solver at the next solve. Not collective, but set them
        alike on every process."""
        return dict(self._petsc_options)

    @petsc_options.setter
    def petsc_options(self, options: dict | None) -> None:
        options = dict(options or {})
        self._options_changed |= options != self._petsc_options
        self._petsc_options = options

    def solver_options(self, petsc_options: dict | None = None) -> dict:
        """The PETSc options (without prefix) :meth:`solve` uses: ``petsc_options``
        (default: :attr:`petsc_options`) over the defaults and the presets that apply to
        this problem (the LDL^T of a symmetric one, a crack's, large sliding's; see
        :func:`~xfem_contact.solvers.options.problem_options`). Not collective."""
        solver = "linear" if self.linear else "newton"
        crack_tip = self.space.branch_field is not None
        if petsc_options is None:
            petsc_options = self._petsc_options
        facts = Facts(
            dict(petsc_options),
            self.symmetric,
            crack_tip,
            bool(self.couplings),
            self.mesh.topology.dim,
        )
        return problem_options(solver, facts)

    def law(self, name: str | None = None) -> InterfaceLaw:
        """The law of interface ``name`` (of the only interface for ``None``)."""
        return self.laws[self._name(name)]

    def _name(self, name: str | None) -> str:
        if name is None:
            if len(self.laws) > 1:
                raise ValueError(f"Name the interface: one of {list(self.laws)}")
            return next(iter(self.laws))
        if name not in self.laws:
            raise ValueError(f"Unknown interface {name!r}; valid: {list(self.laws)}")
        return name

    # -- forms -----------------------------------------------------------------------
    def _law_and_spring_terms(self, u, v) -> list:
        springs = self.loads.spring_terms(u, v)
        terms = [] if springs is None else [springs]
        for name, law in self.laws.items():
            ctx = self.contexts[name]
            term = law.residual(ctx, ctx.fields(u), ctx.fields(v))
            if term is not None:
                terms.append(term)
        return terms

    def bilinear_form(self) -> ufl.Form:
        """``a(u, v)`` of a linear problem (bulk plus the laws' terms, UFL)."""
        if not self.linear:
            raise ValueError("A problem with a contact law has a residual, not a bilinear form")
        u, v = self.space.trial(), self.space.test()
        return sum(self._law_and_spring_terms(u, v), self.bulk.form(u, v))

    def residual(self, w: dolfinx.fem.Function) -> ufl.Form:
        """The residual ``F(w; v)`` at the state ``w`` (a function on ``space.W``, e.g.
        :attr:`w`): UFL, linear in the test functions. Large sliding's two-cell terms
        are not in it (``couplings``, assembled at ``w`` by their ``add_residual``)."""
        u, v = self.space.split(w), self.space.test()
        F = sum(self._law_and_spring_terms(u, v), self.bulk.form(u, v))
        if self.loads.has_terms:
            F -= self.loads.linear_form()
        return F

    def multipliers(self, fields, name: str | None = None) -> tuple:
        """``(lambda_n, lambda_t or None)`` (UFL) of a split mixed function, for a
        contact law (the Cartesian multiplier vector for ``bonded``)."""
        name = self._name(name)
        ctx = self.contexts[name]
        return self.laws[name].multipliers(ctx, ctx.fields(fields))

    # -- solve -----------------------------------------------------------------------
    def prolongation(self):
        """The prolongation ``R`` (full x reduced, ``x = R y``) of the active dofs and the
        laws' multiplier prolongations. Collective."""
        return prolongation_matrix(self.space, *prolongation_parts(self))

    def restriction(self):
        """Deprecated name of :meth:`prolongation` (it returns ``R`` with ``x = R y``)."""
        warnings.warn(
            "Problem.restriction() is deprecated and will be removed in the next release: "
            "use Problem.prolongation() (the same matrix R, x = R y)",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.prolongation()

    def solve(
        self, petsc_options: dict | None = None, log: Callable[[str], None] | None = None
    ) -> SolveReport:
        """Solve on the active dofs; ``self.w`` holds the result. Collective.

        Linear problems: one KSP solve. With a contact law: generalized Newton
        (SNES) from ``self.w``, a log record per iterate (INFO, logger
        ``xfem_contact.solvers.newton``), restarted with another augmentation when it
        stalls (:mod:`~xfem_contact.mechanics.augmentation_restarts`). Either way returns a
        :class:`~xfem_contact.solvers.report.SolveReport` (the solution ``w``, its
        fields, iterations, residual history, reason). The Newton solver is kept between
        solves and rebuilt when the loads, the Dirichlet conditions or
        :attr:`petsc_options` were changed since.

        Args:
            petsc_options: Deprecated (give them at construction, or set
                :attr:`petsc_options`): options for this solve only.
            log: Deprecated (install a handler on the ``xfem_contact`` logger, e.g.
                :func:`~xfem_contact.solvers.log_lines.lines_to`): called with each line.

        Raises:
            NewtonFailure: with the iteration history, if SNES does not converge;
                ``self.w`` then holds the state from before this solve (as it does when
                a solve is interrupted, or a callback raises: that exception comes out
                as itself).
            ValueError: the cut was updated after the problem was built.
        """
        if log is not None:
            warnings.warn(
                "Problem.solve(log=...) is deprecated and will be removed in the next release: "
                "the solver logs on logging.getLogger('xfem_contact'); show its lines with a "
                "handler, e.g. with xfem_contact.solvers.log_lines.lines_to(print): ...",
                DeprecationWarning,
                stacklevel=2,
            )
        if petsc_options is None:
            with lines_to(log):
                return self._solve()
        warnings.warn(
            "Problem.solve(petsc_options=...) is deprecated and will be removed in the next "
            "release: give the options at construction, Problem(..., petsc_options=...), "
            "or set problem.petsc_options",
            DeprecationWarning,
            stacklevel=2,
        )
        kept, self.petsc_options = self._petsc_options, petsc_options
        try:
            with lines_to(log):
                return self._solve()
        finally:
            self._petsc_options = kept
            self._options_changed |= kept != petsc_options

    def _solve(self) -> SolveReport:
        if self.cut_state is not self.cut.state:
            raise ValueError(
                "The cut changed (cut.update) after this problem was built: its enriched "
                f"space, rules and forms follow the old interface (cut revision "
                f"{self.cut_state.revision}, now {self.cut.revision}); move interfaces with "
                "problem.update_interface(levelset)"
            )
        if self._checked_loads != self.loads.revision:  # again only when the loads changed
            check_support(self)
            self._checked_loads = self.loads.revision
        petsc_options = self.solver_options()
        if self.linear:
            try:
                self._last_report = linear_solve(self, petsc_options)
            except LinearSolveFailure as failure:  # self.w is untouched
                self._last_report = failure.report
                raise
            return self._last_report
        changed = self._options_changed or self._newton_loads != self.loads.revision
        if self._newton is not None and changed:
            self._newton.destroy()  # loads or solver options changed since it was built
            self._newton = None
        if self._newton is None:
            self._newton = newton_solver(self, petsc_options)
            self._newton_loads, self._options_changed = self.loads.revision, False
        accepted = self.w.x.array.copy()
        t = self.loads.time
        if self.kinematics == "large":  # turn rotated bodies rigidly first (predictor)
            self.loads.rotate_bodies(self.w, self._rotated_at, t)
        try:
            report = solve_restarting(self._newton, self.laws)
            self._rotated_at = t
            report.w, report.space = self.w, self.space
            self._last_report = report
            return report
        except NewtonFailure as failure:
            self.w.x.array[:] = accepted  # the state before this solve, not the diverged one
            self._last_report = failure.report
            raise NewtonFailure(
                f"{str(failure).splitlines()[0]}; w restored to the state before this solve",
                failure.report,
            ) from None
        except BaseException:  # e.g. an interrupt, or a callback's error: w as it was
            self.w.x.array[:] = accepted
            raise

    @property
    def solver_timings(self) -> dict[str, float]:
        """Wall times (s) of the Newton solver's set-up (forms, sparsity, first
        Jacobian, scaling; empty before the first contact solve)."""
        return {} if self._newton is None else dict(self._newton.timings)

    @property
    def newton(self) -> ReducedNewton | None:
        """The Newton solver of the contact solves (its ``snes``, the reduced Jacobian
        ``J_r``, ``options``), kept between solves; None before the first or after the
        cut changed (it is rebuilt at the next solve after the loads or the options)."""
        return self._newton

    @property
    def last_report(self) -> SolveReport | None:
        """The report of the last solve, linear or Newton, converged or failed (None
        before the first)."""
        return self._last_report

    def accept_step(self) -> None:
        """Accept the current solution as the end of a load step: incremental laws
        (Coulomb) measure the slip of the next step from it."""
        self.w.x.scatter_forward()
        self.w_old.x.array[:] = self.w.x.array
        for coupling in self.couplings.values():
            coupling.accept(self.w)

    def pairing_counts(self) -> dict[str, dict[str, int]]:
        """Per large-sliding interface, the global counts of slave points paired, unpaired
        and changing master cell since the last accepted step (empty in small sliding)."""
        return {name: dict(c.counts) for name, c in self.couplings.items()}

    def unpaired_points(self) -> dict[str, np.ndarray]:
        """Per large-sliding interface, the reference coordinates (m, ``(k, 2)``) of the
        slave points of all processes that found no master within the search radius
        at the current state (they carry no contact). Collective."""
        return {name: c.unpaired_points(self.w) for name, c in self.couplings.items()}

    # -- interface state -------------------------------------------------------------
    def interface_state(
        self, w: dolfinx.fem.Function, name: str | None = None
    ) -> dict[str, np.ndarray]:
        """The law's state at this process's rule points of interface ``name`` (the only
        one for ``None``) for the state ``w`` (e.g. :attr:`w`; see the law's ``state``)."""
        name = self._name(name)
        return self.laws[name].state(self.contexts[name], w)

    def interface_status(self, w: dolfinx.fem.Function, name: str | None = None) -> dict:
        """Global counts of interface rule points by status (contact / stick / slip) for
        the state ``w``: of interface ``name``, or for ``None`` of all, prefixed by the
        interface name when there are several. Collective."""
        laws = self.laws if name is None else {self._name(name): self.law(name)}
        return status_counts(laws, self.contexts, w)

    def interface_samples(
        self, w: dolfinx.fem.Function, name: str | None = None
    ) -> dict[str, list[float]]:
        """The state ``w`` (e.g. :attr:`w`) at the rule points of all processes of
        interface ``name`` (the only one for ``None``), for plots and summaries (see
        :func:`~xfem_contact.mechanics.contexts.samples`). Collective."""
        name = self._name(name)
        return samples(self.laws[name], self.contexts[name], w)
