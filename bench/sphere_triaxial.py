"""A sphere in the unit cube under triaxial compression (3D analogue of paper case 2):
the contact pressure and tangential traction errors of the multiplier against the exact
``sigma n`` (uniform stress ``diag(-1, -2, -3)`` Pa, one material), with their rates.

Run: ``python bench/sphere_triaxial.py [--sizes 4 8] [--degree 2] [--law sticking]
[--cell tetrahedron] [--levelset distance|quadric] [--multiplier-degree 2]
[--lbb restriction]``; prints one
row per size (dofs, Newton iterations, time).
"""

import argparse
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.solid import sphere_errors, sphere_problem
from xfem_contact.mechanics.laws.multiplier import LBB_OPTIONS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=[4, 8], help="cells per edge (even)"
    )
    parser.add_argument("--degree", type=int, default=2, help="displacement degree")
    parser.add_argument("--law", default="sticking", help="sticking, bonded, coulomb, ...")
    parser.add_argument("--cell", default="tetrahedron", help="tetrahedron or hexahedron")
    parser.add_argument("--friction", type=float, default=None, help="coulomb's mu")
    parser.add_argument(
        "--levelset",
        default="distance",
        choices=["distance", "quadric"],
        help="the sphere's level set: signed distance, or the quadric P2 holds exactly",
    )
    parser.add_argument(
        "--multiplier-degree", type=int, default=1, choices=[1, 2], help="of the multiplier"
    )
    parser.add_argument(
        "--lbb", default="stabilized", choices=LBB_OPTIONS, help="the LBB treatment"
    )
    args = parser.parse_args()
    options = {} if args.friction is None else {"friction": args.friction}
    options["multiplier_degree"] = args.multiplier_degree
    options["lbb"] = args.lbb
    comm = MPI.COMM_WORLD
    rows = []
    for n in args.sizes:
        start = time.perf_counter()
        problem = sphere_problem(
            n, args.degree, args.law, args.cell, comm, levelset=args.levelset, **options
        )
        report = problem.solve()
        e_n, e_t = sphere_errors(problem)
        elapsed = time.perf_counter() - start
        dofs = problem.space.W.dofmap.index_map.size_global * problem.space.W.dofmap.index_map_bs
        rows.append((n, e_n, e_t))
        if comm.rank == 0:
            print(
                f"{args.law} {args.cell} P{args.degree}-P{args.multiplier_degree} "
                f"lbb={args.lbb} n={n}: "
                f"pressure error {e_n:.3e}, "
                f"tangential {e_t:.3e}, {dofs} dofs (with inactive), "
                f"{getattr(report, 'iterations', 1)} Newton iterations, {elapsed:.1f} s",
                flush=True,
            )
    if comm.rank == 0 and len(rows) > 1:
        n, e_n, e_t = (np.array(c, dtype=float) for c in zip(*rows, strict=True))
        rate = -np.diff(np.log(e_n)) / np.diff(np.log(n))
        rate_t = -np.diff(np.log(e_t)) / np.diff(np.log(n))
        rates = np.round(rate, 2).tolist(), np.round(rate_t, 2).tolist()
        print(f"pressure rates {rates[0]}, tangential {rates[1]}")


if __name__ == "__main__":
    main()
