"""Paper case 2: circular inclusion in sticking (or Coulomb / frictionless) contact.

Unit square, E = 100 MPa, nu = 0, an X-FEM circular interface of radius 0.2 m
(not meshed), compression -1 Pa on the lateral faces and -2 Pa on the top and
bottom faces. The exact stress is uniform, diag(-1, -2) Pa, so the exact contact
pressure is n.sigma.n = -3/2 + cos(2 theta)/2 and the tangential traction
-sin(2 theta)/2. Quadratic displacement, linear multipliers (the paper's P2-P1
element) by default; generalized Newton (PETSc SNES) on the augmented Lagrangian.

Writes in ``--out``: VTX files of the displacement of each side and of the
multipliers, ``result.vtu`` (the lips: uncut cells and sub-triangles, each side's
displacement), ``subcells.vtu``/``interface.vtu`` (the cut region), a PNG of the
contact pressure against the angle with the exact curve, and a JSON summary
(``--json``, default OUT/summary.json); ``xfem-contact show OUT`` renders the folder.

Run: ``python demos/inclusion_contact.py [--n 40] [--degree 2] [--law sticking]``,
also under ``mpiexec -n 2``.
"""

# %% [markdown]
# ## Imports
# The start-up hook installed with xfem-contact loads the PyPI wheel's MPI library
# before DOLFINx, so the import order is free.

# %%
import argparse
import pathlib
import time

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.paper import INCLUSION_CENTRE, inclusion_errors, inclusion_problem
from xfem_contact.io.output import write_cut_geometry, write_json, write_lips, write_solution
from xfem_contact.io.plots import Series, line_plot
from xfem_contact.io.progress import add_law_arguments, add_output_arguments, printer
from xfem_contact.solvers.log_lines import lines_to
from xfem_contact.solvers.options import LINEAR_PRESETS, preset

# %% [markdown]
# ## The run
# Flags, the problem of paper case 2 ({func}`xfem_contact.cases.paper.inclusion_problem`),
# one generalized-Newton solve with a line per iterate, the interface errors against the
# exact uniform-stress pressure, then the output: VTX fields, the lips and the cut as
# `.vtu`, the pressure plot and the JSON summary with the time of each phase.


# %%
def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--n", type=int, default=40, help="cells per side, even (default %(default)s)"
    )
    add_law_arguments(parser, friction=1.0)
    parser.add_argument(
        "--cell",
        default="quadrilateral",
        choices=["quadrilateral", "triangle"],
        help="cell shape of the mesh (default %(default)s)",
    )
    parser.add_argument(
        "--lbb",
        default="stabilized",
        choices=["stabilized", "restriction"],
        help="treatment of the multipliers' inf-sup condition: the Barbosa-Hughes "
        "stabilisation or the vital-vertex restriction (default %(default)s)",
    )
    parser.add_argument(
        "--solver",
        default="direct",
        choices=sorted(LINEAR_PRESETS),
        help="linear solver of the Newton steps: MUMPS (LDL^T of a symmetric Jacobian, "
        "else LU), or GMRES + band multigrid (default %(default)s)",
    )
    add_output_arguments(parser, "results/inclusion_contact", "VTX, .vtu, PNG, summary.json")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = printer(not args.quiet, comm)
    out = pathlib.Path(args.out)
    timings = {}
    start = time.perf_counter()

    say(f"paper case 2: {args.n}x{args.n} {args.cell}, degree {args.degree}, law {args.law}")
    t0 = time.perf_counter()
    options = {"lbb": args.lbb, "petsc_options": preset(args.solver)}
    if args.law == "coulomb":
        options["friction"] = args.friction
    problem = inclusion_problem(args.n, args.degree, args.law, args.cell, **options)
    cut = problem.cut
    timings |= cut.timings  # "cut" (level set and cut) and "quadrature" (rules)
    timings["spaces"] = time.perf_counter() - t0 - sum(cut.timings.values())
    dofs = problem.space.dof_counts()  # collective
    say(f"  {cut.num_cut_cells_global} cut cells; dofs {dofs._asdict()}")

    with lines_to(say):  # the solver's log: a line per Newton iterate
        report = problem.solve()
    setup = problem.solver_timings
    timings["forms"] = setup["forms"]
    timings["sparsity"] = setup["sparsity"]
    timings["assembly"] = setup["jacobian"] + report.assembly_time
    timings["scaling"] = setup["scaling"]
    timings["linear_solve"] = report.linear_solve_time
    timings["status"] = report.status_time
    t0 = time.perf_counter()
    errors = inclusion_errors(problem, problem.w)
    samples = problem.interface_samples(problem.w)  # collective
    timings["post_processing"] = time.perf_counter() - t0
    say(
        f"  Newton iterations {report.iterations}; contact pressure rel. L2 error "
        f"{errors.pressure:.4e}; tangential traction rel. L2 error {errors.tangential:.4e}"
    )

    t0 = time.perf_counter()
    fields = write_solution(out, problem)
    write_lips(out / "result.vtu", cut, fields[0], fields[1])
    write_cut_geometry(out, cut)
    if comm.rank == 0:
        x, y, lam = (np.array(samples[k]) for k in ("x", "y", "lambda_n"))
        theta = np.arctan2(y - INCLUSION_CENTRE[1], x - INCLUSION_CENTRE[0])
        order = np.argsort(theta)
        plot(out / "contact_pressure.png", theta[order], lam[order], args)
    timings["output"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - start
    if comm.rank == 0:
        summary = {
            "case": "paper case 2: circular inclusion, contact",
            "n": args.n,
            "degree": args.degree,
            "cell": args.cell,
            "law": args.law,
            "lbb": args.lbb,
            "ranks": comm.size,
            "contact_pressure_rel_L2_error": errors.pressure,
            "tangential_traction_rel_L2_error": errors.tangential,
            "newton_iterations": report.iterations,
            "solver": args.solver,
            "factorisation": problem.solver_options()["pc_type"],
            "krylov_iterations": report.linear_iterations,
            "newton_residuals": report.residuals,
            "contact_status": report.status[-1],
            "dofs": dofs._asdict() | {"total": dofs.total},
            "timings": timings,
            "interface_samples": samples,
        }
        path = write_json(args.json or out / "summary.json", summary)
        say(f"  wrote {path}, {out / 'contact_pressure.png'} and VTX/.vtu files in {out}")


# %% [markdown]
# ## The contact pressure against the angle
# The multiplier at the interface quadrature points and the exact `n . sigma n`.


# %%
def plot(path, theta, pressure, args):
    t = np.linspace(-np.pi, np.pi, 400)
    line_plot(
        path,
        [
            Series(np.degrees(theta), pressure, ".", "X-FEM multiplier λₙ"),
            Series(np.degrees(t), -1.5 + 0.5 * np.cos(2 * t), "k--", "exact n·σn"),
        ],
        "angle (degrees)",
        "contact pressure (Pa)",
        f"Case 2, {args.n}x{args.n}, degree {args.degree}, {args.law}",
    )


# %%
if __name__ == "__main__":
    main()
