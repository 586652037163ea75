"""Why Coulomb with mu = 0 and the frictionless law differ on the 3D sphere: two
discretisations of the same pressure, not a defect of either law.

In 3D the Coulomb (and sticking) multiplier is a Cartesian P1 vector ``lambda`` with
``lambda_n = lambda.n``, the frictionless one a P1 scalar ``lambda_n``: on a curved
interface ``lambda.n`` is another discrete pressure than a P1 scalar (in 2D both laws
store ``lambda_n`` as a component of the frame ``(n, t)``, the same space). Printed:

- the triaxial sphere (quadric level set, diag(-1, -2, -3) Pa, the spins held, no exact
  solution): the relative max and L2 difference of ``lambda_n`` of the two laws, with
  the Barbosa-Hughes stabilisation and with the vital-vertex restriction (no
  stabilisation term: if the difference came from the stabilisation's tangential
  part, it would vanish there);
- the concentric spheres (``composite_sphere_problem``: the exact pressure is uniform
  and the exact field has no tangential traction, the solution of both laws): each
  law's relative L2 pressure error against the exact one and their difference.

Serial. Run: ``python bench/friction_limits3d.py [--sizes 4 6 8 10] [--concentric 4 6 8]
[--degree 1] [--write [--name STEM]]``; ``--write`` writes
``bench/results/friction_limits3d.{json,md}``.
"""

import argparse
import json
import pathlib
import sys
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np

from xfem_contact.cases.solid import (
    composite_sphere_problem,
    composite_sphere_traction_errors,
    hold_spins,
    interface_rule,
    sphere_problem,
)

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
LAWS = (("coulomb", {"friction": 0.0}), ("frictionless", {}))


def differences(a, b) -> tuple[float, float]:
    """Relative max and L2 differences of ``lambda_n`` of two solved problems on one
    mesh (over the second's max and L2 norm; L2 by the interface rule)."""
    x, y = (p.interface_state(p.w)["lambda_n"] for p in (a, b))
    _, _, dA = interface_rule(b)
    largest = np.abs(x - y).max() / np.abs(y).max()
    return float(largest), float(np.sqrt(np.sum((x - y) ** 2 * dA) / np.sum(y**2 * dA)))


def triaxial(n: int, degree: int, lbb: str) -> dict:
    """The two laws on the triaxial sphere; their row."""
    start = time.perf_counter()
    solved, newton = [], []
    for law, options in LAWS:
        problem = sphere_problem(n, degree, law, levelset="quadric", lbb=lbb, **options)
        hold_spins(problem, 1.0 / (n * degree))
        newton.append(problem.solve().iterations)
        solved.append(problem)
    largest, l2 = differences(*solved)
    row = {"n": n, "lbb": lbb, "max": largest, "l2": l2, "newton": newton}
    return row | {"time_s": time.perf_counter() - start}


def concentric(n: int, degree: int) -> dict:
    """The two laws on the concentric spheres; their row."""
    start = time.perf_counter()
    solved, errors = [], []
    for law, options in LAWS:
        problem = composite_sphere_problem(n, degree, law, **options)
        problem.solve()
        solved.append(problem)
        errors.append(composite_sphere_traction_errors(problem)[0])
    largest, l2 = differences(*solved)
    row = {"n": n, "coulomb": errors[0], "frictionless": errors[1], "max": largest, "l2": l2}
    return row | {"time_s": time.perf_counter() - start}


def markdown(data: dict, degree: int) -> str:
    """The results page."""
    lines = [
        f"`{data['command']}` (P{degree} tetrahedra, multiplier P1; one process).",
        "",
        "Triaxial sphere (no exact solution): Coulomb mu = 0 against frictionless, "
        "`lambda_n` at the interface rule points.",
        "",
        "| n | lbb | max difference | L2 difference | Newton (mu = 0, frictionless) | time (s) |",
        "|---|---|---|---|---|---|",
    ]
    for r in data["triaxial"]:
        lines.append(
            f"| {r['n']} | {r['lbb']} | {r['max']:.2e} | {r['l2']:.2e} | "
            f"{r['newton'][0]}, {r['newton'][1]} | {r['time_s']:.1f} |"
        )
    lines += [
        "",
        "Concentric spheres (exact uniform pressure, the solution of both laws): relative L2 "
        "pressure errors and the two laws' difference.",
        "",
        "| n | Coulomb mu = 0 error | frictionless error | max difference | L2 difference | "
        "time (s) |",
        "|---|---|---|---|---|---|",
    ]
    for r in data["concentric"]:
        lines.append(
            f"| {r['n']} | {r['coulomb']:.3e} | {r['frictionless']:.3e} | {r['max']:.2e} | "
            f"{r['l2']:.2e} | {r['time_s']:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[4, 6, 8, 10])
    parser.add_argument("--lbb", nargs="+", default=["stabilized", "restriction"])
    parser.add_argument("--concentric", type=int, nargs="*", default=[4, 6, 8])
    parser.add_argument("--degree", type=int, default=1, help="displacement degree")
    parser.add_argument("--write", action="store_true", help="write bench/results/")
    parser.add_argument("--name", default="friction_limits3d", help="stem of the results")
    args = parser.parse_args()
    data = {"triaxial": [], "concentric": []}
    for lbb in args.lbb:
        for n in args.sizes:
            row = triaxial(n, args.degree, lbb)
            data["triaxial"].append(row)
            print(json.dumps(row), flush=True)
    for n in args.concentric:
        row = concentric(n, args.degree)
        data["concentric"].append(row)
        print(json.dumps(row), flush=True)
    if args.write:
        passed = [a for a in sys.argv[1:] if a != "--write"]
        data["command"] = " ".join(["python bench/friction_limits3d.py", *passed, "--write"])
        stem = RESULTS / args.name
        stem.with_suffix(".json").write_text(json.dumps(data, indent=1) + "\n")
        stem.with_suffix(".md").write_text(markdown(data, args.degree))


if __name__ == "__main__":
    main()
