"""What an interface law is: the context it is given and the contract it fulfils.

A :class:`~xfem_contact.mechanics.problem.Problem` composes one law object per
interface. A law

- declares the multiplier field it needs (:meth:`InterfaceLaw.multiplier_components`);
- contributes its terms to the residual ``F(w; v)`` (:meth:`InterfaceLaw.residual`,
  UFL on the interface's measure) and, for laws that couple two cells (large
  sliding), an assembled contribution (:meth:`InterfaceLaw.coupling`);
- evaluates its state at the interface rule points (:meth:`InterfaceLaw.state`)
  *from the same definitions and the same normal* as the residual it enforces, so
  the reported status is what was solved;
- answers what callers ask of any law, with the base class's defaults:
  :attr:`~InterfaceLaw.transmits` (what a closed interface carries),
  :meth:`~InterfaceLaw.multipliers`, :meth:`~InterfaceLaw.traction_vector`,
  :meth:`~InterfaceLaw.point_status`, :meth:`~InterfaceLaw.options`. Callers never
  test a law's type or name.

Conventions: the normal ``n`` points from side -1 to side +1, the jump is
``[u] = u_+ - u_-`` and the multiplier is the traction ``sigma n`` on side -1 (Pa,
compression negative). The tangential part of a vector ``v``
(:meth:`InterfaceContext.tangential`) is, in 2D, the scalar ``v.t`` along ``t``, ``n``
turned by +90 degrees, and in 3D the vector ``(I - n n) v``: the laws are written once
on these parts, for any ``gdim``. SI units.
"""

from __future__ import annotations

import abc
import dataclasses
import inspect
import typing

import dolfinx.fem
import numpy as np
import numpy.typing as npt
import ufl

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import FieldSampler, rule_cells
from xfem_contact.fem.trace_inverse import patch_trace_lengths, side_trace_lengths
from xfem_contact.geometry.levelset import CellMaps, LevelSet
from xfem_contact.mechanics.materials import Material
from xfem_contact.quadrature.rules import RuleSet


class Fields(typing.NamedTuple):
    """The fields a law acts on: both sides' displacements (m) and its multiplier
    (Pa; ``None`` for laws without one). UFL trial, test or coefficient parts."""

    minus: typing.Any
    plus: typing.Any
    multiplier: typing.Any = None

    @property
    def jump(self):
        """``[u] = u_+ - u_-`` (m)."""
        return self.plus - self.minus


@dataclasses.dataclass(frozen=True)
class InterfaceContext:
    """One interface as a law sees it (built by the problem; local to a process).

    Attributes:
        cut: The cut mesh.
        name: The interface's name (``cut.interface_names``).
        measure: Its interface measure (arc length, m).
        rules: Its interface rules (rows index ``cut.cut_cells``).
        materials: The constant materials on its two sides, ``{-1: inside, 1: outside}``.
        cell_size: Cell diameters ``h`` (m), DG0.
        cut_cells: 1 on the cut cells of this interface, 0 elsewhere (UFL, cellwise).
        field: Index of the law's multiplier field in the mixed space (None without).
        w_old: The last accepted state (origin of incremental laws' slip).
        degree: The displacements' Lagrange degree.
        aligned_cells: 1 on the cut cells whose interface piece follows a line of the
            cell's reference coordinates (trace nullity >= 2, see
            :meth:`~xfem_contact.fem.cutmesh.CutMesh.trace_nullity`), DG0; None when
            no process has one.
        split: The fields of a Function on the mixed space, e.g. ``split(w_old)`` (the
            space's ``split``: the displacements with a crack's branch functions).
        ramp: The ramp ``R`` of a crack's branch functions (Lagrange; see
            :class:`~xfem_contact.fem.enrichment.EnrichedSpace`), None without.
        interpolants: Per side, the interpolants subtracted from ``R F_k`` (the space's
            :attr:`~xfem_contact.fem.enrichment.EnrichedSpace.interpolants`), None without.
        ghost_penalty: The ghost penalty's weight as built (the patch lengths credit it).
        ghost_penalty_higher: Its factor of the second-derivative jumps as built.
    """

    cut: CutMesh
    name: str
    measure: ufl.Measure
    rules: RuleSet
    materials: dict[int, Material]
    cell_size: dolfinx.fem.Function
    cut_cells: typing.Any
    field: int | None
    w_old: dolfinx.fem.Function
    degree: int
    aligned_cells: dolfinx.fem.Function | None = None
    split: typing.Callable = ufl.split
    ramp: dolfinx.fem.Function | None = None
    interpolants: dict[int, tuple[dolfinx.fem.Function, ...]] | None = None
    ghost_penalty: float = 0.0
    ghost_penalty_higher: float = 1.0
    #: Point values cached for the fixed rules (basis tables, dofs, the normal) and the
    #: objects made :meth:`once`
    _cache: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    def once(self, key: str, make: typing.Callable[[], typing.Any]) -> typing.Any:
        """``make()`` the first time ``key`` is asked for on this context, the same
        object afterwards (e.g. a law's coupling of this interface)."""
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    def trace_lengths(self, patch: bool = False) -> dict[int, dolfinx.fem.Function]:
        """``{-1: l_-, 1: l_+}``: each side's trace length on the interface's cut cells
        (m, DG0 on :attr:`cell_size`'s space, 0 elsewhere; see
        :mod:`xfem_contact.fem.trace_inverse`): ``int_Gamma_T p^2 ds <= int_T_s p^2 dx /
        l_s`` for the strains ``p`` of a side. With ``patch``, the side's energy in
        ``T`` credited with its facet neighbours' through the ghost penalty
        (:func:`~xfem_contact.fem.trace_inverse.patch_trace_lengths`, with
        :attr:`ghost_penalty` and the sides' Lamé parameters as built). Made once per
        context, that is per cut. Collective."""

        def make():
            V0 = self.cell_size.function_space
            cells = V0.dofmap.list[self.cut.cut_cells, 0]
            if patch:
                h = self.cell_size.x.array[V0.dofmap.list[:, 0]]
                lengths = patch_trace_lengths(
                    self.cut,
                    self.name,
                    self.degree,
                    self.ghost_credit(),
                    h,
                    self.ghost_penalty_higher,
                )
            else:
                lengths = side_trace_lengths(self.cut, self.name, self.degree)
            out = {}
            for side, values in lengths.items():
                f = dolfinx.fem.Function(V0, name=f"trace_length_{side:+d}")
                f.x.array[cells] = values
                f.x.scatter_forward()
                out[side] = f
            return out

        return self.once("patch_trace_lengths" if patch else "trace_lengths", make)

    def ghost_credit(self) -> dict[int, float]:
        """Per side ``eta_s = g 2 mu_s / (2 mu_s + d lambda_s)`` (``g`` the
        :attr:`ghost_penalty`, ``d`` the dimension): the ghost penalty of side ``s``
        bounds ``eta_s sum_j c_j h^(2j+1) |[grad^j q]|^2`` on a facet for every
        component ``q`` of ``C^1/2 eps`` (``|C^1/2 e|^2 <= (2 mu + d lambda) |e|^2``;
        ``c_0 = 1``, ``c_j`` the :attr:`ghost_penalty_higher` for ``j >= 1``). 0 for a
        side whose material varies by region."""
        out = {}
        for s, m in self.materials.items():
            material = getattr(m, "material", None)
            if material is None:
                out[s] = 0.0
                continue
            mu, lmbda = material.mu, material.lmbda
            out[s] = self.ghost_penalty * 2.0 * mu / (2.0 * mu + self.gdim * lmbda)
        return out

    @property
    def gdim(self) -> int:
        """The mesh's geometric dimension (2 or 3)."""
        return self.cut.mesh.geometry.dim

    @property
    def normal(self) -> ufl.core.expr.Expr:
        """Unit normal ``grad phi_h / |grad phi_h|`` (UFL)."""
        return self.cut.normal

    def frame(self) -> tuple:
        """Unit normal ``n`` and tangent ``t`` (``n`` turned by +90 degrees), UFL; 2D only
        (a law uses :meth:`tangential`)."""
        if self.gdim != 2:
            raise ValueError(f"frame: the tangent t is a 2D notion (gdim={self.gdim})")
        n = self.normal
        return n, self.once("tangent", lambda: ufl.as_vector([-n[1], n[0]]))

    def tangential(self, v) -> ufl.core.expr.Expr:
        """The tangential part of the vector ``v`` (UFL): ``v.t`` in 2D (a scalar, see
        :meth:`frame`), ``(I - n n) v`` in 3D (a vector)."""
        if self.gdim == 2:
            return ufl.dot(v, self.frame()[1])
        n = self.normal
        return v - ufl.dot(v, n) * n

    def multiplier_parts(self, lam) -> tuple:
        """``(lambda_n, lambda_t)`` of a multiplier with normal and tangential parts (UFL,
        ``gdim`` components): in 2D its components in the frame ``(n, t)``; in 3D a
        Cartesian traction, split as ``lambda.n`` and ``(I - n n) lambda`` (no tangent
        frame is smooth on a closed surface)."""
        if self.gdim == 2:
            return lam[0], lam[1]
        return ufl.dot(lam, self.normal), self.tangential(lam)

    def tangent_vector(self, a) -> ufl.core.expr.Expr:
        """The Cartesian vector of a tangential part ``a`` (:meth:`tangential`): ``a t``
        in 2D, ``a`` itself in 3D (UFL)."""
        return a * self.frame()[1] if self.gdim == 2 else a

    def fields(self, parts) -> Fields:
        """The law's :class:`Fields` of a split mixed function or argument."""
        return Fields(parts[0], parts[1], None if self.field is None else parts[self.field])

    # -- the same quantities at the rule points (numpy, local) -----------------------
    def normal_at(self) -> npt.NDArray[np.float64]:
        """``n`` at the rule points, ``(npoints, gdim)``: the UFL normal evaluated there
        (not the interface's own normal)."""
        if "normal" not in self._cache:
            self._cache["normal"] = self.cut.normal_at(self.rules)
        return self._cache["normal"]

    def frame_at(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """``n`` and ``t`` at the rule points, each ``(npoints, 2)`` (2D only, as
        :meth:`frame`)."""
        if self.gdim != 2:
            raise ValueError(f"frame_at: the tangent t is a 2D notion (gdim={self.gdim})")
        if "frame" not in self._cache:
            n = self.normal_at()
            self._cache["frame"] = (n, np.c_[-n[:, 1], n[:, 0]])
        return self._cache["frame"]

    def multiplier_parts_at(self, lam: npt.NDArray[np.float64]) -> tuple:
        """:meth:`multiplier_parts` of multiplier values at the rule points, ``(npoints,
        gdim)``: ``lambda_n`` ``(npoints,)`` and ``lambda_t`` as :meth:`tangential_at`."""
        if self.gdim == 2:
            return lam[:, 0], lam[:, 1]
        return np.sum(lam * self.normal_at(), axis=1), self.tangential_at(lam)

    def tangential_at(self, v: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """:meth:`tangential` of vectors ``v`` given at the rule points, ``(npoints,
        gdim)``: ``(npoints,)`` in 2D, ``(npoints, 3)`` in 3D."""
        if self.gdim == 2:
            return np.sum(v * self.frame_at()[1], axis=1)
        n = self.normal_at()
        return v - np.sum(v * n, axis=1)[:, None] * n

    def values_at(self, w: dolfinx.fem.Function, field: int) -> npt.NDArray[np.float64]:
        """Values of field ``field`` of ``w`` (a Function on the problem's mixed space)
        at the rule points, ``(npoints, value_size)``."""
        key = ("sampler", id(w.function_space))
        if key not in self._cache:
            cells = rule_cells(self.cut, self.rules)
            self._cache[key] = (
                w.function_space,
                FieldSampler(w.function_space, cells, self.rules.points),
            )
        return self._cache[key][1](w, field)

    def jump_at(self, w: dolfinx.fem.Function) -> npt.NDArray[np.float64]:
        """``[u]`` of ``w`` at the rule points, ``(npoints, gdim)`` (m); on a crack's
        lips with the branch functions' jump: ``[F_1] = 2 sqrt(r)`` (``r = |psi|``
        there), the others vanish at ``theta = +-pi``; minus the jump of the
        :attr:`interpolants` where the space has them."""
        jump = self.values_at(w, 1) - self.values_at(w, 0)
        crack = self.cut.crack
        if crack is not None:
            if "sqrt_r" not in self._cache:
                cells = self.cut.cut_cells[self.rules.point_rows]
                psi = CellMaps(self.cut.mesh, crack.tangent).values(cells, self.rules.points)
                self._cache["sqrt_r"] = np.sqrt(np.abs(psi))[:, None]
            b = self.values_at(w, w.function_space.num_sub_spaces - 1)  # the branch field
            ramp = self._ramp_at()[:, None]  # the space's R of R F_k
            jump += 2 * self._cache["sqrt_r"] * ramp * b[:, : jump.shape[1]]
            if self.interpolants is not None:
                cells = self.cut.cut_cells[self.rules.point_rows]
                gdim = jump.shape[1]
                pairs = zip(self.interpolants[-1], self.interpolants[1], strict=True)
                for k, pair in enumerate(pairs):
                    minus, plus = (
                        CellMaps(self.cut.mesh, LevelSet(f, None)).values(cells, self.rules.points)
                        for f in pair
                    )
                    jump -= (plus - minus)[:, None] * b[:, gdim * k : gdim * (k + 1)]
        return jump

    def _ramp_at(self) -> npt.NDArray[np.float64]:
        """The :attr:`ramp` of the branch functions at the rule points (1 without)."""
        if self.ramp is None:
            return np.ones(len(self.rules.point_rows))
        cells = self.cut.cut_cells[self.rules.point_rows]
        return CellMaps(self.cut.mesh, LevelSet(self.ramp, None)).values(cells, self.rules.points)

    def cell_size_at(self) -> npt.NDArray[np.float64]:
        """``h`` (m) of the cell of every rule point, ``(npoints,)``."""
        h = self.cell_size
        cells = self.cut.cut_cells[self.rules.point_rows]
        return h.x.array[h.function_space.dofmap.list[cells, 0]]


class Ops(typing.NamedTuple):
    """Pointwise operations, so that one definition of a law serves UFL and numpy:
    ``minimum``, ``maximum``; ``norm(a)`` of a tangential part (a vector: UFL one, or
    numpy ``(npoints, gdim)`` rows), ``scale(s, a)`` and ``divide(a, s)``, ``s a`` and
    ``a / s`` for a scalar ``s``; ``below(a, b, x, y)``: ``x`` where ``a <= b``, else
    ``y``."""

    minimum: typing.Callable
    maximum: typing.Callable
    norm: typing.Callable
    scale: typing.Callable
    divide: typing.Callable
    below: typing.Callable


def _rows(s, a):
    """``s`` broadcast over the rows of ``a`` (numpy)."""
    return s[..., None] if np.ndim(a) > np.ndim(s) else s


UFL_OPS = Ops(
    ufl.min_value,
    ufl.max_value,
    lambda a: ufl.sqrt(ufl.dot(a, a)),
    lambda s, a: s * a,
    lambda a, s: a / s,
    lambda a, b, x, y: ufl.conditional(ufl.le(a, b), x, y),
)
NUMPY_OPS = Ops(
    np.minimum,
    np.maximum,
    lambda a: np.linalg.norm(a, axis=-1),
    lambda s, a: _rows(s, a) * a,
    lambda a, s: a / _rows(s, a),
    lambda a, b, x, y: np.where(_rows(a <= b, x), x, y),
)


def project_on_disc(trial, bound, ops: Ops):
    """The projection of a tangential part ``trial`` on the disc ``|P| <= bound``
    (``bound >= 0``): ``trial`` inside, ``bound (trial / |trial|)`` outside (``trial = 0``
    with ``bound = 0`` is inside: no division by zero is taken).

    A tangential part is a scalar in 2D (:meth:`InterfaceContext.tangential`): the disc
    is then the segment ``[-bound, bound]`` and the projection the clamp
    ``max(-bound, min(bound, trial))``, the same value to the last bit (``trial /
    |trial|`` is exactly +-1) with a Jacobian free of the round-off of differentiating
    ``trial / |trial|``.
    """
    if len(getattr(trial, "ufl_shape", np.shape(trial)[1:])) == 0:
        return ops.maximum(-bound, ops.minimum(bound, trial))
    norm = ops.norm(trial)
    with np.errstate(divide="ignore", invalid="ignore"):  # trial / 0: only where not taken
        return ops.below(norm, bound, trial, ops.scale(bound, ops.divide(trial, norm)))


#: What a closed interface transmits (:attr:`InterfaceLaw.transmits`)
TRANSMITS = ("none", "normal", "full")
#: Codes of :meth:`InterfaceLaw.point_status`: open, sticking, slipping
OPEN, STICK, SLIP = 0, 1, 2


class InterfaceLaw(abc.ABC):
    """An interface law (abstract). Subclasses set :attr:`name` and :attr:`linear`."""

    #: The law's name in scenes and messages
    name: typing.ClassVar[str]
    #: Whether the law's residual is linear in the unknowns (one linear solve)
    linear: typing.ClassVar[bool]
    #: Whether the law acts on the increment since the last accepted state
    incremental: typing.ClassVar[bool] = False
    #: Whether the law's Jacobian is symmetric in every state, so that the Newton
    #: steps may factor LDL^T (:mod:`xfem_contact.solvers.symmetry`); checked on
    #: every matrix factored so
    symmetric: typing.ClassVar[bool] = False
    #: Whether the law pairs the lips in large sliding (the hybrid element)
    sliding: typing.ClassVar[bool] = False
    #: Whether the multiplier has a tangential component in the interface frame
    #: (``lambda_t`` of a contact law; a Cartesian multiplier has none)
    tangential: typing.ClassVar[bool] = False
    #: The LBB treatment of the law's multiplier (``"none"`` without a multiplier)
    lbb: str = "none"
    #: The Lagrange degree of the law's multiplier field (1 without a multiplier)
    multiplier_degree: int = 1

    @property
    def transmits(self) -> str:
        """What a closed interface of the law transmits between its sides (one of
        :data:`TRANSMITS`): ``"full"`` by default, ``"normal"`` for contact without
        friction, ``"none"`` for traction-free lips."""
        return "full"

    def multiplier_components(self, gdim: int) -> int:
        """Number of components of the law's multiplier field (0: none)."""
        return 0

    def multipliers(self, ctx: InterfaceContext, u: Fields) -> tuple:
        """``(lambda_n, lambda_t or None)`` of the law's fields (UFL; ``lambda_t`` a
        tangential part, :meth:`InterfaceContext.tangential`); by default the
        multiplier as it is (a Cartesian vector, or None without one)."""
        return u.multiplier, None

    def traction_vector(self, ctx: InterfaceContext, u: Fields):
        """The traction ``sigma n`` on side -1 the law's multiplier stands for, as a
        Cartesian vector (UFL), or None without a multiplier; by default the
        multiplier itself."""
        return u.multiplier

    def point_status(self, state: dict[str, np.ndarray], npoints: int) -> np.ndarray:
        """Per rule point :data:`OPEN`, :data:`STICK` or :data:`SLIP` (int8,
        ``(npoints,)``) from :meth:`state`; by default what :attr:`transmits` says of
        a closed interface: open for ``"none"``, sticking otherwise."""
        code = OPEN if self.transmits == "none" else STICK
        return np.full(npoints, code, dtype=np.int8)

    def options(self) -> dict:
        """The law's constructor options and their current values, e.g. to build the
        same law in another kinematics."""
        return {name: getattr(self, name) for name in law_options(type(self))}

    def residual(self, ctx: InterfaceContext, u: Fields, v: Fields) -> ufl.Form | None:
        """The law's terms of the residual ``F(w; v)`` (UFL), or None.

        ``u`` holds the parts of the unknown (or trial functions for linear laws:
        the terms are then the bilinear form), ``v`` the test functions.
        """
        return None

    def coupling(self, ctx: InterfaceContext):
        """An assembled contribution beyond UFL cell integrals (laws coupling two
        cells, e.g. large sliding), or None."""
        return None

    def prolongation(self, ctx: InterfaceContext, space):
        """A multiplier prolongation (LBB restriction) of the law's field, or None."""
        return None

    def state(self, ctx: InterfaceContext, w: dolfinx.fem.Function) -> dict[str, np.ndarray]:
        """The law's state at this process's rule points, each ``(npoints,)`` (the
        tangential parts ``(npoints, 3)`` in 3D)."""
        return {}

    def status(self, state: dict[str, np.ndarray]) -> dict[str, int]:
        """Local counts of rule points by status (e.g. contact, stick, slip)."""
        return {}

    def describe(self) -> dict:
        """The law's name and options (for summaries)."""
        return {"law": self.name}

    def check_ghost_penalty(self, ctx: InterfaceContext, name: str, value: float) -> None:
        """Refuse a new value of the ghost penalty's parameter ``name``
        (``"ghost_penalty"`` or ``"ghost_penalty_higher"``) that the forms built on
        ``ctx`` rely on being larger (ValueError); none here."""
        return None


class FixedAtConstruction:
    """A law option that shapes the forms or the pairing (the LBB treatment, the slave
    side, ...): set once by the constructor, then read-only, so that a new value is
    refused in one line instead of being silently ignored by what was built on it."""

    def __set_name__(self, owner, name: str):
        self.name, self.private = name, f"_{name}"

    def __get__(self, law, owner=None):
        if law is None:
            return self
        return getattr(law, self.private)

    def __set__(self, law, value) -> None:
        if hasattr(law, self.private):
            raise ValueError(
                f"{self.name} is fixed when the law is built (its forms and pairing follow "
                f"it): build a new law with {self.name}={value!r} instead"
            )
        setattr(law, self.private, value)


def law_options(law: type[InterfaceLaw]) -> tuple[str, ...]:
    """The options a law class takes (the named arguments of its constructors)."""
    names: list[str] = []
    for cls in law.__mro__:
        init = vars(cls).get("__init__")
        if init is None:
            continue
        for p in inspect.signature(init).parameters.values():
            if p.name != "self" and p.kind is p.POSITIONAL_OR_KEYWORD and p.name not in names:
                names.append(p.name)
    return tuple(names)
