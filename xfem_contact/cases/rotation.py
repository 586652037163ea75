"""Paper case 3 with rotation: the annulus whose inner ring turns by alpha, in large sliding.

Annulus ``3 m <= r <= 20 m``, X-FEM interface ``r = 8 m`` (a level set), one material
(E = 100 MPa, nu = 0), pressure 1 MPa on ``r = 20``, the inner boundary ``r = 3`` turned
rigidly by ``alpha``, frictionless (or Coulomb) contact in large sliding; the outer
ring's spin is removed at one point (``u_y = 0`` at (20, 0)) or along the whole outer
boundary (``u_t = 0`` by a stiff spring, needed when friction transmits a torque).
The small-strain (Lame) pressure is uniform, -1825/1636 MPa, whatever alpha; with
the Saint Venant-Kirchhoff bulk of large kinematics the exact pressure of the *same*
model comes from the axisymmetric problem, a radial ODE integrated to round-off
(:func:`svk_annulus_pressure`). SI units (m, Pa).
"""

from __future__ import annotations

import functools
import warnings

import numpy as np
from mpi4py import MPI

from xfem_contact.cases.paper import (
    ANNULUS_CONTACT_PRESSURE,
    ANNULUS_E,
    ANNULUS_PRESSURE,
    ANNULUS_RADII,
)
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.mechanics.laws import make_law
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

#: Ways of removing the outer ring's spin
OUTER_SUPPORTS = ("point", "tangential_spring")


def _radial_stress(e_r, e_t, mu, lmbda):
    """Second Piola-Kirchhoff ``(S_rr, S_tt)`` (Pa) of the strains ``e_r = u'`` and
    ``e_t = u / R`` (plane strain, Saint Venant-Kirchhoff; the Green-Lagrange strains
    ``e + e^2 / 2`` written without cancellation)."""
    E_rr, E_tt = e_r * (1.0 + 0.5 * e_r), e_t * (1.0 + 0.5 * e_t)
    trace = E_rr + E_tt
    return lmbda * trace + 2.0 * mu * E_rr, lmbda * trace + 2.0 * mu * E_tt


def _shoot(slope, mu, lmbda, radii, steps):
    """Integrate ``d(R P_rr)/dR = P_tt`` (RK4) from ``u(R_i) = 0``, ``u'(R_i) =
    slope``; returns ``(P_rr at the interface, P_rr at R_e)`` (Pa)."""
    r_in, r_gamma, r_out = radii

    def radial_strain(R, e_t, T):  # e_r with (1 + e_r) S_rr(e_r, e_t) = T / R (Newton)
        e_r = 0.0
        for _ in range(30):
            S, _ = _radial_stress(e_r, e_t, mu, lmbda)
            f = (1.0 + e_r) * S - T / R
            step = f / (S + (1.0 + e_r) ** 2 * (lmbda + 2.0 * mu))
            e_r -= step
            if abs(step) <= 1e-15 * (abs(e_r) + 1e-300):
                break
        return e_r

    def rhs(R, u, T):  # (u', T') in Python floats (numpy scalars cost more here)
        e_t = u / R
        e_r = radial_strain(R, e_t, T)
        _, S_tt = _radial_stress(e_r, e_t, mu, lmbda)
        return e_r, (1.0 + e_t) * S_tt

    S_rr, _ = _radial_stress(slope, 0.0, mu, lmbda)
    u, T = 0.0, float(r_in * (1.0 + slope) * S_rr)
    values = {}
    for start, end in ((r_in, r_gamma), (r_gamma, r_out)):
        h = (end - start) / steps
        R = start
        for _ in range(steps):
            a1, b1 = rhs(R, u, T)
            a2, b2 = rhs(R + h / 2, u + h / 2 * a1, T + h / 2 * b1)
            a3, b3 = rhs(R + h / 2, u + h / 2 * a2, T + h / 2 * b2)
            a4, b4 = rhs(R + h, u + h * a3, T + h * b3)
            u += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            T += h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
            R += h
        values[end] = T / end
    return values[r_gamma], values[r_out]


@functools.lru_cache
def svk_annulus_pressure(
    E: float = ANNULUS_E,
    nu: float = 0.0,
    radii: tuple = ANNULUS_RADII,
    pressure: float = ANNULUS_PRESSURE,
    steps: int = 500,
) -> float:
    """Exact contact pressure (Pa, nominal: per unit reference length, negative) of
    case 3 with the Saint Venant-Kirchhoff bulk: the axisymmetric radial problem
    (frictionless contact closed, one material: a continuous ring, the inner ring's
    rigid rotation irrelevant by objectivity) solved by shooting on ``u'(R_i)`` with
    RK4 (``steps`` per ring; the default is converged to round-off). Not collective."""
    mu = E / (2.0 * (1.0 + nu))
    lmbda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    slopes = [0.0, -pressure / E]
    misfits = [_shoot(s, mu, lmbda, radii, steps)[1] + pressure for s in slopes]
    for _ in range(30):  # secant on the outer traction
        change = misfits[-1] - misfits[-2]
        if abs(misfits[-1]) < 1e-13 * pressure or change == 0.0:
            break
        s = slopes[-1] - misfits[-1] * (slopes[-1] - slopes[-2]) / change
        slopes.append(s)
        misfits.append(_shoot(s, mu, lmbda, radii, steps)[1] + pressure)
    return _shoot(slopes[-1], mu, lmbda, radii, steps)[0]


def rotating_annulus_problem(
    n_radial: int,
    degree: int,
    alpha: float,
    n_angular: int | None = None,
    law: str = "frictionless",
    friction: float | None = None,
    outer: str = "point",
    comm: MPI.Comm = MPI.COMM_WORLD,
    quadrature_degree: int = 6,
    segments: bool = True,
    **options,
) -> Problem:
    """Case 3 turned by ``alpha`` (rad) at load factor 1, in large kinematics.

    Args:
        n_radial: Cells across the annulus; ``n_angular`` around (default ``4 n``).
        degree: Displacement degree; degree 2 uses curved 9-node cells, degree 1
            straight 4-node ones (a polygonal outline), as in the paper.
        alpha: Rotation of ``r = 3`` (rad), ramped with the load factor together with
            the pressure.
        law: ``frictionless`` (or ``coulomb`` with ``friction``) in large sliding.
        outer: ``"point"`` (``u_y = 0`` at (20, 0)) or ``"tangential_spring"``
            (``u_t = 0`` along ``r = 20``, a spring of 1000 E / h); ``"tangential"`` is
            its deprecated name.
        quadrature_degree: Of the cut's rules (the cut's default 6), i.e. of each
            slave (sub-)segment's Gauss rule.
        segments: Segment-to-segment integration of the hybrid elements (the slave
            pieces broken where their feet cross master-piece ends, where the master
            field's derivative jumps); False: the cut's interface rule, whose Gauss
            points then integrate across those kinks (see the docs' large-sliding
            page).
        options: Passed to :class:`~xfem_contact.mechanics.problem.Problem` (e.g.
            ``pairing``, ``slave``, ``ghost_penalty``) or to the law (``lbb``, ...).
    """
    from xfem_contact.io.meshes import annulus

    if outer == "tangential":
        warnings.warn(
            'outer="tangential" is deprecated and will be removed in the next release: '
            'use outer="tangential_spring"',
            DeprecationWarning,
            stacklevel=2,
        )
        outer = "tangential_spring"
    if outer not in OUTER_SUPPORTS:
        raise ValueError(f"Unknown outer support {outer!r}; valid: {OUTER_SUPPORTS}")
    problem_keys = ("pairing", "slave", "ghost_penalty", "min_support_fraction")
    problem_keys += ("petsc_options", "petsc_options_prefix")
    problem_options = {k: options.pop(k) for k in problem_keys if k in options}
    r_in, r_gamma, r_out = ANNULUS_RADII
    n_angular = 4 * n_radial if n_angular is None else n_angular
    mesh = annulus(comm, r_in, r_out, n_radial, n_angular, 2 if degree == 2 else 1)
    cut = CutMesh(
        mesh,
        lambda x: np.hypot(x[0], x[1]) - r_gamma,
        degree=2,
        quadrature_degree=quadrature_degree,
    )
    interface = make_law(law, friction=friction, **options)
    problem = Problem(
        cut, degree, Material(ANNULUS_E, 0.0), interface, kinematics="large", **problem_options
    )
    for sliding in problem.laws.values():
        sliding.segments = segments
    tol = 1e-6 * r_out
    problem.loads.add_rotation(lambda x: np.abs(np.hypot(x[0], x[1]) - r_in) < tol, angle=alpha)
    outside = lambda x: np.abs(np.hypot(x[0], x[1]) - r_out) < tol  # noqa: E731
    problem.loads.add_pressure(outside, ANNULUS_PRESSURE)
    if outer == "point":
        problem.loads.add_point_displacement([r_out, 0.0], 0.0, 1)
    else:
        h = (r_out - r_in) / n_radial
        problem.loads.add_tangential_spring(outside, 1e3 * ANNULUS_E / h)
    return problem


def pressure_errors(problem: Problem, reference: float | None = None) -> dict[str, float]:
    """Contact-pressure measures of a solved case-3 problem: ``error``, the relative
    L2 error (arc-length weighted over the slave points) against ``reference``
    (default :func:`svk_annulus_pressure`), ``lame_error`` against the small-strain
    value, ``oscillation`` ``(max - min) / |p_Lame|`` of ``lambda_n`` and ``mean``
    (Pa). Collective."""
    reference = svk_annulus_pressure() if reference is None else reference
    coupling = next(iter(problem.couplings.values()))
    lam = problem.interface_state(problem.w)["lambda_n"]
    w = coupling.weights
    comm = problem.mesh.comm

    def total(a):
        return comm.allreduce(float(np.sum(a)), op=MPI.SUM)

    length = total(w)

    def error(p):
        return float(np.sqrt(total(w * (lam - p) ** 2) / (p * p * length)))

    high = comm.allreduce(float(lam.max(initial=-np.inf)), op=MPI.MAX)
    low = comm.allreduce(float(lam.min(initial=np.inf)), op=MPI.MIN)
    return {
        "error": error(reference),
        "lame_error": error(ANNULUS_CONTACT_PRESSURE),
        "oscillation": (high - low) / abs(ANNULUS_CONTACT_PRESSURE),
        "mean": total(w * lam) / length,
    }
