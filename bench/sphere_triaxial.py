"""A sphere in the unit cube under triaxial compression (3D analogue of paper case 2):
the contact pressure and tangential traction errors of the multiplier against the exact
``sigma n`` (uniform stress ``diag(-1, -2, -3)`` Pa, one material), with their rates.

Each (level set, degree, n) is solved in a process of its own (``bench/scale3d.py``'s
``measured``): whole-process wall time and peak resident memory. For every row also the
patch-test residual: the relative norm of the reduced residual at the exact solution
(the linear displacement and the multiplier ``sigma (x - c) / R`` interpolated), what
the cut rules leave of consistency; with the quadric level set (the sphere exact) the
exact solution lies in the discrete space of either degree, so the error is that
residual's alone.

Run: ``python bench/sphere_triaxial.py [--sizes 4 8] [--degree 1 2]
[--levelset distance quadric] [--law sticking] [--cell tetrahedron]
[--multiplier-degree 2] [--lbb restriction] [--option ghost_penalty=0.1]
[--write [--name STEM]]``; prints one row per run (dofs, Newton iterations, errors,
time, memory) and the rates; ``--write`` writes ``bench/results/sphere_triaxial.{json,md}``
(``--name``: another stem). The study of the docs:
``--sizes 4 8 12 16 --degree 1 2 --levelset quadric distance --write``.
"""

import argparse
import ast
import json
import pathlib
import sys

import numpy as np
from scale3d import measured

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
LBB = ("stabilized", "restriction", "none")
CELLS = {"tetrahedron": "tetrahedra", "hexahedron": "hexahedra"}


def case(args, n: int, degree: int, levelset: str) -> dict:
    """Solve one sphere in this process; its row. Collective."""
    import time

    import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

    # isort: split
    from xfem_contact.cases.solid import patch_residual, sphere_errors, sphere_problem

    start = time.perf_counter()
    options = {"multiplier_degree": args.multiplier_degree, "lbb": args.lbb}
    if args.friction is not None:
        options["friction"] = args.friction
    options |= dict(args.option)
    problem = sphere_problem(n, degree, args.law, args.cell, levelset=levelset, **options)
    report = problem.solve()
    pressure, tangential = sphere_errors(problem)
    solved = time.perf_counter() - start
    return {
        "levelset": levelset,
        "degree": degree,
        "n": n,
        "dofs": problem.space.dof_counts().total,
        "newton": getattr(report, "iterations", 1),
        "pressure": pressure,
        "tangential": tangential,
        "residual": patch_residual(problem),
        "solve_s": solved,
    }


def rates(rows: list[dict], key: str) -> list[float]:
    """Rates of ``key`` between consecutive sizes of one (level set, degree)."""
    n = np.array([r["n"] for r in rows], dtype=float)
    e = np.array([r[key] for r in rows])
    return (-np.diff(np.log(e)) / np.diff(np.log(n))).tolist()


def markdown(rows: list[dict], command: str, args) -> str:
    """The results page."""
    element = "Q" if args.cell == "hexahedron" else "P"
    lines = [
        f"`{command}` ({args.law} sphere, {CELLS[args.cell]}, multiplier "
        f"P{args.multiplier_degree}, lbb={args.lbb}"
        + "".join(f", {k}={v}" for k, v in args.option)
        + "; each row a process of its own: whole-process wall time, peak RSS).",
        "",
        "The patch-test residual is the relative norm of the reduced residual at the exact "
        "solution interpolated (the linear displacement, the multiplier "
        "`sigma (x - c) / R`): what the cut rules leave of consistency. With the quadric "
        "level set (interpolated in P2 whatever the displacement's degree: the exact sphere) "
        "the exact solution lies in the discrete spaces of both degrees (a patch test): the "
        "errors are that residual's, not an approximation error. With the signed distance "
        "the interface and its normal are the P2 interpolant's: the errors are the "
        "normal's.",
        "",
        "| level set | element | n | dofs | Newton | pressure error | rate | tangential error "
        "| rate | patch-test residual | time (s) | peak RSS (MB) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for key in dict.fromkeys((r["levelset"], r["degree"]) for r in rows):
        group = [r for r in rows if (r["levelset"], r["degree"]) == key]
        rate_n, rate_t = [None, *rates(group, "pressure")], [None, *rates(group, "tangential")]
        for r, a, b in zip(group, rate_n, rate_t, strict=True):
            lines.append(
                f"| {r['levelset']} | {element}{r['degree']} | {r['n']} | {r['dofs']:,} | "
                f"{r['newton']} | {r['pressure']:.3e} | {'-' if a is None else f'{a:.2f}'} | "
                f"{r['tangential']:.3e} | {'-' if b is None else f'{b:.2f}'} | "
                f"{r['residual']:.1e} | {r['wall_s']:.1f} | {r['rss_mb']:.0f} |"
            )
    return "\n".join(lines) + "\n"


def option(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` of ``--option`` (VALUE a Python literal)."""
    key, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"--option takes KEY=VALUE, got {text!r}")
    return key, ast.literal_eval(value)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8], help="cells per edge")
    parser.add_argument("--degree", type=int, nargs="+", default=[2], help="displacement")
    parser.add_argument("--law", default="sticking", help="sticking, bonded, coulomb, ...")
    parser.add_argument("--cell", default="tetrahedron", choices=list(CELLS), help="cells")
    parser.add_argument("--friction", type=float, default=None, help="coulomb's mu")
    parser.add_argument(
        "--levelset",
        nargs="+",
        default=["distance"],
        choices=["distance", "quadric"],
        help="the sphere's level set: signed distance, or the quadric P2 holds exactly",
    )
    parser.add_argument(
        "--multiplier-degree", type=int, default=1, choices=[1, 2], help="of the multiplier"
    )
    parser.add_argument("--lbb", default="stabilized", choices=LBB, help="the LBB treatment")
    parser.add_argument(
        "--option", type=option, nargs="*", default=[], help="problem options KEY=VALUE"
    )
    parser.add_argument("--write", action="store_true", help="write bench/results/")
    parser.add_argument("--name", default="sphere_triaxial", help="stem of the results")
    parser.add_argument("--run", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.run:  # the worker: one solve, its row as the last line
        n, degree, levelset = int(args.run[0]), int(args.run[1]), args.run[2]
        row = case(args, n, degree, levelset)
        from mpi4py import MPI

        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(row), flush=True)
        return
    rows = []
    passed = [a for a in sys.argv[1:] if a not in ("--write",)]
    for levelset in args.levelset:
        for degree in args.degree:
            for n in args.sizes:
                command = [sys.executable, __file__, *passed, "--run", str(n)]
                row = measured(command + [str(degree), levelset])
                if "failed" in row:
                    print(f"{levelset} P{degree} n={n}: {row['failed']}", flush=True)
                    continue
                rows.append(row)
                print(
                    f"{args.law} {args.cell} {levelset} P{degree}-P{args.multiplier_degree} "
                    f"lbb={args.lbb} n={n}: pressure error {row['pressure']:.3e}, tangential "
                    f"{row['tangential']:.3e}, patch-test residual {row['residual']:.1e}, "
                    f"{row['dofs']} dofs, {row['newton']} Newton iterations, "
                    f"{row['wall_s']:.1f} s, {row['rss_mb']:.0f} MB",
                    flush=True,
                )
            group = [r for r in rows if (r["levelset"], r["degree"]) == (levelset, degree)]
            if len(group) > 1:
                print(
                    f"{levelset} P{degree}: pressure rates "
                    f"{np.round(rates(group, 'pressure'), 2).tolist()}, tangential "
                    f"{np.round(rates(group, 'tangential'), 2).tolist()}",
                    flush=True,
                )
    if args.write:
        command = "python bench/sphere_triaxial.py " + " ".join(sys.argv[1:])
        RESULTS.mkdir(parents=True, exist_ok=True)
        record = {"command": command, "rows": rows}
        (RESULTS / f"{args.name}.json").write_text(json.dumps(record, indent=1))
        (RESULTS / f"{args.name}.md").write_text(markdown(rows, command, args))


if __name__ == "__main__":
    main()
