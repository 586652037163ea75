"""A parameter sweep costs solves, not compiles: paper case 2 with Coulomb friction,
solved for 10 friction coefficients on one problem (the coefficient is a Constant of
the forms), against building the problem again for each value.

Prints and writes ``bench/results/parameter_sweep.{json,md}``: per value the wall time
of ``law.friction = mu`` + solve, of build + solve, the Newton iterations, the forms
compiled (0 expected after the first solve) and the ratio to the first solve measured
in the same run.

Run: ``python bench/parameter_sweep.py [--n 40] [--values 10]``.
"""

import argparse
import json
import pathlib
import time

import numpy as np

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.fem import forms

RESULTS = pathlib.Path(__file__).parent / "results"


def timed(f):
    start = time.perf_counter()
    value = f()
    return value, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=40, help="cells per side")
    parser.add_argument("--values", type=int, default=10, help="friction coefficients")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    say = (lambda *a: None) if args.no_progress else print
    frictions = np.linspace(0.1, 1.0, args.values)

    compiled = forms.compiled_forms()
    problem, build = timed(lambda: inclusion_problem(args.n, 2, "coulomb", friction=frictions[0]))
    report, first = timed(problem.solve)
    first_compiles = forms.compiled_forms() - compiled
    dofs = problem.space.dof_counts().total
    say(
        f"case 2 Coulomb, n = {args.n}, P2, {dofs} dofs: build {build:.2f} s, first solve "
        f"{first:.2f} s ({first_compiles} forms compiled, {report.iterations} Newton steps)"
    )
    rows = []
    for mu in frictions:
        before = forms.compiled_forms()
        problem.law().friction = mu
        problem.w.x.array[:] = 0.0  # each value from rest, as a new problem would start
        problem.w_old.x.array[:] = 0.0
        report, sweep = timed(problem.solve)
        swept_compiles = forms.compiled_forms() - before
        lambda_n = np.array(problem.interface_samples(problem.w)["lambda_n"])
        fresh, rebuild = timed(lambda mu=mu: inclusion_problem(args.n, 2, "coulomb", friction=mu))
        fresh_report, fresh_solve = timed(fresh.solve)
        difference = (
            np.abs(fresh.w.x.array - problem.w.x.array).max() / np.abs(fresh.w.x.array).max()
        )
        rows.append(
            {
                "friction": float(mu),
                "set_and_solve_s": sweep,
                "newton_steps": report.iterations,
                "forms_compiled": swept_compiles,
                "rebuild_and_solve_s": rebuild + fresh_solve,
                "ratio_to_first_solve": sweep / first,
                "ratio_to_rebuild": sweep / (rebuild + fresh_solve),
                "max_relative_difference_to_rebuilt": float(difference),
                "mean_lambda_n": float(lambda_n.mean()),
            }
        )
        del fresh
        say(
            f"mu = {mu:.2f}: set + solve {sweep:.2f} s ({report.iterations} steps, "
            f"{swept_compiles} compiled), rebuild + solve {rebuild + fresh_solve:.2f} s, "
            f"same solution to {difference:.1e}"
        )
    total = sum(r["set_and_solve_s"] for r in rows)
    summary = {
        "n": args.n,
        "dofs": dofs,
        "build_s": build,
        "first_solve_s": first,
        "first_solve_forms_compiled": first_compiles,
        "sweep_forms_compiled": sum(r["forms_compiled"] for r in rows),
        "sweep_total_s": total,
        "sweep_total_over_values_times_first_solve": total / (len(rows) * first),
        "rows": rows,
    }
    say(
        f"{len(rows)} values: {summary['sweep_forms_compiled']} forms compiled, "
        f"{total:.2f} s = {summary['sweep_total_over_values_times_first_solve']:.2f} x "
        f"({len(rows)} x the first solve)"
    )
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "parameter_sweep.json").write_text(json.dumps(summary, indent=1))
    lines = [
        f"# Friction sweep on one problem (case 2 Coulomb, n = {args.n}, P2, {dofs} dofs)",
        "",
        f"Build {build:.2f} s; first solve {first:.2f} s ({first_compiles} forms compiled on "
        "this process's first use). Each value: `problem.law().friction = mu`, the state reset "
        "to rest, one Newton solve; against a problem built for that value.",
        "",
        "| friction | set + solve (s) | Newton steps | forms compiled | rebuild + solve (s) "
        "| / first solve | / rebuild | max rel. difference |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {r['friction']:.2f} | {r['set_and_solve_s']:.2f} | {r['newton_steps']} | "
        f"{r['forms_compiled']} | {r['rebuild_and_solve_s']:.2f} | "
        f"{r['ratio_to_first_solve']:.2f} | {r['ratio_to_rebuild']:.2f} | "
        f"{r['max_relative_difference_to_rebuilt']:.1e} |"
        for r in rows
    ]
    lines += [
        "",
        f"Sweep: {summary['sweep_forms_compiled']} forms compiled, {total:.2f} s in all, "
        f"{summary['sweep_total_over_values_times_first_solve']:.2f} x {len(rows)} first solves.",
    ]
    (RESULTS / "parameter_sweep.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
