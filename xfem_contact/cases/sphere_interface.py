"""Measures of the multiplier on the sphere of the 3D cases (see
:mod:`xfem_contact.cases.solid`): its surface total variation and oscillation (the LBB
check), the area where it sticks, and its difference to the multiplier of another mesh
(the fine-mesh reference of a case without an exact solution)."""

from __future__ import annotations

import dolfinx.geometry
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.cases.paper import integrate
from xfem_contact.cases.solid import SPHERE_RADIUS, interface_rule
from xfem_contact.fem.evaluation import interface_points
from xfem_contact.mechanics.laws.base import STICK


def surface_total_variation(problem) -> float:
    """``int_Gamma |grad_Gamma lambda_n| dA`` (Pa m) of a solved contact problem: the
    total variation of the contact pressure on the interface, by the interface rule
    (a compiled form). An oscillating multiplier has one far above the exact
    pressure's. Collective."""
    lam_n, _ = problem.multipliers(ufl.split(problem.w))
    n = problem.cut.normal
    g = ufl.grad(lam_n)
    g_surface = g - ufl.dot(g, n) * n
    return integrate(ufl.sqrt(ufl.dot(g_surface, g_surface)) * problem.cut.dGamma)


def pressure_oscillation(problem, pressure: float, radius: float) -> float:
    """``R int |grad_Gamma lambda_n| dA / (|p| 4 pi R^2)`` (dimensionless) of a solved
    problem whose exact contact pressure ``p`` (Pa) is uniform on a sphere of radius
    ``R`` (m): 0 for the exact pressure, of order 1 for a multiplier that swings by its
    own size from cell to cell. Collective."""
    area = 4.0 * np.pi * radius**2
    return radius * surface_total_variation(problem) / (abs(pressure) * area)


def exact_surface_total_variation(problem, stress) -> float:
    """The same of the exact pressure ``n.sigma.n`` of the uniform ``stress`` (3x3, Pa)
    on the sphere of radius ``SPHERE_RADIUS``: ``|grad_Gamma p| = 2 |(I - n n) sigma n|
    / R``, summed by the problem's interface rule. Collective."""
    _, n, dA = interface_rule(problem)
    traction = n @ np.asarray(stress)
    tangential = traction - np.sum(traction * n, axis=1)[:, None] * n
    local = float(np.sum(2.0 / SPHERE_RADIUS * np.linalg.norm(tangential, axis=1) * dA))
    return problem.mesh.comm.allreduce(local, op=MPI.SUM)


def stick_fraction(problem) -> float:
    """The fraction of the interface's area (0..1) where a solved contact problem's law
    sticks, by the interface rule. Collective."""
    ctx, _, dA = interface_rule(problem)
    (law,) = problem.laws.values()
    state = law.state(ctx, problem.w)
    stick = law.point_status(state, dA.size) == STICK
    comm = problem.mesh.comm
    area = comm.allreduce(float(dA.sum()), op=MPI.SUM)
    return comm.allreduce(float(dA[stick].sum()), op=MPI.SUM) / area


#: The parts of a Cartesian multiplier :func:`multiplier_difference` measures
MULTIPLIER_PARTS = ("all", "normal", "tangential")


def multiplier_difference(problem, reference, part: str = "all") -> float:
    """Relative L2 difference on ``problem``'s interface of its Cartesian multiplier
    (Pa) and that of ``reference`` (the same case solved on another mesh, read at the
    same points: the exact sphere of ``levelset="quadric"`` lies in the reference's
    cut cells), by ``problem``'s interface rule. ``part``: the whole vector
    (``"all"``), its normal part ``(lambda.n) n`` or its tangential part ``(I - n n)
    lambda`` (``n`` the exact sphere's), each over the same part of the reference's.
    Serial: the reference is read where the points fall in its local cells."""
    if problem.mesh.comm.size > 1:
        raise ValueError("multiplier_difference: serial only (reads another mesh's cells)")
    if part not in MULTIPLIER_PARTS:
        raise ValueError(f"part must be one of {MULTIPLIER_PARTS}, got {part!r}")
    ctx, n, dA = interface_rule(problem)
    lam = ctx.values_at(problem.w, ctx.field)
    (name,) = reference.laws
    field = reference.contexts[name].field
    lam_ref_function = reference.w.sub(field).collapse()
    points = interface_points(problem.cut, ctx.rules)
    mesh = reference.mesh
    tree = dolfinx.geometry.bb_tree(mesh, mesh.topology.dim)
    candidates = dolfinx.geometry.compute_collisions_points(tree, points)
    colliding = dolfinx.geometry.compute_colliding_cells(mesh, candidates, points)
    cells = np.array([colliding.links(i)[0] for i in range(points.shape[0])], dtype=np.int32)
    lam_ref = lam_ref_function.eval(points, cells)
    if part != "all":
        normal = np.sum(lam * n, axis=1)[:, None] * n, np.sum(lam_ref * n, axis=1)[:, None] * n
        lam, lam_ref = (
            (normal[0], normal[1]) if part == "normal" else (lam - normal[0], lam_ref - normal[1])
        )
    misfit = np.sum(np.sum((lam - lam_ref) ** 2, axis=1) * dA)
    return float(np.sqrt(misfit / np.sum(np.sum(lam_ref**2, axis=1) * dA)))
