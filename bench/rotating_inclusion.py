"""Paper case 3 with rotation (large sliding): accuracy, oscillation and cost.

For each element degree, mesh and rotation angle: the relative L2 error of the
contact pressure against the exact pressure of the same (Saint Venant-Kirchhoff)
bulk model, and against the small-strain Lame value, the oscillation amplitude
(max - min of lambda_n over the interface / 1.1155 MPa), the Newton iterations of
each load step with the last two residuals (the quadratic end), and the wall
time. Meshes: n radial x 4n around (n = 10, 20, 40, 80), and the paper's n x n
reading (20, 40, 80). Angles 0 (1 step), pi/4 (2 steps), pi/2 (4 steps), 0.3 rad and
1 rad (4 steps each; not multiples of the cell angle: pi/4 and pi/2 map the mesh
onto itself). The non-aligned angles are run with segment-to-segment integration
(the default: slave pieces broken where their feet cross master-piece ends) and
without (the interface rule's Gauss points, which then integrate across master
kinks): the ``segments`` column. Time per Newton iteration: the solves' wall time
(and CPU time of the process, less sensitive to other loads on the machine) over
their iterations, the first of several load steps left out (it sets up and
compiles); its baseline, measured in the same run, is a Newton iteration of the
small-sliding solve of case 3 at alpha = 0 on the same mesh (a second solve, from
zero; :func:`~xfem_contact.cases.paper.annulus_problem`).

Run: ``python bench/rotating_inclusion.py [--tiny] [--meshes 10x40,20x80]
[--degrees 1,2] [--angles 0.3,1] [--json PATH]``; writes
``bench/results/rotating_inclusion.{json,md}``.
"""

import argparse
import json
import pathlib
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.paper import annulus_problem
from xfem_contact.cases.rotation import pressure_errors, rotating_annulus_problem
from xfem_contact.io.progress import progress
from xfem_contact.solvers.newton import NewtonFailure

ANGLES = {
    "0": (0.0, 1),
    "pi/4": (np.pi / 4, 2),
    "pi/2": (np.pi / 2, 4),
    "0.3": (0.3, 4),
    "1": (1.0, 4),
}
#: Angles that map the mesh onto itself (segmentation changes nothing there)
ALIGNED = ("0", "pi/4", "pi/2")
RESULTS = pathlib.Path(__file__).parent / "results"


def small_sliding_time(n_radial, n_angular, degree) -> tuple[float, float, float]:
    """Wall time (s) of the small-sliding case-3 solve at alpha = 0 (the baseline),
    and the wall and CPU time (s) of one of its Newton iterations (of a second solve
    from zero: set-up and compilation excluded)."""
    start = time.perf_counter()
    problem = annulus_problem(n_radial, n_angular, degree, 2 if degree == 2 else 1)
    problem.solve()
    elapsed = time.perf_counter() - start
    problem.w.x.array[:] = 0.0
    cpu = time.process_time()
    report = problem.solve()
    cpu = (time.process_time() - cpu) / max(report.iterations, 1)
    return elapsed, report.total_time / max(report.iterations, 1), cpu


def run(n_radial, n_angular, degree, angle_name, segments) -> dict:
    alpha, steps = ANGLES[angle_name]
    start = time.perf_counter()
    problem = rotating_annulus_problem(n_radial, degree, alpha, n_angular, segments=segments)
    row = {"n": n_radial, "n_angular": n_angular, "degree": degree, "alpha": angle_name}
    row["segments"] = segments
    row["dofs"] = problem.space.dof_counts().total
    iterations, ends, timed = [], [], np.zeros(3)  # wall, CPU, iterations
    try:
        for k in range(1, steps + 1):
            problem.loads.set_time(k / steps)
            cpu = time.process_time()
            report = problem.solve()
            cpu = time.process_time() - cpu
            problem.accept_step()
            iterations.append(report.iterations)
            ends.append(report.residuals[-3:])
            if k > 1 or steps == 1:  # the first of several steps sets up and compiles
                timed += (report.total_time, cpu, report.iterations)
    except NewtonFailure as failure:
        row["failure"] = str(failure).splitlines()[0]
    row["time_s"] = time.perf_counter() - start
    row["newton_per_step"] = iterations
    row["last_residuals"] = ends
    row["iteration_s"], row["iteration_cpu_s"] = timed[:2] / max(timed[2], 1)
    if "failure" not in row:
        row |= pressure_errors(problem)
    return row


def table(rows) -> str:
    lines = [
        "| mesh | degree | alpha | segments | dofs | error (same model) | error (Lame) "
        "| oscillation | Newton per step | s per iteration (wall, CPU) | x small sliding (wall, "
        "CPU) | time (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        head = (
            f"| {r['n']}x{r['n_angular']} | {r['degree']} | {r['alpha']} | "
            f"{'yes' if r['segments'] else 'no'} | {r['dofs']} |"
        )
        if "failure" in r:
            lines.append(f"{head} failed: {r['failure']} | | | {r['newton_per_step']} | | | |")
            continue
        lines.append(
            f"{head} {r['error']:.2e} | {r['lame_error']:.2e} | {r['oscillation']:.1e} | "
            f"{r['newton_per_step']} | {r['iteration_s']:.3f}, {r['iteration_cpu_s']:.3f} | "
            f"{r['iteration_ratio']:.2f}, {r['iteration_cpu_ratio']:.2f} | {r['time_s']:.2f} |"
        )
    return "\n".join(lines)


def rates(rows) -> list[str]:
    """Observed rates of the error between successive meshes of one family."""
    out = []
    for family in ("4n", "n"):
        for degree in (1, 2):
            for angle in ANGLES:
                for segments in (True, False):
                    chosen = [
                        r
                        for r in rows
                        if r["degree"] == degree
                        and r["alpha"] == angle
                        and r["segments"] == segments
                        and "error" in r
                        and (r["n_angular"] == 4 * r["n"]) == (family == "4n")
                    ]
                    for a, b in zip(chosen, chosen[1:], strict=False):
                        rate = np.log(a["error"] / b["error"]) / np.log(b["n"] / a["n"])
                        out.append(
                            f"degree {degree}, alpha {angle}, segments "
                            f"{'yes' if segments else 'no'}, {family}: n {a['n']} -> "
                            f"{b['n']}: rate {rate:.2f}"
                        )
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tiny", action="store_true", help="n = 10, 20 only (a quick check)")
    parser.add_argument("--meshes", help="e.g. 10x40,20x80 (n radial x n around)")
    parser.add_argument("--degrees", default="1,2")
    parser.add_argument("--angles", default=",".join(ANGLES), help=f"of {list(ANGLES)}")
    parser.add_argument("--json", default=str(RESULTS / "rotating_inclusion.json"))
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    if args.meshes:
        meshes = [tuple(int(v) for v in m.split("x")) for m in args.meshes.split(",")]
    elif args.tiny:
        meshes = [(10, 40), (20, 80)]
    else:
        meshes = [(10, 40), (20, 80), (40, 160), (20, 20), (40, 40), (80, 80)]
    degrees = [int(d) for d in args.degrees.split(",")]
    angles = args.angles.split(",")
    cases = [
        (m, d, a, s)
        for m in meshes
        for d in degrees
        for a in angles
        for s in ((True,) if a in ALIGNED else (True, False))
    ]
    baselines, rows = {}, []
    for (n, nc), degree, angle, segments in progress(
        cases, "case 3 rotated", not args.no_progress, comm
    ):
        if (n, nc, degree) not in baselines:
            baselines[(n, nc, degree)] = small_sliding_time(n, nc, degree)
        row = run(n, nc, degree, angle, segments)
        base = baselines[(n, nc, degree)]
        row["small_sliding_time_s"] = base[0]
        row["small_sliding_iteration_s"], row["small_sliding_iteration_cpu_s"] = base[1:]
        row["ratio"] = row["time_s"] / row["small_sliding_time_s"]
        row["iteration_ratio"] = row["iteration_s"] / row["small_sliding_iteration_s"]
        row["iteration_cpu_ratio"] = row["iteration_cpu_s"] / row["small_sliding_iteration_cpu_s"]
        rows.append(row)
        if comm.rank == 0 and "error" in row:
            print(
                f"{n}x{nc} P{degree} alpha {angle} segments {segments}: error "
                f"{row['error']:.3e}, oscillation {row['oscillation']:.2e}, Newton "
                f"{row['newton_per_step']}, {row['iteration_s']:.3f} s per iteration "
                f"({row['iteration_ratio']:.2f} x small sliding; CPU "
                f"{row['iteration_cpu_s']:.3f} s, {row['iteration_cpu_ratio']:.2f} x), "
                f"{row['time_s']:.2f} s",
                flush=True,
            )
    if comm.rank == 0:
        text = table(rows) + "\n\n" + "\n".join(f"- {line}" for line in rates(rows)) + "\n"
        print(text)
        path = pathlib.Path(args.json)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({"ranks": comm.size, "rows": rows}, indent=1))
        path.with_suffix(".md").write_text(text)


if __name__ == "__main__":
    main()
