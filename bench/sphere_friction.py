"""Coulomb friction on the sphere under triaxial compression: part of the interface
slips. The stick area and the multiplier converge to those of the finest mesh; the
friction limits are the frictionless (mu = 0) and the sticking (mu large) solutions.

Sphere R = 0.2 (quadric level set) in the unit cube, diag(-1, -2, -3) Pa, mu = 0.1 by
default; the three spins of the ball are held at mesh nodes on its axes for every law
(the frictionless ball has no other hold on them). Per size: Newton iterations, the
stick area fraction and its difference to the reference's, the relative L2 difference
of the Cartesian multiplier to the reference's (read at this mesh's interface points),
and the relative max difference of ``lambda_n`` between Coulomb with mu = 0 and the
frictionless law, and with mu = 1e3 and the sticking law. Serial.
Run: ``python bench/sphere_friction.py [--sizes 4 6 8] [--reference 12] [--degree 1]
[--friction 0.1]``.
"""

import argparse
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np

from xfem_contact.cases.solid import hold_spins, sphere_problem
from xfem_contact.cases.sphere_interface import multiplier_difference, stick_fraction


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 6, 8], help="cells per edge")
    parser.add_argument("--reference", type=int, default=12, help="the finest mesh's n")
    parser.add_argument("--degree", type=int, default=1, help="displacement degree")
    parser.add_argument("--friction", type=float, default=0.1, help="Coulomb's mu")
    args = parser.parse_args()
    start = time.perf_counter()
    reference, report = solved(args.reference, args.degree, "coulomb", friction=args.friction)
    stick_ref = stick_fraction(reference)
    print(
        f"reference P{args.degree} n={args.reference}: stick fraction {stick_ref:.4f}, "
        f"{report.iterations} Newton iterations, {time.perf_counter() - start:.1f} s",
        flush=True,
    )
    for n in args.sizes:
        start = time.perf_counter()
        coulomb, report = solved(n, args.degree, "coulomb", friction=args.friction)
        stick = stick_fraction(coulomb)
        difference = multiplier_difference(coulomb, reference)
        limits = {}
        for mu, law in ((0.0, "frictionless"), (1e3, "sticking")):
            a, _ = solved(n, args.degree, "coulomb", friction=mu)
            b, _ = solved(n, args.degree, law)
            limits[law] = limit_difference(a, b)
        print(
            f"P{args.degree} n={n} mu={args.friction:g}: {report.iterations} Newton "
            f"iterations, stick fraction {stick:.4f} (reference - this: "
            f"{stick_ref - stick:+.4f}), multiplier difference {difference:.3e}; "
            f"lambda_n mu=0 vs frictionless {limits['frictionless']:.2e}, mu=1e3 vs "
            f"sticking {limits['sticking']:.2e}; {time.perf_counter() - start:.1f} s",
            flush=True,
        )


if __name__ == "__main__":
    main()
