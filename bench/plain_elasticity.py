"""The floor of this stack: plain DOLFINx elasticity on the mesh of paper case 2, or of the
3D sphere case.

No cut, no enrichment, no xfem_contact import (but for the mesh of ``--mesh annulus``,
paper case 3's ``--n`` x ``4 n`` curved cells, inner circle clamped, 1 MPa outside):
unit square, ``--n`` x ``--n`` cells,
Lagrange ``--degree`` displacement, E = 100 MPa, nu = 0, the case-2 tractions (-1 Pa
lateral, -2 Pa top and bottom) and the same three point constraints, one direct solve
(MUMPS LU, or with ``--factor cholesky`` its Cholesky, the matrix flagged symmetric
positive definite; ``--mumps icntl_7=4`` sets a MUMPS control, so that
``bench/scaling.py`` gives it the factorisation and controls xfem-contact's solver uses) and
the displacement written as VTX, as the demo does (``--out ''``: not written).
``--mesh cube``: the unit cube, ``--n`` cells per edge (``--cell tetrahedron`` or
``hexahedron``), the material (E = 100 Pa, nu = 0.3) and triaxial pressures of the sphere case
(``xfem_contact.cases.solid.sphere_problem`` without its sphere: 1, 2, 3 Pa on the
faces normal to x, y, z) and its seven point constraints. ``--factor gamg``: CG +
algebraic multigrid with the rigid modes (3 in 2D, 6 in 3D). Prints one JSON line
of dofs, wall times per phase (s) and each rank's CPU time (s); ``bench/scaling.py``
runs it as a process of its own next to the demo. Run: ``python
bench/plain_elasticity.py --n 160 [--degree 2]``, also under ``mpiexec``.
"""

import argparse
import functools
import json
import pathlib
import resource
import time

# isort: split
import dolfinx_solver  # noqa: F401  (before dolfinx: loads the wheel's PETSc and MPI)

# isort: split
import basix.ufl
import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.io
import dolfinx.la
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

E, NU = 100e6, 0.0
OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


#: The sphere case's material (Pa, -) and principal stresses (Pa) along x, y, z
#: (``SOLID`` and ``TRIAXIAL`` of ``xfem_contact.cases.solid``, not imported: the
#: package stays out of this process)
SOLID_E, SOLID_NU = 100.0, 0.3
TRIAXIAL = (-1.0, -2.0, -3.0)
#: Its point constraints: ``u_i = 0`` at the point (``sphere_problem``'s)
HELD_3D = (
    ((0.5, 0.0, 0.5), 0),
    ((0.5, 1.0, 0.5), 0),
    ((0.5, 0.5, 0.0), 0),
    ((0.5, 0.5, 1.0), 0),
    ((0.0, 0.5, 0.5), 1),
    ((0.5, 0.5, 0.0), 1),
    ((0.0, 0.5, 0.5), 2),
)


def rigid_modes(V: dolfinx.fem.FunctionSpace) -> PETSc.NullSpace:
    """The rigid modes of a 2D (three) or 3D (six) vector space, orthonormalised.
    Collective."""
    gdim = V.dofmap.index_map_bs
    x = V.tabulate_dof_coordinates()
    size = V.dofmap.index_map.size_local
    rotations = [(0, 1)] if gdim == 2 else [(0, 1), (1, 2), (2, 0)]
    count = gdim + len(rotations)
    vectors = [dolfinx.la.vector(V.dofmap.index_map, gdim) for _ in range(count)]
    values = [v.array.reshape(-1, gdim) for v in vectors]
    for k in range(gdim):
        values[k][:size, k] = 1.0
    for mode, (i, j) in zip(values[gdim:], rotations, strict=True):
        mode[:size, i], mode[:size, j] = -x[:size, j], x[:size, i]
    dolfinx.la.orthonormalize(vectors)
    return PETSc.NullSpace().create(vectors=[v.petsc_vec for v in vectors], comm=V.mesh.comm)


def _elasticity(mesh, degree: int, young: float = E, nu: float = NU):
    """The space and the bilinear form of linear elasticity (Pa, -) on ``mesh``."""
    gdim = mesh.geometry.dim
    V = dolfinx.fem.functionspace(
        mesh, basix.ufl.element("Lagrange", mesh.basix_cell(), degree, shape=(gdim,))
    )
    mu, lmbda = young / (2 * (1 + nu)), young * nu / ((1 + nu) * (1 - 2 * nu))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)

    def sigma(w):
        return 2 * mu * ufl.sym(ufl.grad(w)) + lmbda * ufl.tr(ufl.grad(w)) * ufl.Identity(gdim)

    return V, ufl.inner(sigma(u), ufl.sym(ufl.grad(v))) * ufl.dx, v


def square(comm, n: int, degree: int, cell: str):
    """Paper case 2's square: ``(V, a, L, bcs)``. Collective."""
    mesh = dolfinx.mesh.create_unit_square(comm, n, n, dolfinx.mesh.CellType[cell])
    V, a, v = _elasticity(mesh, degree)
    fdim = mesh.topology.dim - 1
    sides = [
        (1, lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0)),
        (2, lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0)),
    ]
    facets = [dolfinx.mesh.locate_entities_boundary(mesh, fdim, where) for _, where in sides]
    values = np.concatenate(
        [np.full(f.size, tag, dtype=np.int32) for (tag, _), f in zip(sides, facets, strict=True)]
    )
    order = np.argsort(np.concatenate(facets))
    tags = dolfinx.mesh.meshtags(mesh, fdim, np.concatenate(facets)[order], values[order])
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    normal = ufl.FacetNormal(mesh)
    L = -1.0 * ufl.dot(normal, v) * ds(1) - 2.0 * ufl.dot(normal, v) * ds(2)
    return V, a, L, _held(V, (((0.5, 0.0), 0), ((0.5, 1.0), 0), ((0.0, 0.5), 1)))


def cube(comm, n: int, degree: int, cell: str):
    """The sphere case's cube without its sphere: ``(V, a, L, bcs)``. Collective."""
    mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, dolfinx.mesh.CellType[cell])
    return triaxial(mesh, degree)


def triaxial(mesh, degree: int):
    """The sphere case's loads on a mesh of the unit cube (one material, SOLID_E and
    SOLID_NU), whose nodes include the points of :data:`HELD_3D`: ``(V, a, L, bcs)``.
    Collective."""
    V, a, v = _elasticity(mesh, degree, SOLID_E, SOLID_NU)
    fdim = mesh.topology.dim - 1
    facets = [
        dolfinx.mesh.locate_entities_boundary(
            mesh, fdim, lambda x, k=k: np.isclose(x[k], 0.0) | np.isclose(x[k], 1.0)
        )
        for k in range(3)
    ]
    values = np.concatenate([np.full(f.size, k, dtype=np.int32) for k, f in enumerate(facets)])
    order = np.argsort(np.concatenate(facets))
    tags = dolfinx.mesh.meshtags(mesh, fdim, np.concatenate(facets)[order], values[order])
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    normal = ufl.FacetNormal(mesh)
    L = sum(s * ufl.dot(normal, v) * ds(k) for k, s in enumerate(TRIAXIAL))
    return V, a, L, _held(V, HELD_3D)


def _held(V, held) -> list:
    """Point constraints ``u_i = 0`` at mesh nodes, ``held`` pairs of point and ``i``."""
    bcs = []
    for point, component in held:
        sub = V.sub(component)
        Vc, _ = sub.collapse()
        dofs = dolfinx.fem.locate_dofs_geometrical(
            (sub, Vc), lambda x, p=point: np.all(np.isclose(x[: len(p)].T, p), axis=1)
        )
        bcs.append(dolfinx.fem.dirichletbc(dolfinx.fem.Function(Vc), dofs, sub))
    return bcs


def annulus(comm, n: int, degree: int):
    """Paper case 3's annulus (radii 3 and 20 m, ``n`` x ``4 n`` curved Q2 cells, the
    mesh of ``xfem_contact.io.meshes.annulus``): the inner circle clamped, 1 MPa on
    the outer one. ``(V, a, L, bcs)``. Collective."""
    from xfem_contact.io.meshes import annulus as annulus_mesh  # the mesh only

    mesh = annulus_mesh(comm, 3.0, 20.0, n, 4 * n, 2)
    V, a, v = _elasticity(mesh, degree)
    fdim = mesh.topology.dim - 1
    inner = dolfinx.mesh.locate_entities_boundary(
        mesh, fdim, lambda x: np.hypot(x[0], x[1]) < 3.0 + 1e-6
    )
    zero = dolfinx.fem.Function(V)
    bcs = [dolfinx.fem.dirichletbc(zero, dolfinx.fem.locate_dofs_topological(V, fdim, inner))]
    L = -1e6 * ufl.dot(ufl.FacetNormal(mesh), v) * ufl.ds
    return V, a, L, bcs


def solve(setup, out: pathlib.Path | None, mumps: dict[str, int], factor: str = "lu") -> dict:
    """Solve the problem ``setup()`` gives and write; returns the dofs, the wall time of
    each phase (s) and the Krylov iterations, and the displacement; ``out`` None:
    nothing written. Collective."""
    comm = MPI.COMM_WORLD
    times = {}
    start = time.perf_counter()
    V, a, L, bcs = setup()
    times["mesh_and_spaces"] = time.perf_counter() - start
    t = time.perf_counter()
    a_form, L_form = dolfinx.fem.form(a), dolfinx.fem.form(L)
    times["forms"] = time.perf_counter() - t
    t = time.perf_counter()
    A = dolfinx.fem.petsc.assemble_matrix(a_form, bcs=bcs)
    A.assemble()
    b = dolfinx.fem.petsc.assemble_vector(L_form)
    dolfinx.fem.petsc.apply_lifting(b, [a_form], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)
    times["assembly"] = time.perf_counter() - t
    t = time.perf_counter()
    if factor == "cholesky":
        A.setOption(PETSc.Mat.Option.SPD, True)
    if factor == "gamg":  # CG + algebraic multigrid with the rigid modes
        A.setNearNullSpace(rigid_modes(V))
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(A)
    ksp.setOptionsPrefix("plain_")
    opts = PETSc.Options()
    options = OPTIONS | {"pc_type": factor}
    if factor == "gamg":
        options = {"ksp_type": "cg", "ksp_rtol": 1e-10, "pc_type": "gamg"}
    options |= {f"mat_mumps_{key}": value for key, value in mumps.items()}
    for key, value in options.items():
        opts[f"plain_{key}"] = value
    ksp.setFromOptions()
    uh = dolfinx.fem.Function(V, name="u")
    ksp.solve(b, uh.x.petsc_vec)
    iterations = ksp.getIterationNumber()
    uh.x.scatter_forward()
    times["solve"] = time.perf_counter() - t
    t = time.perf_counter()
    if out is not None:
        with dolfinx.io.VTXWriter(comm, out / "displacement.bp", [uh]) as writer:
            writer.write(0.0)
    times["output"] = time.perf_counter() - t
    for obj in (ksp, A, b):
        obj.destroy()
    dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    return {"dofs": dofs, "timings": times, "krylov": iterations}, uh


def cpu_seconds() -> float:
    """This process's CPU time so far (s: user + system, all its threads). Not
    collective."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=160)
    parser.add_argument("--degree", type=int, default=2, choices=[1, 2])
    cells = ["quadrilateral", "triangle", "tetrahedron", "hexahedron"]
    parser.add_argument("--cell", default=None, choices=cells, help="quadrilateral (2D), ...")
    parser.add_argument("--out", default="results/plain_elasticity", help="'': no output")
    parser.add_argument(
        "--mumps",
        nargs="*",
        default=[],
        metavar="icntl_K=V",
        help="MUMPS controls, e.g. icntl_7=4 (default: MUMPS's own choices)",
    )
    parser.add_argument("--factor", default="lu", choices=["lu", "cholesky", "gamg"])
    parser.add_argument(
        "--mesh",
        default="square",
        choices=["square", "annulus", "cube"],
        help="case 2, case 3 or the 3D sphere case",
    )
    args = parser.parse_args()
    mumps = dict(item.split("=", 1) for item in args.mumps)
    comm = MPI.COMM_WORLD
    planar, solid = ("quadrilateral", "triangle"), ("tetrahedron", "hexahedron")
    cell = args.cell or ("tetrahedron" if args.mesh == "cube" else "quadrilateral")
    if (cell in solid) != (args.mesh == "cube"):
        valid = solid if args.mesh == "cube" else planar
        raise ValueError(f"--cell {cell} on --mesh {args.mesh}; valid: {valid}")
    if args.mesh == "square":
        setup = functools.partial(square, comm, args.n, args.degree, cell)
    elif args.mesh == "cube":
        setup = functools.partial(cube, comm, args.n, args.degree, cell)
    else:
        setup = functools.partial(annulus, comm, args.n, args.degree)
    out = pathlib.Path(args.out) if args.out else None
    result, _ = solve(setup, out, mumps, args.factor)
    result["rank_cpu_s"] = comm.gather(cpu_seconds())
    if MPI.COMM_WORLD.rank == 0:
        print(json.dumps(result))


if __name__ == "__main__":
    main()
