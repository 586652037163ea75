"""The P2 pressure rate of the sticking sphere with the signed-distance level set, averaged
over sphere centres: the asymptotic rate apart from the noise of the cut's position.

The case of ``bench/sphere_triaxial.py`` (sphere R = 0.2 m in the unit cube, one
material, triaxial stress diag(-1, -2, -3) Pa, ``sticking``, P2 tetrahedra, multiplier
P1, the signed distance interpolated in P2) with the centre drawn at random in
``[0.5 - SHIFT, 0.5 + SHIFT]^3`` (``--centres`` of them, ``--seed``: the same centres at
every ``n``). The exact contact traction is ``sigma n`` with the normal of the exact
sphere at the interface rule's points. Each (centre, n) is a process of its own
(``bench/scale3d.py``'s :func:`measured`: wall time, CPU time, peak RSS). Printed and
written: per centre the errors and their rates; per ``n`` the mean, geometric mean, least
and largest error over the centres, and the rates of the means.

Run: ``python bench/sphere_rate3d.py [--sizes 4 8 12 16] [--centres 5] [--seed 0]
[--solver iterative] [--write]``; ``--write`` writes ``bench/results/sphere_rate3d.{json,md}``;
``--report-only`` rewrites the page from the JSON.
"""

import argparse
import json
import pathlib
import shlex
import sys

import numpy as np
from scale3d import measured

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
#: The centres' largest offset from the cube's centre along each axis (m)
SHIFT = 0.1


def centres(count: int, seed: int) -> np.ndarray:
    """``(count, 3)`` sphere centres (m), the same for a given seed."""
    return 0.5 + np.random.default_rng(seed).uniform(-SHIFT, SHIFT, size=(count, 3))


def case(n: int, centre: np.ndarray, solver: str) -> dict:
    """Solve the sticking sphere about ``centre`` on ``n`` cells per edge in this process;
    its errors, dofs and Newton iterations. Collective."""
    import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

    # isort: split
    from xfem_contact.cases.solid import (
        SPHERE_RADIUS,
        traction_errors,
        uniform_stress_problem,
    )
    from xfem_contact.solvers.options import preset

    def distance(x):
        return np.linalg.norm(x.T - centre, axis=1) - SPHERE_RADIUS

    def normals(points):
        arm = points - centre
        return arm / np.linalg.norm(arm, axis=1)[:, None]

    problem = uniform_stress_problem(
        n, 2, "sticking", distance, "tetrahedron", petsc_options=preset(solver)
    )
    report = problem.solve()
    stress = np.diag(problem.stress)
    pressure, tangential = traction_errors(problem, lambda m: m @ stress, normals)
    return {
        "dofs": problem.space.dof_counts().total,
        "newton": report.iterations,
        "pressure": pressure,
        "tangential": tangential,
    }


def rates(sizes, errors) -> list[float]:
    """Observed orders between consecutive sizes."""
    n, e = np.asarray(sizes, dtype=float), np.asarray(errors, dtype=float)
    return (-np.diff(np.log(e)) / np.diff(np.log(n))).tolist()


def statistics(rows: list[dict], sizes: list[int]) -> list[dict]:
    """Per size, the mean, geometric mean, least and largest pressure error over the
    centres."""
    out = []
    for n in sizes:
        e = np.array([r["pressure"] for r in rows if r["n"] == n])
        out.append(
            {
                "n": n,
                "count": e.size,
                "mean": float(e.mean()),
                "geometric": float(np.exp(np.log(e).mean())),
                "min": float(e.min()),
                "max": float(e.max()),
            }
        )
    return out


def fmt(values) -> str:
    return ", ".join(f"{v:.2f}" for v in values)


def markdown(record: dict) -> str:
    """The results page."""
    rows, sizes = record["rows"], record["sizes"]
    stats = statistics(rows, sizes)
    points = sorted({tuple(r["centre"]) for r in rows})
    lines = [
        f"Command: `{record['command']}` (sticking sphere R = 0.2 m, triaxial -1/-2/-3 Pa, "
        f"P2 tetrahedra, multiplier P1, the signed distance interpolated in P2, the "
        f"`{record['solver']}` preset; {len(points)} centres drawn in "
        f"[{0.5 - SHIFT}, {0.5 + SHIFT}]^3 with seed {record['seed']}, the same at every n; "
        "each run a process of its own).",
        "",
        "Relative L2 error of the contact pressure against the exact `n.sigma.n` on the "
        "exact sphere's normal, per size over the centres, and the rates of the means "
        "between consecutive sizes:",
        "",
        "| n | centres | mean | rate | geometric mean | rate | least | largest | largest / least |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    mean_rates = [None, *rates(sizes, [s["mean"] for s in stats])]
    geo_rates = [None, *rates(sizes, [s["geometric"] for s in stats])]
    for s, a, b in zip(stats, mean_rates, geo_rates, strict=True):
        lines.append(
            f"| {s['n']} | {s['count']} | {s['mean']:.3e} | {'-' if a is None else f'{a:.2f}'} "
            f"| {s['geometric']:.3e} | {'-' if b is None else f'{b:.2f}'} | {s['min']:.3e} | "
            f"{s['max']:.3e} | {s['max'] / s['min']:.1f} |"
        )
    if len(sizes) > 1:
        first, last = sizes[0], sizes[-1]
        fit = np.polyfit(np.log(sizes), np.log([s["mean"] for s in stats]), 1)[0]
        lines += [
            "",
            f"Least-squares rate of the mean over n = {', '.join(map(str, sizes))}: "
            f"{-fit:.2f}; from n = {first} to {last}: "
            f"{rates([first, last], [stats[0]['mean'], stats[-1]['mean']])[0]:.2f}.",
        ]
    lines += [
        "",
        "Per centre (pressure error; the rates between consecutive sizes):",
        "",
        "| centre (m) | " + " | ".join(f"n = {n}" for n in sizes) + " | rates |",
        "|---|" + "---|" * (len(sizes) + 1),
    ]
    for point in points:
        group = sorted((r for r in rows if tuple(r["centre"]) == point), key=lambda r: r["n"])
        errors = {r["n"]: r["pressure"] for r in group}
        cells = " | ".join(f"{errors[n]:.3e}" if n in errors else "-" for n in sizes)
        observed = rates([r["n"] for r in group], [r["pressure"] for r in group])
        lines.append(
            f"| ({point[0]:.3f}, {point[1]:.3f}, {point[2]:.3f}) | {cells} | {fmt(observed)} |"
        )
    lines += [
        "",
        "| centre (m) | n | dofs | Newton | pressure error | tangential error | wall (s) "
        "| CPU (s) | peak RSS (MB) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in sorted(rows, key=lambda r: (tuple(r["centre"]), r["n"])):
        c = r["centre"]
        lines.append(
            f"| ({c[0]:.3f}, {c[1]:.3f}, {c[2]:.3f}) | {r['n']} | {r['dofs']:,} | "
            f"{r['newton']} | {r['pressure']:.3e} | {r['tangential']:.3e} | "
            f"{r['wall_s']:.1f} | {r['cpu_s']:.1f} | {r['rss_mb']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8, 12, 16])
    parser.add_argument("--centres", type=int, default=5, help="how many sphere centres")
    parser.add_argument("--seed", type=int, default=0, help="of the centres")
    parser.add_argument("--solver", default="iterative", choices=["direct", "iterative"])
    parser.add_argument("--write", action="store_true", help="write bench/results/")
    parser.add_argument("--report-only", action="store_true", help="the page from the JSON")
    parser.add_argument("--name", default="sphere_rate3d", help="stem of the results")
    parser.add_argument("--run", nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if any(n <= 0 or n % 2 for n in args.sizes):
        raise ValueError(f"--sizes must be positive even numbers of cells, got {args.sizes}")
    if args.centres < 1:
        raise ValueError(f"--centres must be at least 1, got {args.centres}")
    if args.run:  # the worker: one solve, its row as the last line
        n, *centre = args.run
        row = case(int(n), np.array([float(c) for c in centre]), args.solver)
        from mpi4py import MPI

        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(row), flush=True)
        return
    path = RESULTS / f"{args.name}.json"
    if args.report_only:
        text = markdown(json.loads(path.read_text()))
        path.with_suffix(".md").write_text(text)
        print(text)
        return
    command = shlex.join(["python", "bench/sphere_rate3d.py", *sys.argv[1:]])
    record = {"command": command, "sizes": args.sizes, "seed": args.seed, "solver": args.solver}
    record["rows"] = []
    for n in args.sizes:
        for centre in centres(args.centres, args.seed):
            worker = [sys.executable, __file__, "--solver", args.solver, "--run", str(n)]
            row = measured(worker + [repr(float(c)) for c in centre])
            if "failed" in row:
                print(f"centre {centre} n = {n}: {row['failed']}", flush=True)
                continue
            row |= {"n": n, "centre": centre.tolist()}
            record["rows"].append(row)
            print(
                f"centre ({', '.join(f'{c:.3f}' for c in centre)}) n = {n}: pressure error "
                f"{row['pressure']:.3e}, {row['dofs']} dofs, {row['newton']} Newton, wall "
                f"{row['wall_s']:.1f} s, CPU {row['cpu_s']:.1f} s, {row['rss_mb']:.0f} MB",
                flush=True,
            )
            if args.write:  # after each run: a stopped study keeps its rows
                RESULTS.mkdir(parents=True, exist_ok=True)
                path.write_text(json.dumps(record, indent=1))
    text = markdown(record)
    print(text)
    if args.write:
        path.write_text(json.dumps(record, indent=1))
        path.with_suffix(".md").write_text(text)


if __name__ == "__main__":
    main()
