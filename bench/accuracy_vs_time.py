"""What accuracy costs in time: every case, element and option, against the
body-fitted route a user would take without X-FEM, measured in the same run.

Cases: the geometry (disc area and circle length), paper case 1, case 2
(quadrilaterals and triangles), case 3 at alpha = 0 and turned by pi/2 (large
sliding). Swept: displacement degree 1 and 2, five or more mesh sizes, the level
set as a callable or a P2 Function, the quadrature degree, the LBB treatment
(stabilised, restriction), the linear solver (direct LU, iterative band multigrid).
Body-fitted baseline (:mod:`xfem_contact.cases.body_fitted`): gmsh meshes following
the interface, curved P2 cells for degree 2, standard DOLFINx elasticity, meshing
time included. Moving interface: the inclusion resized over 10 positions, X-FEM
re-cutting one mesh (``cut.update``) against the body-fitted route remeshing.

Each (case, method, option) runs in its own process over increasing sizes, so the
peak resident memory after a size is that size's (``ru_maxrss``); runs shorter than
a second are repeated (up to 3 times) and the fastest kept. Every row: error, dofs,
Newton iterations, wall time per phase and in total.

Writes ``bench/results/accuracy_vs_time.json``, one Pareto PNG per case (error
against total time, log-log, the Pareto front circled) and the markdown table
``bench/results/accuracy_vs_time.md`` (the documentation includes it).

Run: ``python bench/accuracy_vs_time.py [--quick]``.
"""

import argparse
import json
import math
import pathlib
import resource
import subprocess
import sys
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np

from xfem_contact.io.progress import note, progress

ROOT = pathlib.Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"

#: Mesh sizes of each family of sweeps: (full run, --quick)
SIZES = {
    "geometry": ([8, 16, 32, 64, 128], [8, 16, 32]),
    "case 1": ([5, 9, 17, 33, 65], [5, 9, 17]),
    "case 2": ([10, 20, 40, 80, 160], [10, 20, 40]),
    "iterative": ([10, 20, 40, 60, 80], [10, 20]),
    "case 3": ([5, 10, 20, 40, 80], [5, 10, 20]),
    "rotated": ([5, 8, 10, 20, 40], [5, 10]),
}
X, FIT = "X-FEM", "body-fitted"
#: (case, method, option label, worker arguments, size family), one row a sweep
# fmt: off
SWEEPS = [
    ("geometry", X, "P2 level set, callable", ["geometry", "2", "callable", "6"], "geometry"),
    ("geometry", X, "P2 level set, Function", ["geometry", "2", "function", "6"], "geometry"),
    ("geometry", X, "P1 level set, callable", ["geometry", "1", "callable", "6"], "geometry"),
    ("geometry", X, "P2 level set, quadrature 4", ["geometry", "2", "callable", "4"], "geometry"),
    ("geometry", X, "P2 level set, quadrature 8", ["geometry", "2", "callable", "8"], "geometry"),
    ("case 1", X, "P1", ["case1", "1"], "case 1"),
    ("case 1", X, "P2", ["case1", "2"], "case 1"),
    ("case 2", X, "P1 quads", ["case2", "1", "quadrilateral", "stabilized", "direct"], "case 2"),
    ("case 2", X, "P2 quads", ["case2", "2", "quadrilateral", "stabilized", "direct"], "case 2"),
    ("case 2", X, "P2 triangles", ["case2", "2", "triangle", "stabilized", "direct"], "case 2"),
    ("case 2", X, "P2 quads, LBB restriction",
     ["case2", "2", "quadrilateral", "restriction", "direct"], "case 2"),
    ("case 2", X, "P2 quads, iterative",
     ["case2", "2", "quadrilateral", "stabilized", "iterative"], "iterative"),
    ("case 2", FIT, "P1 triangles", ["fitted2", "1"], "case 2"),
    ("case 2", FIT, "P2 triangles, curved", ["fitted2", "2"], "case 2"),
    ("case 2", FIT, "P2, duplicated lines + Nitsche", ["nitsche2", "2"], "case 2"),
    ("case 3, alpha = 0", X, "P1 (straight cells)", ["case3", "1"], "case 3"),
    ("case 3, alpha = 0", X, "P2 (curved cells)", ["case3", "2"], "case 3"),
    ("case 3, alpha = 0", FIT, "P1 triangles", ["fitted3", "1"], "case 3"),
    ("case 3, alpha = 0", FIT, "P2 triangles, curved", ["fitted3", "2"], "case 3"),
    ("case 3, alpha = 0", FIT, "P2, duplicated lines + Nitsche", ["nitsche3", "2"], "case 3"),
    ("case 3, alpha = pi/2", X, "P1, large sliding", ["case3rot", "1"], "rotated"),
    ("case 3, alpha = pi/2", X, "P2, large sliding", ["case3rot", "2"], "rotated"),
]
# fmt: on


# -- the workers (one process per sweep) -----------------------------------------------
def geometry(N, degree, kind, quadrature):
    import dolfinx
    from mpi4py import MPI

    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.fem.forms import form

    mesh = dolfinx.mesh.create_unit_square(
        MPI.COMM_WORLD, N, N, dolfinx.mesh.CellType.quadrilateral
    )
    r = 0.3

    def phi(x):
        return np.hypot(x[0] - 0.5, x[1] - 0.5) - r

    levelset = phi
    if kind == "function":
        levelset = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2)))
        levelset.interpolate(phi)
    start = time.perf_counter()
    cut = CutMesh(mesh, levelset, degree=degree, quadrature_degree=quadrature)
    area = dolfinx.fem.assemble_scalar(form(1.0 * cut.dx(-1)))
    length = dolfinx.fem.assemble_scalar(form(1.0 * cut.dGamma))
    total = time.perf_counter() - start
    errors = {"area": abs(area / (np.pi * r * r) - 1), "length": abs(length / (2 * np.pi * r) - 1)}
    timings = dict(cut.timings) | {"forms_and_assembly": total - sum(cut.timings.values())}
    return {
        "error": max(errors.values()),
        "errors": errors,
        "dofs": 0,
        "newton": 0,
        "timings": timings,
    }


def case1(N, degree):
    import ufl

    from xfem_contact.cases.paper import (
        integrate,
        straight_interface_exact,
        straight_interface_problem,
    )

    start = time.perf_counter()
    problem = straight_interface_problem(N + 1, N, degree)
    build = time.perf_counter() - start
    problem.solve()
    solve = time.perf_counter() - start - build
    u = ufl.split(problem.w)[1]
    exact = ufl.as_vector(straight_interface_exact(ufl.SpatialCoordinate(problem.mesh)))
    dx = problem.cut.dx(1)
    error = math.sqrt(
        integrate(ufl.inner(u - exact, u - exact) * dx) / integrate(ufl.inner(exact, exact) * dx)
    )
    return {
        "error": error,
        "dofs": problem.space.dof_counts().total,
        "newton": 0,
        "timings": {"build": build, "solve": solve},
    }


def _contact_row(problem, report, build, start, error):
    timings = {"build": build} | {k: v for k, v in problem.solver_timings.items()}
    timings["newton"] = time.perf_counter() - start - build - sum(problem.solver_timings.values())
    return {
        "error": error,
        "dofs": problem.space.dof_counts().total,
        "newton": report.iterations,
        "timings": timings,
    }


def case2(N, degree, cell, lbb, solver):
    from xfem_contact.cases.paper import inclusion_errors, inclusion_problem
    from xfem_contact.solvers.options import preset

    start = time.perf_counter()
    problem = inclusion_problem(N, degree, "sticking", cell, lbb=lbb, petsc_options=preset(solver))
    build = time.perf_counter() - start
    report = problem.solve()
    return _contact_row(
        problem, report, build, start, inclusion_errors(problem, problem.w).pressure
    )


def case3(n, degree):
    from xfem_contact.cases.paper import annulus_pressure_error, annulus_problem

    start = time.perf_counter()
    problem = annulus_problem(n, 4 * n, degree, 2 if degree == 2 else 1)
    build = time.perf_counter() - start
    report = problem.solve()
    return _contact_row(problem, report, build, start, annulus_pressure_error(problem))


def case3rot(n, degree):
    from xfem_contact.cases.rotation import pressure_errors, rotating_annulus_problem

    start = time.perf_counter()
    problem = rotating_annulus_problem(n, degree, np.pi / 2)
    build = time.perf_counter() - start
    iterations = 0
    for k in range(1, 5):
        problem.loads.set_time(k / 4)
        iterations += problem.solve().iterations
        problem.accept_step()
    total = time.perf_counter() - start
    return {
        "error": pressure_errors(problem)["error"],
        "dofs": problem.space.dof_counts().total,
        "newton": iterations,
        "timings": {"build": build, "steps": total - build},
    }


def fitted(which, N, degree):
    from xfem_contact.cases.body_fitted import fitted_annulus, fitted_inclusion
    from xfem_contact.cases.fitted_nitsche import nitsche_annulus, nitsche_inclusion

    build = {
        "fitted2": lambda: fitted_inclusion(1.0 / N, degree),
        "fitted3": lambda: fitted_annulus(17.0 / N, degree),  # the annulus' radial cell size
        "nitsche2": lambda: nitsche_inclusion(1.0 / N, degree),
        "nitsche3": lambda: nitsche_annulus(17.0 / N, degree),
    }
    row = build[which]()
    return row | {"newton": 0}


def worker(args, sizes):
    kind, rest = args[0], args[1:]
    for size in sizes:
        best = None
        spent = 0.0
        for _ in range(3):
            start = time.perf_counter()
            if kind == "geometry":
                row = geometry(size, int(rest[0]), rest[1], int(rest[2]))
            elif kind == "case1":
                row = case1(size, int(rest[0]))
            elif kind == "case2":
                row = case2(size, int(rest[0]), rest[1], rest[2], rest[3])
            elif kind == "case3":
                row = case3(size, int(rest[0]))
            elif kind == "case3rot":
                row = case3rot(size, int(rest[0]))
            else:
                row = fitted(kind, size, int(rest[0]))
            elapsed = time.perf_counter() - start
            spent += elapsed
            if best is None or elapsed < best["time_s"]:
                best = row | {"time_s": elapsed}
            if spent > 1.0:
                break
        best["size"] = size
        best["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print("ROW " + json.dumps(best), flush=True)


def moving(positions: int = 10) -> dict:
    """The inclusion resized over ``positions`` radii, case 2, P2, h = 1/40."""
    import dolfinx
    from mpi4py import MPI

    from xfem_contact.cases.body_fitted import fitted_inclusion
    from xfem_contact.cases.paper import inclusion_errors
    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.mechanics.materials import Material
    from xfem_contact.mechanics.presets import ContactProblem

    radii = np.linspace(0.15, 0.3, positions)
    start = time.perf_counter()
    mesh = dolfinx.mesh.create_unit_square(
        MPI.COMM_WORLD, 40, 40, dolfinx.mesh.CellType.quadrilateral
    )
    cut, errors = None, []
    for r in radii:

        def phi(x, r=r):
            return np.hypot(x[0] - 0.5, x[1] - 0.5) - r

        if cut is None:
            cut = CutMesh(mesh, phi, degree=2)
        else:
            cut.update(phi)
        problem = ContactProblem(cut, 2, Material(100e6, 0.0), "sticking")
        problem.loads.add_pressure(lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0), 1.0)
        problem.loads.add_pressure(lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), 2.0)
        problem.loads.add_point_displacement([0.5, 0.0], 0.0, 0)
        problem.loads.add_point_displacement([0.5, 1.0], 0.0, 0)
        problem.loads.add_point_displacement([0.0, 0.5], 0.0, 1)
        problem.loading = "paper"
        problem.solve()
        errors.append(inclusion_errors(problem, problem.w).pressure)
    xfem = time.perf_counter() - start
    start = time.perf_counter()
    fitted_errors = [fitted_inclusion(1.0 / 40, 2, radius=r)["error"] for r in radii]
    body = time.perf_counter() - start
    return {
        "positions": positions,
        "xfem_s": xfem,
        "body_fitted_s": body,
        "xfem_errors": errors,
        "body_fitted_errors": fitted_errors,
    }


# -- the report -------------------------------------------------------------------------
def pareto(rows):
    """Indices of the rows no other row beats in both error and time."""
    front = []
    for i, a in enumerate(rows):
        if not any(
            b["error"] <= a["error"]
            and b["time_s"] < a["time_s"]
            or b["error"] < a["error"]
            and b["time_s"] <= a["time_s"]
            for b in rows
        ):
            front.append(i)
    return front


def digit_cost(rows) -> float:
    """Time factor of one more digit along a curve: the least-squares slope of
    log10(time) against -log10(error) over its points (NaN if undefined)."""
    good = [r for r in rows if r["error"] > 1e-11]  # not round-off
    if len(good) < 2:
        return float("nan")
    x = -np.log10([r["error"] for r in good])
    y = np.log10([r["time_s"] for r in good])
    if np.ptp(x) < 0.3:
        return float("nan")
    return float(10 ** np.polyfit(x, y, 1)[0])


def plot(case, curves, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    everything = [r for rows in curves.values() for r in rows]
    for (method, option), rows in curves.items():
        style = "o-" if method == "X-FEM" else "s--"
        ax.loglog(
            [r["time_s"] for r in rows],
            [r["error"] for r in rows],
            style,
            label=f"{method}: {option}",
            markersize=4,
        )
    front = [everything[i] for i in pareto(everything)]
    ax.loglog(
        [r["time_s"] for r in front],
        [r["error"] for r in front],
        "ko",
        markerfacecolor="none",
        markersize=10,
        label="Pareto front",
    )
    ax.set_xlabel("total wall time (s)")
    ax.set_ylabel("relative error")
    ax.set_title(case)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report(rows, moving_result) -> str:
    lines = [
        "| case | method | option | sizes | finest error | its time (s) | dofs | peak RSS (MB) "
        "| one more digit costs | on the Pareto front |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case in dict.fromkeys(r["case"] for r in rows):
        chosen = [r for r in rows if r["case"] == case]
        front = {id(chosen[i]) for i in pareto(chosen)}
        for key in dict.fromkeys((r["method"], r["option"]) for r in chosen):
            curve = [r for r in chosen if (r["method"], r["option"]) == key]
            last = curve[-1]
            cost = digit_cost(curve)
            on = [str(r["size"]) for r in curve if id(r) in front]
            lines.append(
                f"| {case} | {key[0]} | {key[1]} | {curve[0]['size']}..{last['size']} | "
                f"{last['error']:.2e} | {last['time_s']:.3f} | {last['dofs']} | "
                f"{last['peak_rss_mb']:.0f} | "
                + ("-" if math.isnan(cost) else f"x {cost:.1f}")
                + f" | {', '.join(on) or '-'} |"
            )
    lines += ["", *conclusions(rows)]
    if moving_result:
        m = moving_result
        lines += [
            "",
            f"Moving interface (case 2, P2, h = 1/40, {m['positions']} radii 0.15..0.3 m): "
            f"X-FEM re-cutting one mesh {m['xfem_s']:.2f} s (errors "
            f"{min(m['xfem_errors']):.1e}..{max(m['xfem_errors']):.1e}), body-fitted remeshing "
            f"{m['body_fitted_s']:.2f} s (errors {min(m['body_fitted_errors']):.1e}.."
            f"{max(m['body_fitted_errors']):.1e}).",
        ]
    return "\n".join(lines)


def conclusions(rows) -> list[str]:
    """What the figures say, per case: the Pareto front's members, the most accurate
    run, and at the time budgets of the body-fitted runs, which route reaches the
    lower error."""
    out = []
    for case in dict.fromkeys(r["case"] for r in rows):
        chosen = [r for r in rows if r["case"] == case]
        front = [chosen[i] for i in pareto(chosen)]
        members = ", ".join(dict.fromkeys(f"{r['method']} {r['option']}" for r in front))
        best = min(chosen, key=lambda r: r["error"])
        text = (
            f"- {case}: on the front: {members}; most accurate: {best['method']} "
            f"{best['option']} ({best['error']:.1e} in {best['time_s']:.2f} s)."
        )
        fitted = [r for r in chosen if r["method"] == "body-fitted"]
        xfem = [r for r in chosen if r["method"] == "X-FEM"]
        if fitted and xfem:
            winners = []  # (budget, winner) at each body-fitted run's time
            for budget in sorted(r["time_s"] for r in fitted):
                a = min((r["error"] for r in xfem if r["time_s"] <= budget), default=np.inf)
                b = min(r["error"] for r in fitted if r["time_s"] <= budget)
                winner = "X-FEM" if a < b else "body-fitted"
                if not winners or winners[-1][1] != winner:
                    winners.append((budget, winner))
            spans = [f"{w} from {t:.2f} s" for t, w in winners]
            text += " Lower error for the same time budget: " + ", ".join(spans) + "."
        out.append(text)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="three sizes per sweep")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--report-only", action="store_true", help="redo the report from the saved results"
    )
    parser.add_argument("--out", default=str(RESULTS / "accuracy_vs_time.json"))
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    parser.add_argument("--sizes", nargs="+", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--moving", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        return worker(args.worker, args.sizes)
    if args.moving:
        print("ROW " + json.dumps(moving()), flush=True)
        return None
    out = pathlib.Path(args.out)
    if args.report_only:  # the saved results, the report (table, plots) anew
        saved = json.loads(out.read_text())
        return publish(saved["rows"], saved["moving"], out)
    rows = []

    sweeps = progress(SWEEPS, "accuracy vs time: sweeps", not args.no_progress)
    for case, method, option, worker_args, family in sweeps:
        chosen = SIZES[family][1 if args.quick else 0]
        command = [sys.executable, __file__, "--worker", *worker_args, "--sizes", *map(str, chosen)]
        start = time.perf_counter()
        result = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
        found = [
            json.loads(line[4:]) for line in result.stdout.splitlines() if line.startswith("ROW ")
        ]
        if result.returncode != 0:
            print(f"{case} / {method} / {option}: failed:\n{result.stderr[-2000:]}", flush=True)
        for row in found:
            rows.append({"case": case, "method": method, "option": option} | row)
        note(  # above the progress bar
            f"{case} / {method} / {option}: {len(found)} sizes in "
            f"{time.perf_counter() - start:.1f} s; errors "
            + ", ".join(f"{r['error']:.1e}" for r in found)
        )
    result = subprocess.run(
        [sys.executable, __file__, "--moving"], capture_output=True, text=True, cwd=ROOT
    )
    moving_rows = [
        json.loads(line[4:]) for line in result.stdout.splitlines() if line.startswith("ROW ")
    ]
    moving_result = moving_rows[0] if moving_rows else None
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"rows": rows, "moving": moving_result}, indent=1))
    publish(rows, moving_result, out)


def publish(rows, moving_result, out: pathlib.Path) -> None:
    """The Pareto PNGs and the markdown report beside ``out``."""
    for case in dict.fromkeys(r["case"] for r in rows):
        chosen = [r for r in rows if r["case"] == case]
        curves = {}
        for r in chosen:
            curves.setdefault((r["method"], r["option"]), []).append(r)
        name = case.replace(" ", "_").replace(",", "").replace("=", "").replace("/", "")
        plot(case, curves, out.parent / f"accuracy_vs_time_{name}.png")
    text = report(rows, moving_result)
    out.with_suffix(".md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
