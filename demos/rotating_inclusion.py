"""Paper case 3 with rotation: an inner ring turned by alpha in large sliding.

Annulus 3 m <= r <= 20 m, E = 100 MPa, nu = 0, pressure 1 MPa on r = 20, the X-FEM
interface r = 8 m (a level set, not a mesh line) in frictionless contact, the inner
boundary r = 3 turned rigidly by alpha over the load steps (the pressure ramps with
it). Saint Venant-Kirchhoff bulk (large rotations, small strains); every slave
point of the inner lip is paired with its closest point on the deformed outer lip
at every Newton iterate (the paper's hybrid element). The exact contact pressure is
uniform for any alpha: -1.1155 MPa in small strain, -1.1131 MPa for this bulk model
(a radial ODE, ``xfem_contact.cases.rotation.svk_annulus_pressure``).

Writes in ``--out``: VTX files of each side's displacement (the deformed configuration:
warp by ``u`` at scale 1 in ParaView) and of the multiplier, ``result.vtu`` (the
lips), a PNG of lambda_n against the angle (the paper's Fig. 8; both degrees with
``--degree both``) and a JSON summary (``--json``, default OUT/summary.json).

Run: ``python demos/rotating_inclusion.py [--n 20] [--degree 2] [--alpha 1.5708]
[--steps 4]``, also under ``mpiexec -n 2``.
"""

# %% [markdown]
# ## Imports
# The start-up hook installed with xfem-contact loads the PyPI wheel's MPI library
# before DOLFINx, so the import order is free.

# %%
import argparse
import pathlib
import sys
import time

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.paper import ANNULUS_CONTACT_PRESSURE
from xfem_contact.cases.rotation import (
    OUTER_SUPPORTS,
    pressure_errors,
    rotating_annulus_problem,
    svk_annulus_pressure,
)
from xfem_contact.io.output import write_json, write_lips, write_solution
from xfem_contact.io.plots import Series, line_plot
from xfem_contact.io.progress import add_output_arguments, printer, progress
from xfem_contact.mechanics.laws import SLIDING_LAWS
from xfem_contact.mechanics.loads import load_steps
from xfem_contact.mechanics.sliding.coupling import PAIRING_UPDATES
from xfem_contact.solvers.log_lines import lines_to
from xfem_contact.solvers.newton import NewtonFailure

# %% [markdown]
# ## Flags
# Mesh, degree (or both), angle, load steps, law and friction, the outer support, the
# pairing update and the output paths.


# %%
def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--n", type=int, default=20, help="cells across the annulus (default %(default)s)"
    )
    parser.add_argument("--nc", type=int, default=None, help="cells around (default 4 n)")
    parser.add_argument(
        "--degree",
        default="2",
        choices=["1", "2", "both"],
        help="polynomial degree of the displacement, or both one after the other "
        "(default %(default)s)",
    )
    parser.add_argument(
        "--alpha",
        type=float,
        default=np.pi / 2,
        help="rotation of the inner boundary (rad, default pi/2)",
    )
    parser.add_argument(
        "--steps", type=int, default=4, help="number of load steps (default %(default)s)"
    )
    parser.add_argument(
        "--law",
        default="frictionless",
        choices=list(SLIDING_LAWS),
        help="contact law of the interface in large sliding (default %(default)s)",
    )
    parser.add_argument(
        "--friction",
        type=float,
        default=None,
        help="Coulomb friction coefficient, needed with --law coulomb",
    )
    parser.add_argument(
        "--outer",
        default="point",
        choices=list(OUTER_SUPPORTS),
        help="support of the outer boundary: u_y = 0 at one point, or u_t = 0 all "
        "along it (default %(default)s)",
    )
    parser.add_argument(
        "--pairing",
        default="iterate",
        choices=list(PAIRING_UPDATES),
        help="pair the lips at every Newton iterate or once per load step (default %(default)s)",
    )
    add_output_arguments(parser, "results/rotating_inclusion", "VTX, .vtu, PNG, summary.json")
    parser.add_argument("--no-progress", action="store_true", help="show no progress bar")
    return parser.parse_args()


# %% [markdown]
# ## One degree: the load steps
# The problem ({func}`xfem_contact.cases.rotation.rotating_annulus_problem`), then per load
# step one Newton solve (a line per iterate) and the pairing counts; a failing step is
# reported with its history and the last accepted state is kept and written. Then the
# errors against the exact pressure of the same bulk model, the fields and the summary.


# %%
def solve(args, degree: int, say, comm) -> tuple[dict, dict]:
    """Build and solve one degree; returns (summary, samples)."""
    timings, start = {}, time.perf_counter()
    options = {"pairing": args.pairing}
    if args.law == "coulomb":
        options["friction"] = args.friction
    problem = rotating_annulus_problem(
        args.n, degree, args.alpha, args.nc, args.law, outer=args.outer, **options
    )
    timings["build"] = time.perf_counter() - start
    dofs = problem.space.dof_counts()
    say(f"degree {degree}: {problem.cut.num_cut_cells_global} cut cells; dofs {dofs._asdict()}")
    steps, history = load_steps(args.steps), []
    t0 = time.perf_counter()
    bar = progress(steps, f"degree {degree}: load steps", not args.no_progress, comm)
    for k, t in enumerate(bar, start=1):
        problem.loads.set_time(t)
        try:
            with lines_to(say):  # the solver's log: a line per Newton iterate
                report = problem.solve()
        except NewtonFailure as failure:  # the last accepted state is kept in problem.w
            say(f"load step {k} (angle {t * args.alpha:.4f} rad) failed:\n{failure}")
            break
        problem.accept_step()
        counts = problem.pairing_counts()["interface"]
        unpaired = problem.unpaired_points()["interface"]  # collective
        history.append(
            {
                "load_factor": float(t),
                "angle": float(t * args.alpha),
                "newton_iterations": report.iterations,
                "newton_residuals": report.residuals,
                "pairing": counts,
                "unpaired_points": unpaired.tolist(),
            }
        )
        say(
            f"load step {k}/{len(steps)} (angle {t * args.alpha:.4f} rad): "
            f"{report.iterations} Newton iterations; pairing {counts}"
        )
    timings["solve"] = time.perf_counter() - t0
    errors = pressure_errors(problem)
    samples = problem.interface_samples(problem.w)
    complete = len(history) == len(steps)
    say(
        f"degree {degree}: lambda_n rel. L2 error {errors['error']:.3e} (against the "
        f"same bulk model), {errors['lame_error']:.3e} (Lame); oscillation "
        f"{errors['oscillation']:.3e}" + ("" if complete else " (at the last accepted step)")
    )
    out = pathlib.Path(args.out) / f"degree{degree}"
    t0 = time.perf_counter()
    fields = write_solution(out, problem)
    write_lips(out / "result.vtu", problem.cut, fields[0], fields[1])
    timings["output"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - start
    summary = {
        "case": "paper case 3 with rotation: large sliding",
        "n": args.n,
        "n_angular": args.nc or 4 * args.n,
        "degree": degree,
        "alpha": args.alpha,
        "law": args.law,
        "outer": args.outer,
        "pairing_update": args.pairing,
        "ranks": comm.size,
        "completed": complete,
        "contact_pressure_rel_L2_error": errors["error"],
        "contact_pressure_rel_L2_error_lame": errors["lame_error"],
        "oscillation_amplitude": errors["oscillation"],
        "mean_contact_pressure": errors["mean"],
        "reference_pressure": svk_annulus_pressure(),
        "lame_pressure": ANNULUS_CONTACT_PRESSURE,
        "newton_iterations": [h["newton_iterations"] for h in history],
        "load_steps": history,
        "pairing": [h["pairing"] for h in history],
        "dofs": dofs._asdict() | {"total": dofs.total},
        "timings": timings,
        "interface_samples": {
            k: samples[k] for k in ("x", "y", "lambda_n", "lambda_t", "gap") if k in samples
        },
    }
    return summary, samples


# %% [markdown]
# ## Both degrees and the figure
# The paper's Fig. 8: lambda_n against the angle on the reference interface, with the
# exact pressures of the Saint Venant-Kirchhoff and the small-strain models.


# %%
def main() -> int:
    args = arguments()
    comm = MPI.COMM_WORLD
    say = printer(not args.quiet, comm)
    degrees = [1, 2] if args.degree == "both" else [int(args.degree)]
    say(
        f"paper case 3 turned by {args.alpha:.4f} rad in {args.steps} steps: "
        f"{args.n} x {args.nc or 4 * args.n} cells, law {args.law}, outer {args.outer}"
    )
    try:
        results = [solve(args, degree, say, comm) for degree in degrees]
    except ValueError as error:  # bad input: one line
        if comm.rank == 0:
            print(f"error: {error}", file=sys.stderr)
        return 2
    out = pathlib.Path(args.out)
    if comm.rank == 0:
        series = []
        for (summary, samples), style in zip(results, (".", "x"), strict=False):
            theta = np.degrees(np.arctan2(samples["y"], samples["x"]))
            order = np.argsort(theta)
            lam = np.array(samples["lambda_n"])[order] / 1e6
            series.append(Series(theta[order], lam, style, f"degree {summary['degree']}"))
        t = np.array([-180.0, 180.0])
        series.append(Series(t, [svk_annulus_pressure() / 1e6] * 2, "k-", "exact (same model)"))
        series.append(Series(t, [ANNULUS_CONTACT_PRESSURE / 1e6] * 2, "k--", "Lame"))
        png = line_plot(
            out / "contact_pressure.png",
            series,
            "angle on the reference interface (degrees)",
            "contact pressure lambda_n (MPa)",
            f"Case 3 turned by {args.alpha:.3f} rad, {args.n} x {args.nc or 4 * args.n}",
        )
        summary = results[-1][0] if len(results) == 1 else {"degrees": [r[0] for r in results]}
        path = write_json(args.json or out / "summary.json", summary)
        say(f"wrote {path}, {png} and VTX/.vtu files in {out}")
    return 0 if all(r[0]["completed"] for r in results) else 1


# %%
if __name__ == "__main__":
    sys.exit(main())
