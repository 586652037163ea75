"""Cracks with exact solutions as ready problems: the Williams near-tip field, the Griffith
crack and the closed inclined crack with Coulomb friction.

Shared by the tests and the benchmarks. SI units; the material is E = 1 Pa, nu = 0.3,
plane strain unless given. Every crack is straight; by default turned so that no mesh
line follows it, its tips inside cells (never on a node or an edge); the Griffith and
frictional cases also take a mesh of their plate.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.branch import NUMPY, branch_values
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.io.meshes import ghosted_partitioner
from xfem_contact.mechanics.composition import crack_law
from xfem_contact.mechanics.fracture import UFL, GriffithCrack, WilliamsField, kolosov, tip_frame
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

#: The material of the cases (Pa, 1, plane strain)
MATERIAL = Material(1.0, 0.3, "strain")
#: Direction of every crack (rad from the x axis) and the offset of its centre or tip (m
#: per unit of the case's length): off every mesh line
ANGLE, OFFSET = 0.3, np.array([0.0123, 0.0271])
CELLS = {
    "triangle": dolfinx.mesh.CellType.triangle,
    "quadrilateral": dolfinx.mesh.CellType.quadrilateral,
}


@dataclasses.dataclass
class CrackCase:
    """A cracked problem with its exact solution.

    Attributes:
        problem: The problem, loads applied, not solved.
        K: Exact ``(K_I, K_II)`` (Pa m^1/2) of each tip, in the order of
            ``problem.cut.crack.tips``.
        displacement: The exact displacement (m) of side ``s``: ``displacement(s)(x)``,
            ``x`` of shape (3, n), values (2, n).
        size: The length unit of the case (m): the crack's half length ``a`` or the
            square's half width.
    """

    problem: Problem
    K: list[tuple[float, float]]
    displacement: Callable[[int], Callable[[np.ndarray], np.ndarray]]
    size: float


def _square(half: float, n: int, cell: str, comm: MPI.Comm) -> dolfinx.mesh.Mesh:
    if cell not in CELLS:
        raise ValueError(f"cell must be one of {list(CELLS)}, got {cell!r}")
    corners = [np.array([-half, -half]), np.array([half, half])]
    return dolfinx.mesh.create_rectangle(
        comm, corners, [n, n], CELLS[cell], partitioner=ghosted_partitioner()
    )


def _plate(mesh: dolfinx.mesh.Mesh | None, half: float, n: int, cell: str, comm: MPI.Comm):
    """``mesh`` if given, else the structured ``cell`` mesh of ``[-half, half]^2``, ``n``
    cells a side."""
    return _square(half, n, cell, comm) if mesh is None else mesh


def _on_boundary(half: float) -> Callable[[np.ndarray], np.ndarray]:
    return lambda x: np.isclose(np.abs(x[0]), half) | np.isclose(np.abs(x[1]), half)


def _boundary_values(half: float, field: Callable) -> Callable[[np.ndarray], np.ndarray]:
    """``field`` (values (2, n)) on the boundary of the square of half width ``half``, 0
    inside: a Dirichlet value that never evaluates an exact field at a tip on a node."""

    def values(x: np.ndarray) -> np.ndarray:
        on = _on_boundary(half)(x)
        out = np.zeros((2, x.shape[1]))
        out[:, on] = field(x[:, on])
        return out

    return values


def _frame(angle: float = ANGLE) -> tuple[np.ndarray, np.ndarray]:
    d = np.array([math.cos(angle), math.sin(angle)])
    return d, np.array([-d[1], d[0]])


def williams_case(
    n: int,
    degree: int,
    K: tuple[float, float] = (1.0, 0.5),
    tip_radius: float | None = 0.3,
    cell: str = "triangle",
    comm: MPI.Comm = MPI.COMM_WORLD,
    aggregation: float | None = None,
    tip_basis: str = "auto",
    tip_dofs: str = "nodal",
) -> CrackCase:
    """The exact Williams field of ``K = (K_I, K_II)`` on the square ``[-1, 1]^2`` (``n``
    cells a side) with a crack from its left side to a tip near the centre, imposed on the
    whole boundary (each lip's value where the crack meets it). Geometric tip enrichment
    of radius ``tip_radius`` (m; None: topological); ``aggregation``, ``tip_basis``,
    ``tip_dofs``: see
    :class:`~xfem_contact.mechanics.problem.Problem`."""
    d, normal = _frame()
    tip = OFFSET
    cut = CutMesh(
        _square(1.0, n, cell, comm),
        lambda x: (x[0] - tip[0]) * normal[0] + (x[1] - tip[1]) * normal[1],
        degree=degree,
        tangent=lambda x: (x[0] - tip[0]) * d[0] + (x[1] - tip[1]) * d[1],
    )
    field = WilliamsField(tip_frame(tip, d), K[0], K[1], MATERIAL.E, MATERIAL.nu)
    problem = Problem(
        cut,
        degree,
        MATERIAL,
        "free",
        ghost_penalty=0.0,
        tip_radius=tip_radius,
        aggregation=aggregation,
        tip_basis=tip_basis,
        tip_dofs=tip_dofs,
    )
    displacement = _williams_sides(field)
    problem.loads.add_displacement(_on_boundary(1.0), {-1: displacement(-1), 1: displacement(1)})
    return CrackCase(problem, [K], displacement, 1.0)


def williams_energy_error(case: CrackCase) -> float:
    """The relative energy-norm error of a solved :func:`williams_case` against its
    exact field (both sides, the tip cells' Duffy rules included). Collective."""
    problem = case.problem
    cut, u = problem.cut, problem.space.split(problem.w)
    frame = tip_frame(cut.crack.tips[0], cut.crack.directions[0])
    K_I, K_II = case.K[0]
    exact = WilliamsField(frame, K_I, K_II, MATERIAL.E, MATERIAL.nu)
    G = exact.gradient(ufl.SpatialCoordinate(problem.mesh), UFL)
    mu, nu = MATERIAL.E / (2 * (1 + MATERIAL.nu)), MATERIAL.nu
    lmbda = 2 * mu * nu / (1 - 2 * nu)

    def energy(g):
        e = ufl.sym(g)
        return ufl.inner(2 * mu * e + lmbda * ufl.tr(e) * ufl.Identity(2), e)

    def total(expr) -> float:
        local = dolfinx.fem.assemble_scalar(form(expr))
        return problem.mesh.comm.allreduce(local, op=MPI.SUM)

    error = sum(total(energy(ufl.grad(u[i]) - G) * cut.dx(s)) for i, s in enumerate((-1, 1)))
    return math.sqrt(error / sum(total(energy(G) * cut.dx(s)) for s in (-1, 1)))


def _williams_sides(field: WilliamsField) -> Callable[[int], Callable]:
    """The Williams displacement continued smoothly across the crack from side ``s``:
    ``theta`` beyond ``+-pi`` on the other side's part behind the tip."""

    def of_side(side: int) -> Callable[[np.ndarray], np.ndarray]:
        def u(x: np.ndarray) -> np.ndarray:
            (c, s), o = field.frame.direction, field.frame.origin
            x1 = c * (x[0] - o[0]) + s * (x[1] - o[1])
            x2 = c * (x[1] - o[1]) - s * (x[0] - o[0])
            theta = np.arctan2(x2, x1)
            theta = np.where(side * theta < -0.5 * np.pi, theta + side * 2 * np.pi, theta)
            F = branch_values(np.hypot(x1, x2), theta, NUMPY)
            rows = field.coefficients()
            u1, u2 = (sum(a * f for a, f in zip(row, F, strict=True)) for row in rows)
            return np.stack([c * u1 - s * u2, s * u1 + c * u2])

        return u

    return of_side


def griffith_case(
    N: int,
    degree: int,
    beta: float = 0.5 * math.pi,
    tip_radius: float | str | None = 0.3,
    width: float = 2.0,
    comm: MPI.Comm = MPI.COMM_WORLD,
    angle: float = ANGLE,
    offset: tuple[float, float] = tuple(OFFSET),
    cell: str = "triangle",
    mesh: dolfinx.mesh.Mesh | None = None,
    tip_basis: str = "auto",
) -> CrackCase:
    """A Griffith crack of half length ``a = 1`` m, inclined at ``beta`` (rad) to a
    remote tension of 1 Pa, in the square of half width ``width`` (m) meshed with
    ``h = a / N`` (``cell``: triangles or quadrilaterals); Westergaard's exact
    displacement on the boundary, so that the plate's size adds no error. Tip enrichment
    radius ``tip_radius`` (m, or ``"auto"``, see
    :class:`~xfem_contact.mechanics.problem.Problem`). The crack runs at ``angle`` (rad)
    from the x axis through ``offset`` (m): by default off every mesh line (``angle = 0``,
    ``offset = (0, 0)``: along a row of cell edges, tips on nodes). ``mesh``: a mesh of
    that square instead (e.g. unstructured; ``N`` and ``cell`` are then unused)."""
    a, (d, normal) = 1.0, _frame(angle)
    centre = np.asarray(offset, dtype=float) * a
    crack = GriffithCrack.uniaxial(a, 1.0, beta, center=tuple(centre), direction=tuple(d))
    cut = CutMesh(
        _plate(mesh, width, int(round(2 * width * N / a)), cell, comm),
        lambda x: (x[0] - centre[0]) * normal[0] + (x[1] - centre[1]) * normal[1],
        degree=degree,
        tangent=lambda x: np.abs((x[0] - centre[0]) * d[0] + (x[1] - centre[1]) * d[1]) - a,
    )
    problem = Problem(
        cut,
        degree,
        MATERIAL,
        "free",
        ghost_penalty=0.0,
        tip_radius=tip_radius,
        tip_basis=tip_basis,
    )

    def displacement(side: int) -> Callable:
        return lambda x: crack.displacement(x, MATERIAL.E, MATERIAL.nu, MATERIAL.plane)

    problem.loads.add_displacement(_on_boundary(width), _boundary_values(width, displacement(1)))
    K = crack.stress_intensity_factors
    return CrackCase(problem, [K] * len(cut.crack.tips), displacement, a)


def frictional_crack_case(
    N: int,
    degree: int,
    friction: float = 0.3,
    beta: float = 0.25 * math.pi,
    tip_radius: float | str | None = 0.3,
    width: float = 2.0,
    comm: MPI.Comm = MPI.COMM_WORLD,
    lbb: str | None = None,
    angle: float = ANGLE,
    offset: tuple[float, float] = tuple(OFFSET),
    mesh: dolfinx.mesh.Mesh | None = None,
    cell: str = "triangle",
    along_row: float | None = None,
    multiplier_degree: int = 1,
    tip_basis: str = "auto",
) -> CrackCase:
    """A closed crack of half length ``a = 1`` m inclined at ``beta`` to a remote
    compression of 1 Pa, Coulomb friction ``friction`` on its lips, in the square of half
    width ``width`` meshed with ``h = a / N``. The exact solution (sliding when
    ``|tau| > friction |sigma_n|``): the uniform stress plus Westergaard's mode II field of
    the crack loaded by the effective shear ``tau_eff = |tau| - friction |sigma_n|``;
    imposed on the boundary. ``K_I = 0``, ``K_II = sign(tau) tau_eff sqrt(pi a)``. The law
    is ``frictionless`` for ``friction = 0``. ``lbb``: the law's LBB treatment (None: a
    crack's default). ``angle``, ``offset``, ``mesh``: as for :func:`griffith_case`;
    ``cell``: ``"triangle"`` or ``"quadrilateral"``; ``along_row``: None, or the crack
    along a row of cells, this fraction of a cell above a mesh line (``angle`` and the
    second component of ``offset`` are then unused); ``multiplier_degree``: the lips'
    multiplier's (1 or 2); ``tip_basis``: see :class:`~xfem_contact.mechanics.problem.Problem`."""
    a, (d, normal) = 1.0, _frame(angle)
    centre = np.asarray(offset, dtype=float) * a
    if along_row is not None:
        d, normal = np.array([1.0, 0.0]), np.array([0.0, 1.0])
        centre = np.array([centre[0], along_row * a / N])
    S11, S22, S12 = GriffithCrack.uniaxial(a, -1.0, beta).remote
    T = math.copysign(max(abs(S12) - friction * abs(S22), 0.0), S12)
    sliding = GriffithCrack(a, (0.0, 0.0, T), center=tuple(centre), direction=tuple(d))
    mu, kappa = MATERIAL.E / (2 * (1 + MATERIAL.nu)), kolosov(MATERIAL.nu, MATERIAL.plane)
    # the uniform stress the sliding field leaves: (S11, S22, S12 - T), strain C^-1 S
    sxx, syy, sxy = S11, S22, S12 - T
    exx = ((kappa + 1) * sxx + (kappa - 3) * syy) / (8 * mu)
    eyy = ((kappa + 1) * syy + (kappa - 3) * sxx) / (8 * mu)
    exy = sxy / (2 * mu)

    def exact(x: np.ndarray) -> np.ndarray:
        X = (x[0] - centre[0]) * d[0] + (x[1] - centre[1]) * d[1]
        Y = (x[1] - centre[1]) * d[0] - (x[0] - centre[0]) * d[1]
        ux, uy = exx * X + exy * Y, exy * X + eyy * Y
        uniform = np.stack([d[0] * ux - d[1] * uy, d[1] * ux + d[0] * uy])
        return uniform + sliding.displacement(x, MATERIAL.E, MATERIAL.nu, MATERIAL.plane)

    cut = CutMesh(
        _plate(mesh, width, int(round(2 * width * N / a)), cell, comm),
        lambda x: (x[0] - centre[0]) * normal[0] + (x[1] - centre[1]) * normal[1],
        degree=degree,
        tangent=lambda x: np.abs((x[0] - centre[0]) * d[0] + (x[1] - centre[1]) * d[1]) - a,
    )
    options = {"lbb": lbb, "multiplier_degree": multiplier_degree}
    law = (
        crack_law("coulomb", friction=friction, **options)
        if friction > 0
        else crack_law("frictionless", **options)
    )
    problem = Problem(
        cut,
        degree,
        MATERIAL,
        law,
        ghost_penalty=0.0,
        tip_radius=tip_radius,
        tip_basis=tip_basis,
    )
    problem.loads.add_displacement(_on_boundary(width), _boundary_values(width, exact))
    K = (0.0, T * math.sqrt(math.pi * a))
    return CrackCase(problem, [K] * len(cut.crack.tips), lambda side: exact, a)


def frictional_slip(s: np.ndarray, friction: float = 0.3, beta: float = 0.25 * math.pi):
    """The exact slip ``[u] . t`` (m) of :func:`frictional_crack_case` at the distance
    ``s`` (m) from the crack's centre along it: ``4 (1 - nu^2) T / E sqrt(a^2 - s^2)``
    (plane strain), ``T`` the signed effective shear; and the normal traction (Pa)."""
    _, S22, S12 = GriffithCrack.uniaxial(1.0, -1.0, beta).remote
    T = math.copysign(max(abs(S12) - friction * abs(S22), 0.0), S12)
    E, nu = MATERIAL.E, MATERIAL.nu
    return 4 * (1 - nu**2) * T / E * np.sqrt(np.clip(1.0 - s**2, 0.0, None)), S22


def plate_in_tension(
    path,
    n: int,
    tip_radius: float,
    width: float = 2.0,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> Problem:
    """A square plate of half width ``width`` (m, ``n`` P2 triangles a side) with the crack
    ``path`` (a :class:`~xfem_contact.mechanics.fracture.GrowthPath`, traction-free lips),
    pulled by 1 Pa on its top and bottom sides, the rigid modes held at two corners (they
    carry no load). Not solved. For growth: ``grow(problem, path, da, rings)``."""
    cut = CutMesh(_square(width, n, "triangle", comm), path.phi, degree=2, tangent=path.psi)
    problem = Problem(cut, 2, MATERIAL, "free", tip_radius=tip_radius)
    problem.loads.add_traction(lambda x: np.isclose(x[1], width), (0.0, 1.0))
    problem.loads.add_traction(lambda x: np.isclose(x[1], -width), (0.0, -1.0))
    for component in (0, 1):
        problem.loads.add_point_displacement((-width, -width), 0.0, component)
    problem.loads.add_point_displacement((width, -width), 0.0, 1)
    return problem
