"""Random inclusions in the unit cube on P2 tetrahedra with each contact law: Newton's
iterations, the pressure error against the exact uniform stress and the failures.

Spheres and ellipsoids (random centre, semi-axes and orientation; quadric level sets,
which P2 holds exactly) in the unit cube (``--n`` cells per edge) under a uniform
stress: ``sticking`` and ``coulomb`` (mu = 1, inside the cone everywhere: the exact
solution sticks) under the triaxial stress diag(-1, -2, -3) Pa, ``frictionless`` under
the hydrostatic -2 Pa (no tangential traction). The exact contact traction is ``sigma
n``. ``slipping`` (Coulomb with mu = 0.1 under the triaxial stress: part of the
interface slips, no exact solution) is judged on its Newton iterations alone. A run
fails when it raises, does not converge, takes more than 15 Newton iterations (those
of a solve restarted after a stall included), gives a NaN, or has a pressure error above
3x the median of its law and shape (spheres and ellipsoids apart: their curvatures
differ) and above ``ERROR_FLOOR``; a failure without a warning or an error is a silent
one. The floor: where the exact traction lies in the discrete space (``frictionless``
on every inclusion, ``sticking`` and ``coulomb`` on spheres, whose ``sigma n`` is linear)
the whole error is that of the cut rules' quadrature, 1e-6 to 1e-5, whose spread
about its median says nothing a user would act on.

Run: ``python bench/robustness3d.py [--count 100] [--n 4] [--degree 2] [--cell
tetrahedron|hexahedron] [--laws sticking ...] [--seed 0] [--aggregation 0.15]
[--stabilization-length cell|cut|patch] [--inf-sup] [--write]
[--name NAME]``;
prints one row per run, the iteration histogram and the failures per law; ``--write``
writes ``bench/results/robustness3d.{json,md}`` (``robustness3d_hexahedron.*`` on
hexahedra, ``NAME.*`` with ``--name``),
``--render`` rewrites the ``.md`` from the ``.json``, ``--resume`` goes on from it
(with ``--placements``: reruns those, in place of their rows);
``--placements I J ...`` runs only those (the medians are then theirs); ``--inf-sup``
prints, per placement, the inf-sup constant of the ``bonded`` pair on the same cut
(:func:`~xfem_contact.mechanics.inf_sup.inf_sup_constant`) and the negative eigenvalues
of its displacement block (a stabilisation that took more than the bulk energy).
"""

import argparse
import json
import pathlib
import sys
import time
import warnings

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.solid import TRIAXIAL, traction_errors, uniform_stress_problem
from xfem_contact.mechanics.inf_sup import inf_sup_constant
from xfem_contact.mechanics.laws.multiplier import STABILIZATION_LENGTHS

RESULTS = pathlib.Path(__file__).parent / "results"
#: Per run label: the law, its options and the uniform stress (Pa, principal values)
LAWS = {
    "sticking": ("sticking", {}, TRIAXIAL),
    "coulomb": ("coulomb", {"friction": 1.0}, TRIAXIAL),
    "frictionless": ("frictionless", {}, (-2.0, -2.0, -2.0)),
    "slipping": ("coulomb", {"friction": 0.1}, TRIAXIAL),
}
#: The laws whose solution is the uniform stress (the others: no pressure-error check)
EXACT = ("sticking", "coulomb", "frictionless")
MAX_ITERATIONS = 15
ERROR_FACTOR = 3.0
#: Relative pressure errors below this are no failure, whatever the median (see above)
ERROR_FLOOR = 1e-4


def placements(count: int, seed: int) -> list[dict]:
    """``count`` inclusions: alternately spheres and ellipsoids, centre in
    [0.3, 0.7]^3, semi-axes in [0.1, 0.25] m (one radius for a sphere), a random
    orientation (a QR factor of a Gaussian matrix)."""
    rng = np.random.default_rng(seed)
    found = []
    for k in range(count):
        centre = rng.uniform(0.3, 0.7, 3)
        if k % 2 == 0:
            axes, rotation = np.full(3, rng.uniform(0.1, 0.25)), np.eye(3)
        else:
            axes = rng.uniform(0.1, 0.25, 3)
            rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        shape = "sphere" if k % 2 == 0 else "ellipsoid"
        found.append({"shape": shape, "centre": centre, "axes": axes, "rotation": rotation})
    return found


def quadric(placement: dict):
    """The level set ``((x - c)^T M (x - c) - 1) a_min / 2`` (``M = Q diag(a^-2) Q^T``)
    and its unit normals (numpy callables of ``x`` ``(3, n)`` and of points ``(p, 3)``)."""
    c, a, Q = placement["centre"], placement["axes"], placement["rotation"]
    M = Q @ np.diag(a**-2.0) @ Q.T
    scale = a.min() / 2

    def levelset(x):
        arm = x.T - c
        return (np.einsum("pi,ij,pj->p", arm, M, arm) - 1.0) * scale

    def normals(points):
        g = (points - c) @ M
        return g / np.linalg.norm(g, axis=1)[:, None]

    return levelset, normals


def run(
    placement: dict,
    law: str,
    n: int,
    degree: int,
    cell: str = "tetrahedron",
    aggregation: float | None = None,
    stabilization_length: str = "cell",
) -> dict:
    """One solve: its Newton iterations, convergence, pressure error, NaN and the
    warnings or the error it raised; ``aggregation``: the problem's cell aggregation
    threshold (None: off); ``stabilization_length``: the laws' (one of
    :data:`~xfem_contact.mechanics.laws.multiplier.STABILIZATION_LENGTHS`)."""
    name, options, stress = LAWS[law]
    options = options | {"aggregation": aggregation, "stabilization_length": stabilization_length}
    levelset, normals = quadric(placement)
    row = {"law": law, "shape": placement["shape"], "iterations": None, "error": None}
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            problem = uniform_stress_problem(
                n, degree, name, levelset, cell, stress=stress, **options
            )
            report = problem.solve()
            # every Newton step, those of solves restarted after a stall included
            row["iterations"] = report.total_iterations
            row["converged"] = bool(report.converged)
            row["nan"] = bool(not np.all(np.isfinite(problem.w.x.array)))
            sigma = np.diag(stress)
            row["error"], _ = traction_errors(problem, lambda m: m @ sigma, normals)
            row["raised"] = None
        except Exception as error:  # noqa: BLE001  (a failure to count, with its message)
            row["raised"] = f"{type(error).__name__}: {error}".splitlines()[0][:200]
            row["converged"], row["nan"] = False, False
    row["warnings"] = sorted({f"{w.category.__name__}: {w.message}"[:200] for w in caught})
    row["seconds"] = time.perf_counter() - start
    return row


def bonded_inf_sup(
    placement: dict, n: int, degree: int, cell: str, aggregation, stabilization_length: str
) -> str:
    """The inf-sup constant of the ``bonded`` pair on ``placement``'s cut, in words."""
    levelset, _ = quadric(placement)
    options = {"aggregation": aggregation, "stabilization_length": stabilization_length}
    problem = uniform_stress_problem(n, degree, "bonded", levelset, cell, **options)
    result = inf_sup_constant(problem)
    return (
        f"bonded pair: beta^2 {result.beta_squared:.3g}, negative displacement modes "
        f"{result.negative_displacement_modes}"
    )


def judge(rows: list[dict]) -> None:
    """Mark each row's failures (``failures``: the reasons) and whether a failure came
    without a warning or an error (``silent``)."""
    for group in {(r["law"], r["shape"]) for r in rows}:
        mine = [r for r in rows if (r["law"], r["shape"]) == group]
        errors = [r["error"] for r in mine if r["error"] is not None]
        median = float(np.median(errors)) if errors else np.nan
        for r in mine:
            reasons = []
            if r["raised"]:
                reasons.append("raised")
            if not r["converged"] and not r["raised"]:
                reasons.append("not converged")
            if r["iterations"] is not None and r["iterations"] > MAX_ITERATIONS:
                reasons.append(f"> {MAX_ITERATIONS} iterations")
            if r["nan"] or (r["error"] is not None and not np.isfinite(r["error"])):
                reasons.append("NaN")
            bound = max(ERROR_FACTOR * median, ERROR_FLOOR)
            if r["law"] in EXACT and r["error"] is not None and r["error"] > bound:
                reasons.append(f"error > {ERROR_FACTOR:g}x median and > {ERROR_FLOOR:g}")
            r["median_error"], r["failures"] = median, reasons
            r["silent"] = bool(reasons) and not r["raised"] and not r["warnings"]


def summary(rows: list[dict]) -> dict:
    """Per law: runs, failures, silent failures, the iteration histogram and the error
    quantiles."""
    table = {}
    for law in LAWS:
        mine = [r for r in rows if r["law"] == law]
        if not mine:
            continue
        iterations = [r["iterations"] for r in mine if r["iterations"] is not None]
        errors = np.array([r["error"] for r in mine if r["error"] is not None], dtype=float)
        ratios = [r["error"] / r["median_error"] for r in mine if r["error"] is not None]
        table[law] = {
            "runs": len(mine),
            "failures": sum(bool(r["failures"]) for r in mine),
            "silent failures": sum(r["silent"] for r in mine),
            "warned": sum(bool(r["warnings"]) for r in mine),
            "histogram": {int(k): iterations.count(k) for k in sorted(set(iterations))},
            "median error": float(np.median(errors)) if errors.size else None,
            "max error": float(errors.max()) if errors.size else None,
            "max / median": float(max(ratios)) if ratios else None,
            "seconds": float(sum(r["seconds"] for r in mine)),
        }
    return table


def markdown(table: dict, rows: list[dict], args, done: int) -> str:
    lines = [
        f"# Random inclusions, degree {args.degree} on {args.cell} cells, n = {args.n} "
        f"({placed(args, done)}, seed {args.seed})",
        "",
        f"Command: `{getattr(args, 'command', 'python bench/robustness3d.py')}`. A run fails "
        f"when it raises, does not converge, takes more than {MAX_ITERATIONS} Newton "
        "iterations in all (a solve restarted after a stall included), gives a NaN, or has "
        f"a pressure error above {ERROR_FACTOR:g}x the median of its law and shape and above "
        f"{ERROR_FLOOR:g} (where the exact traction is in the discrete space the error is "
        "the cut rules' quadrature error alone: see the script's docstring).",
        "",
        "| law | runs | failures | silent failures | runs with a warning | Newton iterations: "
        "runs | median pressure error (both shapes) | max | max / median of its shape | time (s) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for law, t in table.items():
        histogram = ", ".join(f"{k}: {v}" for k, v in t["histogram"].items())
        lines.append(
            f"| {law} | {t['runs']} | {t['failures']} | {t['silent failures']} | {t['warned']} "
            f"| {histogram} | {t['median error']:.2e} | {t['max error']:.2e} "
            f"| {t['max / median']:.2f} | {t['seconds']:.0f} |"
        )
    failed = [r for r in rows if r["failures"]]
    lines += ["", f"Failures: {len(failed)}."]
    shapes = placements(done, args.seed)
    h = 1.0 / args.n
    for r in failed:
        shape = shapes[r["index"]]
        where = (
            f"centre {np.round(shape['centre'], 3).tolist()}, semi-axes / h "
            f"{np.round(shape['axes'] / h, 2).tolist()}"
        )
        error = ""
        if r["error"] is not None:
            error = f", pressure error {r['error']:.2e} against the median {r['median_error']:.2e}"
        lines.append(
            f"- {r['law']} {r['shape']} #{r['index']} ({where}): {', '.join(r['failures'])}"
            f"{error} (warnings: {len(r['warnings']) or 'none'}; "
            f"raised: {r['raised'] or 'nothing'})"
        )
    kinds = sorted({w.split(":")[0] for r in rows for w in r["warnings"]})
    if kinds:
        lines += ["", "Warnings seen (runs with one, and an example):"]
        for kind in kinds:
            seen = [w for r in rows for w in r["warnings"] if w.split(":")[0] == kind]
            lines.append(f"- {kind}: {len(seen)} runs, e.g. {seen[0]}")
    return "\n".join(lines) + "\n"


def placed(args, done: int) -> str:
    """The placements run, in words: ``100 placements`` or ``placements 3, 7 of 100``."""
    chosen = getattr(args, "placements", None)
    if not chosen:
        return f"{done} placements"
    return f"placements {', '.join(map(str, sorted(chosen)))} of {args.count}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=100, help="placements")
    parser.add_argument("--n", type=int, default=4, help="cells per edge (even)")
    parser.add_argument("--degree", type=int, default=2, help="displacement degree")
    parser.add_argument("--cell", default="tetrahedron", help="tetrahedron or hexahedron")
    parser.add_argument("--laws", nargs="+", default=list(EXACT), choices=list(LAWS))
    parser.add_argument("--name", default=None, help="of the results (default from --cell)")
    parser.add_argument("--seed", type=int, default=0, help="of the random placements")
    parser.add_argument(
        "--placements", type=int, nargs="+", default=None, help="run only these (indices)"
    )
    parser.add_argument(
        "--aggregation", type=float, default=None, help="cell aggregation threshold (default: off)"
    )
    parser.add_argument(
        "--stabilization-length",
        choices=list(STABILIZATION_LENGTHS),
        default="cell",
        help="length of the Barbosa-Hughes scale (the laws' stabilization_length)",
    )
    parser.add_argument(
        "--inf-sup", action="store_true", help="the bonded pair's inf-sup constant too"
    )
    parser.add_argument("--write", action="store_true", help="write bench/results/")
    parser.add_argument(
        "--render", action="store_true", help="rewrite the .md from the .json run before"
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="go on from the .json of a stopped sweep (with --placements: rerun those)",
    )
    args = parser.parse_args()
    args.command = "python bench/robustness3d.py " + " ".join(sys.argv[1:])
    if args.render:
        record = json.loads((RESULTS / f"{results_name(args)}.json").read_text())
        for key in ("n", "degree", "seed", "command", "placements"):
            setattr(args, key, record.get(key, getattr(args, key)))
        write(record["runs"], args, record["count"])
        return
    if MPI.COMM_WORLD.size > 1:
        raise SystemExit("robustness3d: serial (one solve per placement)")
    rows, done = [], 0
    if args.resume:  # the placements of a stopped sweep's results, with its seed and n
        record = json.loads((RESULTS / f"{results_name(args)}.json").read_text())
        rows, done = record["runs"], record["count"]
    # --resume with --placements: rerun those of the sweep's placements, in place of
    # their rows (the record stays that of the whole sweep)
    redo = set(args.placements or []) if args.resume else set()
    if redo:
        rows = [r for r in rows if r["index"] not in redo]
        args.placements = None
    for index, placement in enumerate(placements(args.count, args.seed)):
        if redo:
            if index not in redo:
                continue
        elif index < done or (args.placements and index not in args.placements):
            continue
        for law in args.laws:
            row = run(
                placement,
                law,
                args.n,
                args.degree,
                args.cell,
                args.aggregation,
                args.stabilization_length,
            )
            row |= {"index": index}
            rows.append(row)
            error = "-" if row["error"] is None else f"{row['error']:.2e}"
            print(
                f"#{index} {placement['shape']} {law}: iterations {row['iterations']}, "
                f"pressure error {error}, {row['seconds']:.1f} s, "
                f"warnings {len(row['warnings'])}, raised {row['raised']}",
                flush=True,
            )
        if args.inf_sup:
            print(
                f"#{index} {placement['shape']} "
                + bonded_inf_sup(
                    placement,
                    args.n,
                    args.degree,
                    args.cell,
                    args.aggregation,
                    args.stabilization_length,
                ),
                flush=True,
            )
        rows.sort(key=lambda r: r["index"])  # a rerun placement in its place
        if args.write:  # after each placement: a stopped sweep keeps what it ran
            write(rows, args, max(done, index + 1))
    table = (
        write(rows, args, max(done, 1 + max(redo)) if redo else args.count)
        if args.write
        else report(rows)
    )
    for law, t in table.items():
        print(
            f"{law}: {t['runs']} runs, {t['failures']} failures ({t['silent failures']} "
            f"silent), iterations histogram {t['histogram']}, pressure error median "
            f"{t['median error']:.2e} max {t['max error']:.2e} ({t['max / median']:.2f}x)"
        )
    print(f"failures: {sum(t['failures'] for t in table.values())}")


def report(rows: list[dict]) -> dict:
    """:func:`judge` the rows and return their :func:`summary`."""
    judge(rows)
    return summary(rows)


def results_name(args) -> str:
    """``--name``, or ``robustness3d`` (``robustness3d_hexahedron`` on hexahedra)."""
    if args.name:
        return args.name
    return "robustness3d" if args.cell == "tetrahedron" else f"robustness3d_{args.cell}"


def write(rows: list[dict], args, done: int) -> dict:
    """Write ``bench/results/robustness3d.{json,md}`` (``robustness3d_hexahedron.*`` on
    hexahedra) of the ``done`` placements run; the summary."""
    table = report(rows)
    RESULTS.mkdir(exist_ok=True)
    name = results_name(args)
    record = {"n": args.n, "degree": args.degree, "cell": args.cell, "count": done}
    record["seed"], record["command"] = args.seed, args.command
    record["placements"] = args.placements
    record |= {"summary": table, "runs": rows}
    (RESULTS / f"{name}.json").write_text(json.dumps(record, indent=1, default=str))
    (RESULTS / f"{name}.md").write_text(markdown(table, rows, args, done))
    return table


if __name__ == "__main__":
    main()
