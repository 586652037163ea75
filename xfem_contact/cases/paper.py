"""The paper's validation cases as ready problems with their exact solutions.

Shared by the demos, the tests and the benchmarks (SI units, tension positive).
"""

from __future__ import annotations

import typing

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.evaluation import interface_points, rule_cells
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.presets import ContactProblem, ElasticityProblem

#: Paper case 2: inclusion centre (m), radius (m), Young's modulus (Pa)
INCLUSION_CENTRE, INCLUSION_RADIUS, INCLUSION_E = (0.5, 0.5), 0.2, 100e6

#: Far-field loadings of the inclusion plate: (sigma_xx, sigma_yy) in Pa
LOADINGS = {
    "paper": (-1.0, -2.0),  # compression -1 Pa lateral, -2 Pa top/bottom
    "hydrostatic": (-1.0, -1.0),
    "pull": (1.0, -2.0),  # pulled in x: part of the interface opens
}


def inclusion_problem(
    n: int,
    degree: int,
    law: str,
    cell: str = "quadrilateral",
    loading: str = "paper",
    comm: MPI.Comm = MPI.COMM_WORLD,
    radius: float = INCLUSION_RADIUS,
    materials: dict[int, Material] | None = None,
    levelset: str = "distance",
    **options,
) -> ElasticityProblem:
    """Paper case 2: unit square with a circular inclusion (R = 0.2 m), E = 100 MPa,
    nu = 0, far-field stress ``LOADINGS[loading]`` applied as boundary tractions,
    rigid modes removed by u_x = 0 at (0.5, 0), (0.5, 1) and u_y = 0 at (0, 0.5).
    The stress is uniform, whatever the radius, when both sides share the material.

    Args:
        n: Cells per side (even, so the three points are mesh nodes).
        degree: Displacement degree.
        law: Interface law (``free``, ``bonded``, ``frictionless``, ``coulomb``, ``sticking``).
        cell: ``quadrilateral`` or ``triangle``.
        loading: A key of :data:`LOADINGS`.
        comm: Communicator of the mesh.
        radius: Inclusion radius (m), for degenerate cuts (through nodes, tiny cuts).
        materials: ``{-1: inside, 1: outside}`` instead of the paper's one material
            (the exact solution then no longer holds).
        levelset: ``"distance"`` (the signed distance, whose P2 interpolant's zero set
            is the circle to O(h^3)) or ``"quadric"`` (``(|x - c|^2 - R^2) / (2 R)``,
            which P2 represents exactly: the exact circle and normal, on which the exact
            contact pressure ``n.sigma.n`` is the trace of a quadratic polynomial).
        options: Passed to the problem (``friction``, ``lbb``, ``augmentation``, ...).
    """
    if loading not in LOADINGS:
        raise ValueError(f"Unknown loading {loading!r}; valid: {sorted(LOADINGS)}")
    mesh = dolfinx.mesh.create_unit_square(comm, n, n, dolfinx.mesh.CellType[cell])
    cx, cy = INCLUSION_CENTRE
    shapes = {
        "distance": lambda x: np.hypot(x[0] - cx, x[1] - cy) - radius,
        "quadric": lambda x: ((x[0] - cx) ** 2 + (x[1] - cy) ** 2 - radius**2) / (2 * radius),
    }
    if levelset not in shapes:
        raise ValueError(f"levelset must be one of {sorted(shapes)}, got {levelset!r}")
    cut = CutMesh(mesh, shapes[levelset], degree=2)
    material = materials or Material(INCLUSION_E, 0.0)
    cls = ContactProblem if law in ContactProblem.LAWS else ElasticityProblem
    problem = cls(cut, degree, material, law, **options)
    sxx, syy = LOADINGS[loading]
    problem.loads.add_pressure(lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0), -sxx)
    problem.loads.add_pressure(lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), -syy)
    problem.loads.add_point_displacement([0.5, 0.0], 0.0, 0)
    problem.loads.add_point_displacement([0.5, 1.0], 0.0, 0)
    problem.loads.add_point_displacement([0.0, 0.5], 0.0, 1)
    problem.loading = loading
    return problem


class InterfaceErrors(typing.NamedTuple):
    """Relative L2 errors on the interface (the paper's norm)."""

    pressure: float  # || lambda_n - n.sigma.n || / || n.sigma.n ||
    tangential: float  # || lambda_t - t.sigma.n || / || t.sigma.n || (nan if not computed)


def inclusion_exact_traction(mesh, loading: str = "paper"):
    """Exact (n.sigma.n, t.sigma.n) on the circle as UFL expressions of x (uniform stress)."""
    x = ufl.SpatialCoordinate(mesh)
    r = x - ufl.as_vector(INCLUSION_CENTRE)
    n = r / ufl.sqrt(ufl.inner(r, r))
    t = ufl.as_vector([-n[1], n[0]])
    sigma = ufl.as_matrix(np.diag(LOADINGS[loading]).tolist())
    return ufl.dot(n, sigma * n), ufl.dot(t, sigma * n)


def pressure_total_variation(problem: ContactProblem, centre=INCLUSION_CENTRE) -> float:
    """Total variation (Pa) of ``lambda_n`` around a closed interface, the interface
    points ordered by polar angle about ``centre``; an oscillating multiplier has a
    total variation far above that of the exact pressure. Collective."""
    samples = problem.interface_samples(problem.w)
    theta = np.arctan2(np.array(samples["y"]) - centre[1], np.array(samples["x"]) - centre[0])
    values = np.array(samples["lambda_n"])[np.argsort(theta)]
    return float(np.abs(np.diff(np.r_[values, values[:1]])).sum())


def pressure_fourier_misfit(
    problem: ContactProblem, modes: int = 9, centre=INCLUSION_CENTRE
) -> float:
    """Largest deviation of ``lambda_n`` around a closed interface from its
    least-squares fit by ``modes`` Fourier modes of the polar angle about ``centre``,
    over the mean ``|lambda_n|`` (dimensionless): the multiplier's oscillation at the
    mesh scale, apart from the smooth variation a finite body adds to the pressure.
    Collective."""
    samples = problem.interface_samples(problem.w)
    theta = np.arctan2(np.array(samples["y"]) - centre[1], np.array(samples["x"]) - centre[0])
    lam = np.array(samples["lambda_n"])
    k = np.arange(modes)
    basis = np.c_[np.cos(np.outer(theta, k)), np.sin(np.outer(theta, k[1:]))]
    smooth = basis @ np.linalg.lstsq(basis, lam, rcond=None)[0]
    return float(np.abs(lam - smooth).max() / np.abs(lam).mean())


def integrate(expr) -> float:
    """Global value of a functional (collective)."""
    f = form(expr)
    return f.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(f), op=MPI.SUM)


def inclusion_errors(problem: ElasticityProblem, w: dolfinx.fem.Function) -> InterfaceErrors:
    """Interface pressure and tangential traction errors of a solved inclusion problem,
    summed with the interface rule itself at its points (numpy: no form to compile).
    Contact laws: their multipliers ``lambda_n``, ``lambda_t``; linear laws: the
    Cartesian multiplier on the exact circle's normal and tangent. Collective."""
    cut = problem.cut
    (name,) = problem.laws
    ctx = problem.contexts[name]
    rules = ctx.rules
    J = cut.maps.jacobian(rule_cells(cut, rules), rules.points)
    ds = rules.weights * np.abs(np.linalg.det(J))  # arc length (m) of each point
    arm = interface_points(cut, rules) - np.asarray(INCLUSION_CENTRE)
    n = arm / np.linalg.norm(arm, axis=1)[:, None]
    t = np.c_[-n[:, 1], n[:, 0]]
    sigma = np.diag(LOADINGS[problem.loading])
    p_ex, t_ex = (np.einsum("pi,ij,pj->p", a, sigma, n) for a in (n, t))
    lam = ctx.values_at(w, ctx.field)
    if not problem.linear:
        lam_n = lam[:, 0]
        lam_t = lam[:, 1] if lam.shape[1] > 1 else None
    else:
        lam_n, lam_t = np.sum(lam * n, axis=1), np.sum(lam * t, axis=1)
    comm = cut.mesh.comm

    def total(values) -> float:
        return comm.allreduce(float(np.sum(values * ds)), op=MPI.SUM)

    e_n = np.sqrt(total((lam_n - p_ex) ** 2) / total(p_ex**2))
    e_t = np.nan
    if lam_t is not None:
        norm_t, diff_t = total(t_ex**2), total((lam_t - t_ex) ** 2)
        e_t = np.sqrt(diff_t / norm_t) if norm_t > 0 else np.sqrt(diff_t)
    return InterfaceErrors(float(e_n), float(e_t))


def straight_interface_exact(x):
    """Paper case 1: exact displacement (m) of the upper block, as a list of two
    components, for numpy points ``x`` (shape (>=2, n)) or the UFL coordinate."""
    return [
        5e-6 * x[0] * (x[1] - 2.0),
        -2.5e-6 * x[0] ** 2 - 5e-7 * x[1] ** 2 + 2e-6 * x[1] + 8e-6,
    ]


def straight_interface_problem(
    nx: int, ny: int, degree: int, cell: str = "quadrilateral", comm: MPI.Comm = MPI.COMM_WORLD
) -> ElasticityProblem:
    """Paper case 1: 3 m x 2 m plate (x in [-1.5, 1.5], y in [0, 2]) cut by y = 1,
    plane stress, E = 10 GPa, nu = 0.2; bottom clamped; top u_x = 0 and
    u_y = -2.5e-6 x^2 + 1e-5 m; pressure 0.1 - 0.05 y MPa on the upper block's
    sides; free interface. Use an odd ``ny`` to keep y = 1 off the mesh lines."""
    mesh = dolfinx.mesh.create_rectangle(
        comm, [[-1.5, 0.0], [1.5, 2.0]], [nx, ny], dolfinx.mesh.CellType[cell]
    )
    cut = CutMesh(mesh, lambda x: x[1] - 1.0, degree=1)
    problem = ElasticityProblem(cut, degree, Material(10e9, 0.2, "stress"), "free")
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 0.0), 0.0)
    problem.loads.add_displacement(lambda x: np.isclose(x[1], 2.0), 0.0, component=0)
    problem.loads.add_displacement(
        lambda x: np.isclose(x[1], 2.0), lambda x: -2.5e-6 * x[0] ** 2 + 1e-5, component=1
    )
    problem.loads.add_pressure(
        lambda x: np.isclose(np.abs(x[0]), 1.5), lambda x: 1e5 - 5e4 * x[1], side=1
    )
    return problem


#: Paper case 3: radii (m), modulus (Pa), outer pressure (Pa), exact contact pressure (Pa)
ANNULUS_RADII = (3.0, 8.0, 20.0)
ANNULUS_E, ANNULUS_PRESSURE = 100e6, 1e6
ANNULUS_CONTACT_PRESSURE = -1825.0 / 1636.0 * 1e6


def annulus_problem(
    n_radial: int,
    n_angular: int,
    degree: int,
    geometry_degree: int = 2,
    comm: MPI.Comm = MPI.COMM_WORLD,
    **options,
) -> ContactProblem:
    """Paper case 3 with alpha = 0 (no rotation yet): plate 3 m <= r <= 20 m, X-FEM
    circular interface r = 8 m in frictionless contact, E = 100 MPa, nu = 0, pressure
    1 MPa on r = 20, inner boundary fixed; u_y = 0 at (20, 0) removes the outer ring's
    free rotation. Exact contact pressure -1825/1636 MPa (Lamé)."""
    from xfem_contact.io.meshes import annulus

    r_in, r_gamma, r_out = ANNULUS_RADII
    mesh = annulus(comm, r_in, r_out, n_radial, n_angular, geometry_degree)
    cut = CutMesh(mesh, lambda x: np.hypot(x[0], x[1]) - r_gamma, degree=2)
    problem = ContactProblem(cut, degree, Material(ANNULUS_E, 0.0), "frictionless", **options)
    tol = 1e-6 * r_out
    problem.loads.add_displacement(lambda x: np.abs(np.hypot(x[0], x[1]) - r_in) < tol, 0.0)
    problem.loads.add_pressure(
        lambda x: np.abs(np.hypot(x[0], x[1]) - r_out) < tol, ANNULUS_PRESSURE
    )
    problem.loads.add_point_displacement([r_out, 0.0], 0.0, 1)
    return problem


def annulus_pressure_error(problem: ContactProblem) -> float:
    """Relative L2 error of the contact pressure against the uniform exact value."""
    lam_n, _ = problem.multipliers(ufl.split(problem.w))
    p = ANNULUS_CONTACT_PRESSURE
    dG = problem.cut.dGamma
    return float(np.sqrt(integrate((lam_n - p) ** 2 * dG) / integrate(p**2 * dG)))
