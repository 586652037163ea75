"""Parallel efficiency of large sliding against plain DOLFINx's on the same mesh.

Paper case 3 turned by 1 rad in 4 load steps (P2, ``n`` x ``4 n`` curved cells,
:func:`~xfem_contact.cases.rotation.rotating_annulus_problem`), each run a process of
its own on 1 and ``--ranks`` ranks with each linear-solver preset (``direct``: GMRES on
a reused MUMPS LU; ``iterative``: GMRES + band multigrid), next to plain DOLFINx linear
elasticity on the same mesh in the same run (``bench/plain_elasticity.py --mesh
annulus``: MUMPS LU with xfem-contact's controls beside ``direct``, CG + GAMG beside
``iterative``). Each configuration runs ``--repeat`` times in turn and its fastest run
stands for it (a shared machine only ever slows a run down). Prints the whole-process
wall times, the solve's (the 4 load steps) and plain's assembly + solve, the speed-ups
and their ratio to plain DOLFINx's, and the largest difference of ``lambda_n`` between
1 and ``--ranks`` ranks (interface points matched by position). Writes
``bench/results/parallel_sliding.{json,md}``.

Run: ``python bench/parallel_sliding.py [--n 80] [--ranks 2] [--repeat 2]``.
"""

import argparse
import json
import pathlib
import sys
import tempfile
import time

from scaling import RESULTS, max_difference, mumps_controls, plain, run

PLAIN_FACTOR = {"direct": "lu", "iterative": "gamg"}


def case(n: int, solver: str, path: str) -> None:
    """Case 3 turned by 1 rad in 4 steps in this process; writes its numbers. Collective."""
    from mpi4py import MPI

    from xfem_contact.cases.rotation import pressure_errors, rotating_annulus_problem
    from xfem_contact.solvers.options import preset

    problem = rotating_annulus_problem(n, 2, 1.0, petsc_options=preset(solver))
    start, iterations, krylov = time.perf_counter(), [], []
    for k in range(1, 5):
        problem.loads.set_time(k / 4)
        report = problem.solve()
        problem.accept_step()
        iterations.append(report.iterations)
        krylov.append(report.linear_iterations)
    solve = time.perf_counter() - start
    samples = problem.interface_samples(problem.w)  # collective, as the two below
    errors, dofs = pressure_errors(problem), problem.space.dof_counts().total
    if MPI.COMM_WORLD.rank == 0:
        data = {"dofs": dofs, "solve": solve, "newton": iterations}
        data |= {"krylov": krylov, "error": errors["error"], "_samples": samples}
        pathlib.Path(path).write_text(json.dumps(data))


def sliding(n: int, solver: str, ranks: int, work: pathlib.Path) -> dict:
    path = work / f"case_{n}_{solver}_{ranks}.json"
    command = [sys.executable, __file__, "--case", str(n), solver, str(path)]
    if ranks > 1:
        command = [str(pathlib.Path(sys.executable).parent / "mpiexec"), "-n", str(ranks)] + command
    wall, rss, _ = run(command)
    return json.loads(path.read_text()) | {"wall": wall, "rss_mb": rss}


def fastest(measure, repeat: int) -> dict:
    runs = [measure() for _ in range(repeat)]
    return min(runs, key=lambda r: r["wall"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=80, help="n radial (n x 4n cells)")
    parser.add_argument("--ranks", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--solvers", nargs="+", default=["direct", "iterative"])
    parser.add_argument("--case", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        case(int(args.case[0]), args.case[1], args.case[2])
        return
    mumps, rows = mumps_controls(), []
    with tempfile.TemporaryDirectory() as folder:
        work = pathlib.Path(folder)
        for solver in args.solvers:
            factor = PLAIN_FACTOR[solver]
            runs = {}
            for ranks in (1, args.ranks):
                runs[ranks] = fastest(
                    lambda r=ranks, s=solver: sliding(args.n, s, r, work), args.repeat
                )
                runs[ranks, "plain"] = fastest(
                    lambda r=ranks, f=factor: plain(args.n, 2, work, mumps, None, r, f, "annulus"),
                    args.repeat,
                )
            one, many = runs[1], runs[args.ranks]
            p1, pn = runs[1, "plain"], runs[args.ranks, "plain"]

            def work_time(p):
                return p["timings"]["assembly"] + p["timings"]["solve"]

            row = {
                "n": args.n,
                "solver": solver,
                "ranks": args.ranks,
                "dofs": one["dofs"],
                "plain_dofs": p1["dofs"],
                "newton": one["newton"],
                "krylov": [one["krylov"], many["krylov"]],
                "wall": [one["wall"], many["wall"]],
                "solve": [one["solve"], many["solve"]],
                "plain_wall": [p1["wall"], pn["wall"]],
                "plain_solve": [work_time(p1), work_time(pn)],
                "speedup_wall": one["wall"] / many["wall"],
                "speedup_solve": one["solve"] / many["solve"],
                "plain_speedup_wall": p1["wall"] / pn["wall"],
                "plain_speedup_solve": work_time(p1) / work_time(pn),
                "lambda_difference": max_difference(one["_samples"], many["_samples"]),
                "error": one["error"],
            }
            row["ratio_wall"] = row["speedup_wall"] / row["plain_speedup_wall"]
            row["ratio_solve"] = row["speedup_solve"] / row["plain_speedup_solve"]
            rows.append(row)
            print(line(row), flush=True)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "parallel_sliding.json").write_text(json.dumps(rows, indent=1))
    (RESULTS / "parallel_sliding.md").write_text(table(rows))


def line(row: dict) -> str:
    return (
        f"case 3 n={row['n']} {row['solver']}: {row['dofs']} dofs; whole process "
        f"{row['wall'][0]:.1f} s / {row['wall'][1]:.1f} s on 1 / {row['ranks']} ranks "
        f"(speed-up {row['speedup_wall']:.2f}, plain {row['plain_speedup_wall']:.2f}: ratio "
        f"{row['ratio_wall']:.2f}); solve {row['solve'][0]:.1f} / {row['solve'][1]:.1f} s "
        f"(speed-up {row['speedup_solve']:.2f}, plain assembly + solve "
        f"{row['plain_speedup_solve']:.2f}: ratio {row['ratio_solve']:.2f}); lambda_n 1 vs "
        f"{row['ranks']} ranks {row['lambda_difference']:.1e}; Newton {row['newton']}"
    )


def table(rows: list[dict]) -> str:
    head = (
        "| n | solver | dofs | whole process 1 / N ranks (s) | speed-up | plain | ratio "
        "| solve 1 / N (s) | speed-up | plain (assembly + solve) | ratio | lambda_n 1 vs N "
        "| Newton | Krylov 1 / N |"
    )
    lines = [head, "|" + "---|" * 14]
    for r in rows:
        lines.append(
            f"| {r['n']} | {r['solver']} | {r['dofs']:,} "
            f"| {r['wall'][0]:.1f} / {r['wall'][1]:.1f} | {r['speedup_wall']:.2f} "
            f"| {r['plain_speedup_wall']:.2f} | **{r['ratio_wall']:.2f}** "
            f"| {r['solve'][0]:.1f} / {r['solve'][1]:.1f} | {r['speedup_solve']:.2f} "
            f"| {r['plain_speedup_solve']:.2f} | **{r['ratio_solve']:.2f}** "
            f"| {r['lambda_difference']:.1e} | {r['newton']} "
            f"| {r['krylov'][0]} / {r['krylov'][1]} |"
        )
    return (
        "# Parallel efficiency of large sliding\n\n"
        f"`python bench/parallel_sliding.py` ({rows[0]['ranks']} ranks; paper case 3 turned "
        "by 1 rad in 4 steps, P2; plain DOLFINx linear elasticity on the same mesh in the same "
        "run; fastest of the repeats)\n\n" + "\n".join(lines) + "\n"
    )


if __name__ == "__main__":
    main()
