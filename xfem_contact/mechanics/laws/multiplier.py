"""Laws with an interface multiplier, and their LBB treatments.

The multiplier is Lagrange on the nodes of the interface's cut cells: P1 on their
vertices (``multiplier_degree=1``) or P2 on their vertices and edge nodes
(``multiplier_degree=2``). A space that rich violates the inf-sup (LBB) condition and
oscillates, so every multiplier law takes an ``lbb`` option:

- ``"stabilized"`` (default): the consistent Barbosa-Hughes term
  ``- s int (lambda - t(u)).(mu - t(v))`` (:meth:`MultiplierLaw.stabilization_form`);
- ``"restriction"``: the vital-vertex reduction of the multiplier space
  (:func:`xfem_contact.mechanics.lbb_space.vital_vertex_prolongation`; 2D and 3D);
- ``"none"``: neither (for studies: it oscillates or diverges).

Besides, a tiny normal-gradient term (:meth:`MultiplierLaw.extension_form`) fixes
the multiplier off the interface (not with ``"none"``, but for the cells whose piece
follows a line of their reference coordinates, where it is needed with any treatment).
"""

from __future__ import annotations

import numbers

import ufl

from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.laws.base import (
    Fields,
    FixedAtConstruction,
    InterfaceContext,
    InterfaceLaw,
)
from xfem_contact.mechanics.lbb_space import vital_vertex_prolongation
from xfem_contact.mechanics.parameters import Parameter, constant

LBB_OPTIONS = ("stabilized", "restriction", "none")
#: The lengths the Barbosa-Hughes scale may take (see ``MultiplierLaw.stabilization_scale``)
STABILIZATION_LENGTHS = ("cell", "cut", "patch")
#: The default weight ``gamma`` of the Barbosa-Hughes term with each length
STABILIZATION_WEIGHTS = {"cell": 0.1, "cut": 0.5, "patch": 0.5}
#: Lagrange degrees of a multiplier field
MULTIPLIER_DEGREES = (1, 2)
#: Weight of the normal-gradient term on cells where the interface follows a reference
#: coordinate line (the multiplier modes there have no trace; see ``extension_form``)
ALIGNED_EXTENSION = 0.1


class MultiplierLaw(InterfaceLaw):
    """Base of the laws with a multiplier field (abstract).

    Args:
        lbb: ``"stabilized"``, ``"restriction"`` or ``"none"``.
        multiplier_stabilization: Weight ``gamma`` of the Barbosa-Hughes term
            (used with ``lbb="stabilized"``); a Constant of the forms. Default (None):
            that of :data:`STABILIZATION_WEIGHTS` for ``stabilization_length``.
        multiplier_extension: Weight of the normal-gradient term (see
            :meth:`extension_form`; not with ``lbb="none"``); a Constant of the forms.
        multiplier_degree: Lagrange degree of the multiplier on the cut cells (one of
            :data:`MULTIPLIER_DEGREES`): 1 on their vertices, 2 on their vertices and
            edge nodes (with ``lbb="restriction"`` the vital nodes of
            :func:`~xfem_contact.mechanics.lbb_space.vital_vertex_prolongation`).
        stabilization_length: The length of the Barbosa-Hughes scale (one of
            :data:`STABILIZATION_LENGTHS`): ``"cell"`` the cell's diameter, ``"cut"`` the
            sides' trace lengths in each cut cell, ``"patch"`` those lengths credited
            with the facet neighbours' control through the ghost penalty (see
            :meth:`stabilization_scale`).
    """

    multiplier_stabilization = Parameter(minimum=0.0)
    multiplier_extension = Parameter(minimum=0.0)
    lbb = FixedAtConstruction()
    multiplier_degree = FixedAtConstruction()
    stabilization_length = FixedAtConstruction()

    def __init__(
        self,
        lbb: str = DEFAULT.lbb,
        multiplier_stabilization: float | None = DEFAULT.multiplier_stabilization,
        multiplier_extension: float = DEFAULT.multiplier_extension,
        multiplier_degree: int = DEFAULT.multiplier_degree,
        stabilization_length: str = DEFAULT.stabilization_length,
    ):
        if lbb not in LBB_OPTIONS:
            raise ValueError(f"Unknown LBB treatment {lbb!r}; valid: {LBB_OPTIONS}")
        if stabilization_length not in STABILIZATION_LENGTHS:
            raise ValueError(
                f"Unknown stabilization_length {stabilization_length!r}; valid: "
                f"{STABILIZATION_LENGTHS}"
            )
        integer = isinstance(multiplier_degree, numbers.Integral)
        if (
            not integer
            or isinstance(multiplier_degree, bool)
            or (multiplier_degree not in MULTIPLIER_DEGREES)
        ):
            raise ValueError(
                f"multiplier_degree must be one of {MULTIPLIER_DEGREES}, got {multiplier_degree!r}"
            )
        self.lbb = lbb
        self.multiplier_degree = int(multiplier_degree)
        self.stabilization_length = stabilization_length
        if multiplier_stabilization is None:
            multiplier_stabilization = STABILIZATION_WEIGHTS[stabilization_length]
        self.multiplier_stabilization = multiplier_stabilization
        self.multiplier_extension = multiplier_extension

    @property
    def stabilized(self) -> bool:
        """Whether the forms hold the Barbosa-Hughes term (``lbb="stabilized"``)."""
        return self.lbb == "stabilized"

    @property
    def extended(self) -> bool:
        """Whether the forms hold the normal-gradient term (not with ``lbb="none"``)."""
        return self.lbb != "none"

    def describe(self) -> dict:
        return super().describe() | {
            "lbb": self.lbb,
            "multiplier_degree": self.multiplier_degree,
            "stabilization_length": self.stabilization_length,
        }

    def check_ghost_penalty(self, ctx: InterfaceContext, name: str, value: float) -> None:
        """With ``stabilization_length="patch"`` the trace lengths credit the ghost
        penalty the context was built with (:meth:`InterfaceContext.trace_lengths`): a
        lower weight or factor ``name`` would void their bound, and is refused (a
        higher one keeps it)."""
        built = getattr(ctx, name)
        if self.stabilization_length == "patch" and value < built:
            raise ValueError(
                f"{name} {value!r} is below {built!r}, the value the "
                "stabilization_length='patch' lengths were computed with (they credit it): "
                f"build the problem with the lower {name}"
            )

    def prolongation(self, ctx: InterfaceContext, space):
        if self.lbb != "restriction":
            return None
        return vital_vertex_prolongation(ctx.cut, space, ctx.field, ctx.name)

    # -- LBB terms ----------------------------------------------------------------------
    def side_compliances(self, ctx: InterfaceContext) -> dict:
        """Per side ``s``, ``c_s = l_s / (2 mu_s + lambda_s)`` (m/Pa, UFL, cellwise):
        the side's trace length (:meth:`InterfaceContext.trace_lengths`; the patch
        lengths with ``stabilization_length="patch"``) over its
        P-wave modulus. ``int_Gamma_T |sigma_s n|^2 ds <= a_T_s(u, u) / c_s`` on every
        cut cell ``T`` (``a_T_s`` the side's elastic energy in ``T``): ``|sigma n|^2 <=
        (2 mu + lambda) sigma : eps`` pointwise, with the plane-stress ``lambda`` in
        plane stress."""
        lengths = ctx.trace_lengths(patch=self.stabilization_length == "patch")
        m = ctx.materials
        return {s: lengths[s] / (2.0 * m[s].ufl_mu + m[s].ufl_lmbda) for s in (-1, 1)}

    def traction_weights(self, ctx: InterfaceContext) -> tuple:
        """Weights ``(w_-, w_+)`` of the sides in the interface traction average (UFL).

        ``stabilization_length="cell"``: ``w_- = mu_+ / (mu_- + mu_+)``, ``w_+ = mu_- /
        (mu_- + mu_+)`` (1/2 each for one material): the softer side weighs more, as in
        weighted Nitsche methods (with the plain mean a much stiffer inclusion's
        contact pressure oscillates: docs' mechanics page).

        ``"cut"``: ``w_s = c_s / (c_- + c_+)`` per cut cell (:meth:`side_compliances`):
        the side with the larger share of the cell and the softer side weigh more (the
        volume and stiffness weights of Annavarapu, Hautefeuille and Dolbow 2012); a
        side that holds a sliver of the cell weighs nothing.
        """
        if self.stabilization_length in ("cut", "patch"):
            c = self.side_compliances(ctx)
            total = c[-1] + c[1]
            return c[-1] / total, c[1] / total
        mu_minus, mu_plus = ctx.materials[-1].ufl_mu, ctx.materials[1].ufl_mu
        return mu_plus / (mu_minus + mu_plus), mu_minus / (mu_minus + mu_plus)

    def interface_traction(self, ctx: InterfaceContext, u: Fields) -> ufl.core.expr.Expr:
        """Weighted average traction ``(w_- sigma_-(u_-) + w_+ sigma_+(u_+)) n`` (Pa)
        (see :meth:`traction_weights`)."""
        w_minus, w_plus = self.traction_weights(ctx)
        m = ctx.materials
        stress = w_minus * m[-1].stress(u.minus) + w_plus * m[1].stress(u.plus)
        return stress * ctx.normal

    def stabilization_scale(self, ctx: InterfaceContext) -> ufl.core.expr.Expr:
        """The scale ``s`` (m/Pa, UFL) of the multiplier stabilisation.

        ``stabilization_length="cell"``: ``gamma h / (4 sum_s w_s^2 mu_s)`` (``gamma h /
        (2 mu)`` for one material; ``h`` the cell's diameter, ``w_s`` of
        :meth:`traction_weights`).

        ``"cut"`` (and ``"patch"``, with the patch lengths of
        :meth:`InterfaceContext.trace_lengths`, whose bound counts the ghost penalty
        too): ``gamma (c_- + c_+)`` per cut cell (:meth:`side_compliances`). With
        the weights ``w_s = c_s / (c_- + c_+)`` it bounds what the displacement block
        loses, ``s int_Gamma_T |t(u)|^2 ds <= gamma a_T(u, u)`` on every cut cell ``T``:
        the block keeps ``(1 - gamma)`` of the elastic energy for ``gamma < 1`` however
        the interface cuts, and ``s`` stays at least ``gamma`` times the larger side's
        compliance (docs' stability page).
        """
        gamma = constant(self, "multiplier_stabilization")
        if self.stabilization_length in ("cut", "patch"):
            c = self.side_compliances(ctx)
            return gamma * (c[-1] + c[1])
        w_minus, w_plus = self.traction_weights(ctx)
        shear = w_minus**2 * ctx.materials[-1].ufl_mu + w_plus**2 * ctx.materials[1].ufl_mu
        return gamma * ctx.cell_size / (4.0 * shear)

    def stabilization_form(self, ctx: InterfaceContext, lam, mu, u: Fields, v: Fields):
        """Barbosa-Hughes term ``s int (lambda - t(u)).(mu - t(v))`` (``s`` the
        :meth:`stabilization_scale`, ``t`` the weighted average interface traction;
        ``lam``, ``mu`` Cartesian vectors): consistent, and LBB-stable for any
        multiplier space."""
        t_u, t_v = self.interface_traction(ctx, u), self.interface_traction(ctx, v)
        return self.stabilization_scale(ctx) * ufl.inner(lam - t_u, mu - t_v) * ctx.measure

    def extension_form(self, ctx: InterfaceContext, lam, mu) -> ufl.Form:
        """``gamma h^2 / (2 mu) int_{cut cells} (grad lambda n).(grad mu n) dx``.

        The multiplier lives on the vertices of cut cells but acts on the interface
        only. Where the interface follows a line of the cells' reference coordinates
        (a circle in a polar mesh, a line along a cell row), combinations of those
        vertex functions vanish on the whole interface: every interface term, the
        Barbosa-Hughes one included, misses them and the matrix is singular (Newton
        then stalls on round-off). This term sets the multiplier constant along the
        normal off the interface (the normal-gradient stabilisation of TraceFEM): it
        removes those modes. It only has to make them determinate, so its weight is
        tiny: the term is not consistent for a multiplier varying along a curved
        interface, and larger weights spoil the accuracy (the docs' mechanics page
        gives the weights tried).

        On cells whose piece follows a line of the reference coordinates
        (``ctx.aligned_cells``) the modes have no trace at all, and the term there acts
        on them alone (the normal derivative of a Q1 function across such a line is
        independent of its values on it): it gets the weight ``ALIGNED_EXTENSION``
        instead, so that they are fixed by a term of the size of the others, not by a
        tiny one (the pressure does not depend on that weight; the conditioning does).
        That part holds with every LBB treatment, ``"none"`` too (without it the matrix
        is singular); the tiny term elsewhere only with :attr:`extended`.
        ``lam``, ``mu``: multiplier (scalar or vector) trial/test or coefficient.
        """
        n = ctx.normal
        shear = 0.5 * (ctx.materials[-1].ufl_mu + ctx.materials[1].ufl_mu)
        weight = constant(self, "multiplier_extension") * ctx.cut_cells if self.extended else 0
        if ctx.aligned_cells is not None:
            weight = weight + ALIGNED_EXTENSION * ctx.aligned_cells
        scale = weight * ctx.cell_size**2 / (2.0 * shear)
        grad_lam, grad_mu = ufl.dot(ufl.grad(lam), n), ufl.dot(ufl.grad(mu), n)
        return scale * ufl.inner(grad_lam, grad_mu) * ctx.cut.dx_cut(ctx.name)

    def lbb_terms(self, ctx: InterfaceContext, lam, mu, u: Fields, v: Fields):
        """The LBB terms to subtract from the residual: extension and stabilisation
        (``lam``, ``mu``: Cartesian multiplier vectors of ``u``, ``v``), or None."""
        terms = []
        if self.extended or ctx.aligned_cells is not None:
            terms.append(self.extension_form(ctx, u.multiplier, v.multiplier))
        if self.stabilized:
            terms.append(self.stabilization_form(ctx, lam, mu, u, v))
        return sum(terms[1:], terms[0]) if terms else None
