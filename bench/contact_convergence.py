"""Paper case 2 (circular inclusion in contact): accuracy against cost.

For each element degree, contact law, LBB treatment and mesh size: the relative
L2 errors of the contact pressure and of the tangential traction on the
interface (the paper's norm), their observed rates, Newton iterations, dofs, the
wall time of setup (cut + quadrature + spaces) and of the solve, and the
multiplier oscillation: the total variation of lambda_n along the interface
divided by that of the exact pressure (1 = no oscillation). A treatment whose
Newton fails is reported with its failure, not hidden.

Run: ``python bench/contact_convergence.py [--sizes 10 20 40 80 160] [--json out.json]``.
"""

import argparse
import json
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.paper import inclusion_errors, inclusion_problem, pressure_total_variation
from xfem_contact.solvers.newton import NewtonFailure

EXACT_TOTAL_VARIATION = 4.0  # of -3/2 + cos(2 theta)/2 over the circle


def oscillation(problem) -> float:
    """Total variation of lambda_n along the interface / that of the exact pressure."""
    return pressure_total_variation(problem) / EXACT_TOTAL_VARIATION


def run(n, degree, law, lbb, cell):
    t0 = time.perf_counter()
    options = {"lbb": lbb}
    if law == "coulomb":
        options["friction"] = 1.0
    problem = inclusion_problem(n, degree, law, cell, **options)
    setup = time.perf_counter() - t0
    row = {
        "N": n,
        "degree": degree,
        "law": law,
        "lbb": lbb,
        "setup_s": setup,
        "dofs": problem.space.dof_counts().total,
    }
    try:
        report = problem.solve()
    except NewtonFailure as failure:
        return row | {"failed": str(failure).splitlines()[0], "residuals": failure.report.residuals}
    errors = inclusion_errors(problem, problem.w)
    return row | {
        "pressure_error": errors.pressure,
        "tangential_error": errors.tangential,
        "newton_iterations": report.iterations,
        "solve_s": report.total_time,
        "oscillation": oscillation(problem),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 20, 40, 80, 160])
    parser.add_argument("--degrees", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--laws", nargs="+", default=["sticking", "coulomb"])
    parser.add_argument("--lbb", nargs="+", default=["stabilized", "restriction", "none"])
    parser.add_argument("--cells", nargs="+", default=["quadrilateral", "triangle"])
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    root = MPI.COMM_WORLD.rank == 0
    rows = []
    if root:
        print(
            f"{'cell':>4} {'deg':>3} {'law':>9} {'lbb':>11} {'N':>4} {'dofs':>7} "
            f"{'e_pressure':>10} {'rate':>5} {'e_tangent':>10} {'rate':>5} "
            f"{'newton':>6} {'osc':>6} {'setup s':>8} {'solve s':>8}"
        )
    for cell, degree in ((c, d) for c in args.cells for d in args.degrees):
        for law in args.laws:
            for lbb in args.lbb:
                previous = None
                for n in args.sizes:
                    r = run(n, degree, law, lbb, cell)
                    rows.append(r)
                    if not root:
                        continue
                    if "failed" in r:
                        print(
                            f"{cell[:4]:>4} {degree:3d} {law:>9} {lbb:>11} {n:4d} {r['dofs']:7d}  "
                            f"{r['failed']} (residuals {np.round(r['residuals'], 3)})"
                        )
                        previous = None
                        continue
                    rates = ["", ""]
                    if previous is not None:
                        for k, key in enumerate(("pressure_error", "tangential_error")):
                            rates[k] = (
                                f"{np.log(previous[key] / r[key]) / np.log(n / previous['N']):5.2f}"
                            )
                    print(
                        f"{cell[:4]:>4} {degree:3d} {law:>9} {lbb:>11} {n:4d} {r['dofs']:7d} "
                        f"{r['pressure_error']:10.3e} {rates[0]:>5} {r['tangential_error']:10.3e} "
                        f"{rates[1]:>5} {r['newton_iterations']:6d} {r['oscillation']:6.2f} "
                        f"{r['setup_s']:8.2f} {r['solve_s']:8.2f}",
                        flush=True,
                    )
                    previous = r
    if args.json and root:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=2)


if __name__ == "__main__":
    main()
