"""The paper's cases solved without X-FEM: gmsh meshes that follow the interface.

What a user would do without this package: mesh the interface (gmsh, curved P2 cells
for degree 2), solve standard DOLFINx elasticity, read the contact pressure off the
stress on the interface facets. For the paper's cases 2 (closed and sticking: no gap,
no slip) and 3 at alpha = 0 (closed, frictionless, no shear by symmetry) the contact
problem has the solution of the bonded body, so a conforming mesh with shared nodes
is one body-fitted route; the other, duplicated interface lines tied by Nitsche's
method, is :mod:`xfem_contact.cases.fitted_nitsche`. The meshing time is part of the
cost. SI units (m, Pa).
"""

from __future__ import annotations

import pathlib
import tempfile

import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact._timers import phase, seconds
from xfem_contact.cases.paper import (
    ANNULUS_CONTACT_PRESSURE,
    ANNULUS_E,
    ANNULUS_PRESSURE,
    ANNULUS_RADII,
    INCLUSION_CENTRE,
    INCLUSION_E,
    INCLUSION_RADIUS,
    LOADINGS,
    integrate,
)
from xfem_contact.io.gmsh import read_gmsh
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.plain import PlainElasticityProblem

#: The unit square with the circle (centre cx, cy; radius r) as a meshed curve: surfaces
#: 1 "plate", 2 "inclusion", curve group "interface"; format with h, cx, cy, r
INCLUSION_GEO = """
lc = {h};
Point(1) = {{0, 0, 0, lc}}; Point(2) = {{0.5, 0, 0, lc}}; Point(3) = {{1, 0, 0, lc}};
Point(4) = {{1, 0.5, 0, lc}}; Point(5) = {{1, 1, 0, lc}}; Point(6) = {{0.5, 1, 0, lc}};
Point(7) = {{0, 1, 0, lc}}; Point(8) = {{0, 0.5, 0, lc}};
Point(9) = {{{cx}, {cy}, 0, lc}};
Point(10) = {{{cx} + {r}, {cy}, 0, lc}}; Point(11) = {{{cx}, {cy} + {r}, 0, lc}};
Point(12) = {{{cx} - {r}, {cy}, 0, lc}}; Point(13) = {{{cx}, {cy} - {r}, 0, lc}};
Line(1) = {{1, 2}}; Line(2) = {{2, 3}}; Line(3) = {{3, 4}}; Line(4) = {{4, 5}};
Line(5) = {{5, 6}}; Line(6) = {{6, 7}}; Line(7) = {{7, 8}}; Line(8) = {{8, 1}};
Circle(9) = {{10, 9, 11}}; Circle(10) = {{11, 9, 12}};
Circle(11) = {{12, 9, 13}}; Circle(12) = {{13, 9, 10}};
Curve Loop(1) = {{1, 2, 3, 4, 5, 6, 7, 8}}; Curve Loop(2) = {{9, 10, 11, 12}};
Plane Surface(1) = {{1, 2}}; Plane Surface(2) = {{2}};
Physical Surface("plate") = {{1}}; Physical Surface("inclusion") = {{2}};
Physical Curve("interface") = {{9, 10, 11, 12}};
"""

ANNULUS_GEO = """
lc = {h};
Point(1) = {{0, 0, 0, lc}};
{points}
{circles}
Curve Loop(1) = {{5, 6, 7, 8}}; Curve Loop(2) = {{9, 10, 11, 12}};
Curve Loop(3) = {{1, 2, 3, 4}};
Plane Surface(1) = {{1, 2}}; Plane Surface(2) = {{3, 1}};
Physical Surface("inner_ring") = {{1}}; Physical Surface("outer_ring") = {{2}};
Physical Curve("interface") = {{5, 6, 7, 8}};
"""


def annulus_geo(h: float) -> str:
    """Three circles, each of four arcs through the axes' points: curves 1-4 r = 20 m,
    5-8 the interface r = 8 m, 9-12 r = 3 m."""
    points, circles, tag = [], [], 2
    for k, r in enumerate(sorted(ANNULUS_RADII, reverse=True)):  # 20, 8, 3
        ids = []
        for x, y in ((r, 0), (0, r), (-r, 0), (0, -r)):
            points.append(f"Point({tag}) = {{{x}, {y}, 0, lc}};")
            ids.append(tag)
            tag += 1
        first = 1 + 4 * k
        for j in range(4):
            circles.append(f"Circle({first + j}) = {{{ids[j]}, 1, {ids[(j + 1) % 4]}}};")
    return ANNULUS_GEO.format(h=h, points="\n".join(points), circles="\n".join(circles))


def mesh_geo(text: str, degree: int, cell: str, comm: MPI.Comm):
    """Mesh a .geo text (e.g. :data:`INCLUSION_GEO` formatted with ``h, cx, cy, r``, or
    :func:`annulus_geo`) with gmsh on rank 0, cells of ``degree``, and distribute it;
    returns the :class:`~xfem_contact.io.gmsh.GmshMesh`. Collective."""
    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(comm.bcast(folder if comm.rank == 0 else None, root=0)) / "m.geo"
        if comm.rank == 0:
            path.write_text(text)
        comm.barrier()
        return read_gmsh(path, comm, geometry_degree=degree, cell=cell)


def interface_pressure_error(u, gm, material: Material, exact) -> float:
    """Relative L2 error on the interface facets of ``n . sigma(u) n`` (the mean of the
    two sides' stresses, Pa) against ``exact`` (UFL or number, Pa). Collective."""
    mesh = gm.mesh
    dS = ufl.Measure("dS", domain=mesh, subdomain_data=gm.facet_tags)(gm.parts["interface"])
    n = ufl.FacetNormal(mesh)("+")
    sigma = ufl.avg(material.stress(u))
    p = ufl.dot(n, sigma * n)
    return float(np.sqrt(integrate((p - exact) ** 2 * dS) / integrate(exact**2 * dS)))


def fitted_inclusion(
    h: float,
    degree: int,
    cell: str = "triangle",
    comm: MPI.Comm = MPI.COMM_WORLD,
    radius: float = INCLUSION_RADIUS,
) -> dict:
    """Paper case 2 on a mesh that follows the circle (cell size ``h``, m): the pressure
    error against ``-3/2 + cos(2 theta)/2`` Pa, dofs and wall times (s) of meshing,
    solving (forms, assembly, LU) and post-processing. Collective."""
    cx, cy = INCLUSION_CENTRE
    timer = phase("body-fitted mesh")
    gm = mesh_geo(INCLUSION_GEO.format(h=h, cx=cx, cy=cy, r=radius), degree, cell, comm)
    timings = {"mesh": seconds(timer)}
    material = Material(INCLUSION_E, 0.0)
    problem = PlainElasticityProblem(gm.mesh, degree, material)
    sxx, syy = LOADINGS["paper"]
    problem.loads.add_pressure(lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0), -sxx)
    problem.loads.add_pressure(lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), -syy)
    problem.loads.add_point_displacement([0.5, 0.0], 0.0, 0)
    problem.loads.add_point_displacement([0.5, 1.0], 0.0, 0)
    problem.loads.add_point_displacement([0.0, 0.5], 0.0, 1)
    timer = phase("body-fitted solve")
    u = problem.solve().w
    timings["solve"] = seconds(timer)
    timer = phase("body-fitted post")
    x = ufl.SpatialCoordinate(gm.mesh)("+")
    theta = ufl.atan2(x[1] - cy, x[0] - cx)
    error = interface_pressure_error(u, gm, material, -1.5 + 0.5 * ufl.cos(2 * theta))
    timings["post"] = seconds(timer)
    dofs = problem.V.dofmap.index_map.size_global * problem.V.dofmap.bs
    return {"error": error, "dofs": dofs, "timings": timings}


def fitted_annulus(h: float, degree: int, cell: str = "triangle", comm=MPI.COMM_WORLD) -> dict:
    """Paper case 3 at alpha = 0 on a mesh that follows r = 8 m: the pressure error
    against -1825/1636 MPa, dofs and wall times (s), as :func:`fitted_inclusion`."""
    timer = phase("body-fitted mesh")
    gm = mesh_geo(annulus_geo(h), degree, cell, comm)
    timings = {"mesh": seconds(timer)}
    material = Material(ANNULUS_E, 0.0)
    problem = PlainElasticityProblem(gm.mesh, degree, material)
    r_in, _, r_out = ANNULUS_RADII
    tol = 1e-6 * r_out
    problem.loads.add_displacement(lambda x: np.abs(np.hypot(x[0], x[1]) - r_in) < tol, 0.0)
    problem.loads.add_pressure(
        lambda x: np.abs(np.hypot(x[0], x[1]) - r_out) < tol, ANNULUS_PRESSURE
    )
    problem.loads.add_point_displacement([r_out, 0.0], 0.0, 1)
    timer = phase("body-fitted solve")
    u = problem.solve().w
    timings["solve"] = seconds(timer)
    timer = phase("body-fitted post")
    error = interface_pressure_error(u, gm, material, ANNULUS_CONTACT_PRESSURE)
    timings["post"] = seconds(timer)
    dofs = problem.V.dofmap.index_map.size_global * problem.V.dofmap.bs
    return {"error": error, "dofs": dofs, "timings": timings}
