"""P2-P1 against P2-P2: what the P2 multiplier (``multiplier_degree=2``) buys, and at
what cost, on the paper's cases with exact solutions.

- **Case 2** (sticking inclusion under the paper's biaxial compression; uniform stress,
  the exact contact pressure ``n.sigma.n`` and tangential traction ``t.sigma.n`` are on
  the circle the traces of quadratic polynomials): relative L2 errors of both and their
  rates, quadrilaterals and triangles, the stabilised and the restricted multiplier, the
  circle by its signed distance (the paper's; its P2 interpolant holds the circle to
  O(h^3)) and by the quadric ``(|x - c|^2 - R^2) / (2 R)`` (held exactly by P2).
- **Case 3 turned by 1 rad** (large sliding, P2 curved cells, 4 load steps): the contact
  pressure's error against the same bulk model's exact (uniform) pressure and its
  oscillation ``(max - min) / |p|``.
- **The closed frictional crack** (Coulomb 0.3, inclined at pi/4 to a remote compression
  of 1 Pa; the lips' exact traction is uniform: ``sigma_n = -0.5`` Pa,
  ``|tau| = 0.15`` Pa where they slide): the lips' traction errors (RMS over the rule
  points, relative to ``|sigma_n|``) and the slip's relative L2 error, with the crack's
  restriction.

Each row: the reduced unknowns (the system solved: active dofs, the restriction's
multiplier unknowns) and the multiplier's share, Newton iterations and the wall time of
set-up and solve (s; the first P2-multiplier run of a kind compiles its kernels).

Run: ``python bench/multiplier_degree.py [--sizes 10 20 40 80] [--annulus 10 20 40]
[--crack 8 16]``; writes ``bench/results/multiplier_degree.{json,md}``.
"""

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import argparse
import json
import math
import pathlib
import time

import numpy as np
from mpi4py import MPI

from xfem_contact.cases.cracks import frictional_crack_case, frictional_slip
from xfem_contact.cases.paper import inclusion_errors, inclusion_problem
from xfem_contact.cases.rotation import pressure_errors, rotating_annulus_problem
from xfem_contact.io.progress import note

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
#: The frictional crack's frame (:func:`frictional_crack_case`'s defaults)
CRACK_CENTRE, CRACK_ANGLE = np.array([0.0123, 0.0271]), 0.3


def unknowns(problem) -> tuple[int, int]:
    """The reduced system's size and its multiplier unknowns (collective)."""
    R = problem.prolongation()
    total = R.getSize()[1]
    R.destroy()
    counts = problem.space.dof_counts()
    return total, total - counts.standard - counts.enriched


def case2(sizes, say) -> list[dict]:
    rows = []
    for levelset in ("distance", "quadric"):
        for cell in ("quadrilateral", "triangle"):
            for lbb in ("stabilized", "restriction"):
                for multiplier in (1, 2):
                    for n in sizes:
                        start = time.perf_counter()
                        problem = inclusion_problem(
                            n,
                            2,
                            "sticking",
                            cell,
                            levelset=levelset,
                            lbb=lbb,
                            multiplier_degree=multiplier,
                        )
                        report = problem.solve()
                        errors = inclusion_errors(problem, problem.w)
                        total, lam = unknowns(problem)
                        row = {
                            "case": "2",
                            "levelset": levelset,
                            "cell": cell,
                            "lbb": lbb,
                            "element": f"P2-P{multiplier}",
                            "n": n,
                            "unknowns": total,
                            "multiplier_unknowns": lam,
                            "pressure_error": errors.pressure,
                            "tangential_error": errors.tangential,
                            "newton": report.iterations,
                            "time_s": time.perf_counter() - start,
                        }
                        rows.append(row)
                        say(
                            f"case 2 {levelset:8s} {cell:13s} {lbb:11s} {row['element']} n={n:3d}: "
                            f"pressure {errors.pressure:.3e}, tangential {errors.tangential:.3e}, "
                            f"{total} unknowns ({lam} multiplier), {row['time_s']:.1f} s"
                        )
    return rows


def case3(sizes, say) -> list[dict]:
    rows = []
    for multiplier in (1, 2):
        for n in sizes:
            start = time.perf_counter()
            problem = rotating_annulus_problem(n, 2, 1.0, multiplier_degree=multiplier)
            iterations = []
            for k in range(1, 5):
                problem.loads.set_time(k / 4)
                iterations.append(problem.solve().iterations)
                problem.accept_step()
            measures = pressure_errors(problem)
            total, lam = unknowns(problem)
            row = {
                "case": "3, 1 rad",
                "element": f"P2-P{multiplier}",
                "n": n,
                "unknowns": total,
                "multiplier_unknowns": lam,
                "pressure_error": measures["error"],
                "oscillation": measures["oscillation"],
                "newton": iterations,
                "time_s": time.perf_counter() - start,
            }
            rows.append(row)
            say(
                f"case 3 1 rad P2-P{multiplier} n={n:3d}: pressure {row['pressure_error']:.3e}, "
                f"oscillation {row['oscillation']:.2e}, {total} unknowns ({lam} multiplier), "
                f"{row['time_s']:.1f} s"
            )
    return rows


def crack(sizes, say) -> list[dict]:
    rows = []
    for multiplier in (1, 2):
        for N in sizes:
            start = time.perf_counter()
            case = frictional_crack_case(
                N, 2, friction=0.3, tip_radius=0.3, multiplier_degree=multiplier
            )
            report = case.problem.solve()
            samples = case.problem.interface_samples(case.problem.w)
            d = np.array([math.cos(CRACK_ANGLE), math.sin(CRACK_ANGLE)])
            s = (np.asarray(samples["x"]) - CRACK_CENTRE[0]) * d[0]
            s += (np.asarray(samples["y"]) - CRACK_CENTRE[1]) * d[1]
            slip, _ = frictional_slip(s)
            slip_error = np.linalg.norm(-np.asarray(samples["slip"]) - slip) / np.linalg.norm(slip)
            lam_n, lam_t = (np.asarray(samples[k]) for k in ("lambda_n", "lambda_t"))
            sigma_n, tau = -0.5, 0.3 * 0.5
            sliding = np.abs(slip) > 0
            total, lam = unknowns(case.problem)
            row = {
                "case": "frictional crack",
                "element": f"P2-P{multiplier}",
                "n": N,
                "unknowns": total,
                "multiplier_unknowns": lam,
                "normal_error": float(np.sqrt(np.mean((lam_n - sigma_n) ** 2)) / abs(sigma_n)),
                "tangential_error": float(
                    np.sqrt(np.mean((np.abs(lam_t[sliding]) - tau) ** 2)) / abs(sigma_n)
                ),
                "slip_error": float(slip_error),
                "newton": report.iterations,
                "time_s": time.perf_counter() - start,
            }
            rows.append(row)
            say(
                f"crack P2-P{multiplier} h=a/{N}: sigma_n {row['normal_error']:.3e}, tau "
                f"{row['tangential_error']:.3e}, slip {slip_error:.3e}, {total} unknowns "
                f"({lam} multiplier), {row['time_s']:.1f} s"
            )
    return rows


def rate(rows: list[dict], row: dict, key: str) -> str:
    """Observed rate of ``key`` from the previous mesh of the same series."""
    same = [r for r in rows if all(r.get(k) == row.get(k) for k in SERIES) and r["n"] < row["n"]]
    if not same:
        return ""
    previous = max(same, key=lambda r: r["n"])
    if previous[key] <= 0 or row[key] <= 0:
        return ""
    return f" ({math.log(previous[key] / row[key]) / math.log(row['n'] / previous['n']):.2f})"


SERIES = ("case", "levelset", "cell", "lbb", "element")


def table(rows: list[dict], columns: dict[str, str], errors: tuple[str, ...]) -> list[str]:
    """Markdown lines: ``columns`` (key: heading) then each error with its rate."""
    head = list(columns.values()) + [f"{e} (rate)" for e in errors]
    head += ["unknowns (multiplier)", "Newton", "time (s)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [str(row.get(k, "")) for k in columns]
        cells += [f"{row[e]:.2e}{rate(rows, row, e)}" for e in errors]
        cells += [f"{row['unknowns']} ({row['multiplier_unknowns']})", str(row["newton"])]
        cells += [f"{row['time_s']:.1f}"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[10, 20, 40, 80], help="case 2")
    parser.add_argument("--annulus", type=int, nargs="*", default=[10, 20, 40], help="case 3")
    parser.add_argument("--crack", type=int, nargs="*", default=[8, 16], help="a / h")
    args = parser.parse_args()
    root = MPI.COMM_WORLD.rank == 0

    def say(message: str) -> None:
        if root:
            note(message)

    two, three, cracked = case2(args.sizes, say), case3(args.annulus, say), crack(args.crack, say)
    lines = ["Case 2, sticking, P2 displacement:", ""]
    lines += table(
        two,
        {"levelset": "circle", "cell": "cell", "lbb": "lbb", "element": "element", "n": "n"},
        ("pressure_error", "tangential_error"),
    )
    lines += ["", "Case 3 turned by 1 rad (large sliding, 4 steps), n x 4n curved cells:", ""]
    lines += table(three, {"element": "element", "n": "n"}, ("pressure_error", "oscillation"))
    lines += ["", "Closed frictional crack (restriction), h = a / n:", ""]
    lines += table(
        cracked,
        {"element": "element", "n": "n"},
        ("normal_error", "tangential_error", "slip_error"),
    )
    if root:
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / "multiplier_degree.md").write_text("\n".join(lines) + "\n")
        data = {"rows": two + three + cracked, "args": vars(args)}
        (RESULTS / "multiplier_degree.json").write_text(json.dumps(data, indent=1))
        print("\n".join(lines))
        print(f"wrote {RESULTS / 'multiplier_degree.md'} and .json")


if __name__ == "__main__":
    main()
