"""A sphere in sticking (or Coulomb / frictionless) contact in a cube under triaxial compression.

Unit cube, E = 100 Pa, nu = 0.3, one material on both sides, an X-FEM spherical interface
of radius 0.2 m at the centre (not meshed; its level set the quadric that a P2 level set
holds exactly), pressures 1, 2 and 3 Pa on the pairs of faces normal to x, y and z and the
six rigid motions held at nodes the exact field leaves in place. The exact stress is
uniform, diag(-1, -2, -3) Pa, so the exact contact traction on the sphere is sigma n: the
pressure n.sigma.n and its tangential part. Quadratic displacement and linear multipliers
on tetrahedra or hexahedra by default; generalized Newton (PETSc SNES) on the augmented
Lagrangian.

Writes in ``--out``: VTX files of the displacement of each side and of the multipliers,
``result.vtu`` (each side's displacement and stresses on the uncut cells and the pieces of
the cut cells), ``subcells.vtu`` and ``interface.vtu`` (the interface surface with the
law's ``lambda_n``, ``lambda_t``, ``gap``, ``slip`` and status), pictures (``result.png``:
the deformed body cut open; ``pressure.png``: the interface coloured by the contact
pressure; ...) and a JSON summary (``--json``, default OUT/summary.json).

Run: ``python demos/sphere_contact.py [--n 8] [--degree 2] [--cell tet|hex]``, also under
``mpiexec -n 2``.
"""

# %% [markdown]
# ## Imports

# %%
import argparse
import pathlib
import time

# isort: split
from mpi4py import MPI

from xfem_contact.cases.solid import sphere_errors, sphere_problem
from xfem_contact.io.interface_data import interface_point_data
from xfem_contact.io.output import write_cut_geometry, write_json, write_lips, write_solution
from xfem_contact.io.pictures import render_folder
from xfem_contact.io.progress import add_law_arguments, add_output_arguments, printer
from xfem_contact.mechanics.stress import StressFields
from xfem_contact.solvers.log_lines import lines_to

CELLS = {"tet": "tetrahedron", "hex": "hexahedron"}

# %% [markdown]
# ## The run
# Flags, the problem ({func}`xfem_contact.cases.solid.sphere_problem`), one
# generalized-Newton solve with a line per iterate, the interface errors against the exact
# traction, then the output: VTX fields, the grids as `.vtu`, the pictures and the JSON
# summary with the time of each phase.


# %%
def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--n", type=int, default=8, help="cells per edge of the cube, even (default %(default)s)"
    )
    add_law_arguments(parser, friction=0.3)
    parser.add_argument(
        "--cell",
        default="tet",
        choices=sorted(CELLS),
        help="cells of the mesh: tetrahedra or hexahedra (default %(default)s)",
    )
    add_output_arguments(parser, "results/sphere_contact", "VTX, .vtu, PNG, summary.json")
    parser.add_argument("--no-png", action="store_true", help="write no pictures")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = printer(not args.quiet, comm)
    out = pathlib.Path(args.out)
    timings = {}
    start = time.perf_counter()

    cell = CELLS[args.cell]
    say(f"sphere in a cube: {args.n}^3 {cell}, degree {args.degree}, law {args.law}")
    t0 = time.perf_counter()
    options = {"friction": args.friction} if args.law == "coulomb" else {}
    problem = sphere_problem(args.n, args.degree, args.law, cell, levelset="quadric", **options)
    cut = problem.cut
    timings |= cut.timings  # "cut" (level set and cut) and "quadrature" (rules)
    timings["spaces"] = time.perf_counter() - t0 - sum(cut.timings.values())
    dofs = problem.space.dof_counts()  # collective
    say(f"  {cut.num_cut_cells_global} cut cells; dofs {dofs._asdict()}")

    t0 = time.perf_counter()
    with lines_to(say):  # the solver's log: a line per Newton iterate
        report = problem.solve()
    timings["solve"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    e_n, e_t = sphere_errors(problem)
    samples = problem.interface_samples(problem.w)  # collective
    timings["errors"] = time.perf_counter() - t0
    # the exact traction is sticking contact's: where the interface slips it differs
    against = "error" if args.law == "sticking" else "difference from sticking contact's traction"
    tangential = "" if e_t != e_t else f"; tangential traction rel. L2 {against} {e_t:.4e}"
    say(
        f"  Newton iterations {report.iterations}; contact pressure rel. L2 {against} "
        f"{e_n:.4e}{tangential}"
    )

    t0 = time.perf_counter()
    fields = write_solution(out, problem)
    material = problem.bulk.materials[1]
    stress = StressFields([("u_minus", material, fields[0]), ("u_plus", material, fields[1])])
    stress.update()
    named = {
        "stress": dict(zip((-1, 1), stress.stress, strict=True)),
        "von_mises": dict(zip((-1, 1), stress.von_mises, strict=True)),
    }
    write_lips(out / "result.vtu", cut, fields[0], fields[1], named)
    write_cut_geometry(out, cut, interface_point_data(problem), fields[0])
    timings["output"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - start
    comm.barrier()  # every rank's pieces are on disk before rank 0 draws them
    if comm.rank == 0:
        summary = {
            "scene": "sphere_contact",  # names the pictures
            "case": "sphere in a cube under triaxial compression, contact",
            "n": args.n,
            "degree": args.degree,
            "cell": cell,
            "law": args.law,
            "ranks": comm.size,
            "contact_pressure_rel_L2_error": e_n,
            "tangential_traction_rel_L2_error": e_t,
            "newton_iterations": report.iterations,
            "newton_residuals": report.residuals,
            "contact_status": report.status[-1],
            "dofs": dofs._asdict() | {"total": dofs.total},
            "interfaces": {name: law.describe() for name, law in problem.laws.items()},
            "timings": timings,
            "interface_samples": samples,
        }
        path = write_json(args.json or out / "summary.json", summary)
        say(f"  wrote {path} and VTX/.vtu files in {out}")
        if not args.no_png:
            for picture in render_folder(out):
                say(f"  wrote {picture}")


# %%
if __name__ == "__main__":
    main()
