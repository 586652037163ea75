"""Coulomb friction on the sphere under triaxial compression: part of the interface
slips. The multiplier and the stick area converge to those of a finer mesh (no exact
solution); optionally the friction limits, Coulomb with mu = 0 against the frictionless
law and with mu = 1e3 against the sticking law.

Sphere R = 0.2 (quadric level set) in the unit cube, diag(-1, -2, -3) Pa, mu = 0.1 by
default; the three spins of the ball are held at mesh nodes on its axes for every law
(the frictionless ball has no other hold on them). The reference is solved first, then
per size: Newton iterations, the stick area fraction and its difference to the
reference's, the relative L2 difference of the Cartesian multiplier to the reference's
(read at this mesh's interface points), the relative L2 difference of ``lambda_n`` and
of ``lambda_t`` alone, and their rates; with ``--limits`` the relative max difference
of ``lambda_n`` between Coulomb with mu = 0 and the frictionless law, and with mu = 1e3
and the sticking law. Serial; peak RSS of the process (it holds the reference).
Run: ``python bench/sphere_friction.py [--sizes 4 6 8 12] [--reference 24] [--degree 1]
[--friction 0.1] [--limits] [--write [--name STEM]]``; ``--write`` writes
``bench/results/sphere_friction.{json,md}``.
"""

import argparse
import json
import pathlib
import resource
import sys
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np

from xfem_contact.cases.solid import hold_spins, sphere_problem
from xfem_contact.cases.sphere_interface import multiplier_difference, stick_fraction

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"


def held_sphere(n: int, degree: int, law: str, **options):
    """:func:`sphere_problem` (quadric) with the ball's three spins held
    (:func:`hold_spins`) at the nodes one node spacing ``1 / (n degree)`` off the centre,
    the same for every law compared."""
    problem = sphere_problem(n, degree, law, levelset="quadric", **options)
    hold_spins(problem, 1.0 / (n * degree))
    return problem


def solved(n: int, degree: int, law: str, **options):
    problem = held_sphere(n, degree, law, **options)
    report = problem.solve()
    return problem, report


def limit_difference(a, b) -> float:
    """Max |lambda_n| difference of two solved problems on one mesh over the second's
    max |lambda_n|."""
    x, y = (p.interface_state(p.w)["lambda_n"] for p in (a, b))
    return float(np.abs(x - y).max() / np.abs(y).max())


def peak_rss_mb() -> float:
    """This process's peak resident memory (MB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def rates(rows: list[dict], key: str) -> list[float]:
    """Rates of ``key`` against ``n`` between consecutive rows."""
    n = np.array([r["n"] for r in rows], dtype=float)
    e = np.array([r[key] for r in rows])
    return (-np.diff(np.log(e)) / np.diff(np.log(n))).tolist()


def markdown(reference: dict, rows: list[dict], command: str, args) -> str:
    """The results page."""
    lines = [
        f"`{command}` (Coulomb mu = {args.friction:g}, sphere R = 0.2 with the quadric "
        f"level set in the unit cube, diag(-1, -2, -3) Pa, P{args.degree} tetrahedra, "
        "multiplier P1, lbb=stabilized, the spins held; one process, serial).",
        "",
        f"Reference: n = {reference['n']}, {reference['dofs']:,} dofs, "
        f"{reference['newton']} Newton iterations, stick fraction "
        f"{reference['stick']:.4f}, {reference['time_s']:.1f} s; peak RSS of the whole run "
        f"{reference['peak_rss_mb']:.0f} MB.",
        "",
        "Differences to the reference's multiplier read at each mesh's interface points "
        "(relative L2 on the sphere): the Cartesian multiplier, its normal part and its "
        "tangential part; the rate is against n.",
        "",
        "| n | dofs | Newton | stick fraction | reference - this | multiplier | rate | "
        "normal | rate | tangential | rate | time (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    keys = ("multiplier", "normal", "tangential")
    slopes = {k: ["-"] + [f"{r:.2f}" for r in rates(rows, k)] for k in keys}
    for i, row in enumerate(rows):
        cells = [f"{row[k]:.3e} | {slopes[k][i]}" for k in keys]
        lines.append(
            f"| {row['n']} | {row['dofs']:,} | {row['newton']} | {row['stick']:.4f} | "
            f"{reference['stick'] - row['stick']:+.4f} | " + " | ".join(cells) + f" | "
            f"{row['time_s']:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 6, 8], help="cells per edge")
    parser.add_argument("--reference", type=int, default=12, help="the finest mesh's n")
    parser.add_argument("--degree", type=int, default=1, help="displacement degree")
    parser.add_argument("--friction", type=float, default=0.1, help="Coulomb's mu")
    parser.add_argument("--limits", action="store_true", help="the friction limits per size")
    parser.add_argument("--write", action="store_true", help="write bench/results/")
    parser.add_argument("--name", default="sphere_friction", help="stem of the results")
    args = parser.parse_args()
    start = time.perf_counter()
    reference, report = solved(args.reference, args.degree, "coulomb", friction=args.friction)
    ref = {
        "n": args.reference,
        "dofs": reference.space.dof_counts().total,
        "newton": report.iterations,
        "stick": stick_fraction(reference),
        "time_s": time.perf_counter() - start,
    }
    print(
        f"reference P{args.degree} n={args.reference}: {ref['dofs']} dofs, stick fraction "
        f"{ref['stick']:.4f}, {report.iterations} Newton iterations, {ref['time_s']:.1f} s",
        flush=True,
    )
    rows = []
    for n in args.sizes:
        start = time.perf_counter()
        coulomb, report = solved(n, args.degree, "coulomb", friction=args.friction)
        row = {
            "n": n,
            "dofs": coulomb.space.dof_counts().total,
            "newton": report.iterations,
            "stick": stick_fraction(coulomb),
        }
        for part, key in (
            ("all", "multiplier"),
            ("normal", "normal"),
            ("tangential", "tangential"),
        ):
            row[key] = multiplier_difference(coulomb, reference, part)
        row["time_s"] = time.perf_counter() - start
        text = ""
        if args.limits:
            limits = {}
            for mu, law in ((0.0, "frictionless"), (1e3, "sticking")):
                a, _ = solved(n, args.degree, "coulomb", friction=mu)
                b, _ = solved(n, args.degree, law)
                limits[law] = limit_difference(a, b)
            row["limits"] = limits
            text = (
                f"; lambda_n mu=0 vs frictionless {limits['frictionless']:.2e}, mu=1e3 vs "
                f"sticking {limits['sticking']:.2e}"
            )
        rows.append(row)
        print(
            f"P{args.degree} n={n} mu={args.friction:g}: {row['newton']} Newton iterations, "
            f"stick fraction {row['stick']:.4f} (reference - this: "
            f"{ref['stick'] - row['stick']:+.4f}), multiplier difference "
            f"{row['multiplier']:.3e} (normal {row['normal']:.3e}, tangential "
            f"{row['tangential']:.3e}){text}; {row['time_s']:.1f} s",
            flush=True,
        )
    ref["peak_rss_mb"] = peak_rss_mb()
    for key in ("multiplier", "normal", "tangential"):
        print(f"rates of the {key} difference: {[round(r, 2) for r in rates(rows, key)]}")
    print(f"peak RSS {ref['peak_rss_mb']:.0f} MB")
    if args.write:
        passed = [a for a in sys.argv[1:] if a != "--write"]
        command = " ".join(["python bench/sphere_friction.py", *passed, "--write"])
        stem = RESULTS / args.name
        stem.with_suffix(".json").write_text(
            json.dumps({"command": command, "reference": ref, "rows": rows}, indent=1) + "\n"
        )
        stem.with_suffix(".md").write_text(markdown(ref, rows, command, args))


if __name__ == "__main__":
    main()
