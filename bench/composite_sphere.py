"""A ball of another material in the unit cube under hydrostatic compression, the cube
held by the exact composite-sphere field (3D Lame): the displacement errors of both
sides and the interface pressure error, with their rates. With ``--law frictionless``
the two bodies are concentric spheres in contact (the exact field is the same: radial,
closed, no tangential traction; uniform contact pressure).

Run: ``python bench/composite_sphere.py [--sizes 4 8 12] [--degree 2] [--law bonded]
[--cell tetrahedron] [--levelset quadric|distance]``; prints one row per size (dofs,
Newton iterations, time).
"""

import argparse
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.solid import (
    composite_sphere_errors,
    composite_sphere_problem,
    composite_sphere_traction_errors,
)


def rates(sizes, errors) -> list[float]:
    """Observed orders between consecutive sizes."""
    n, e = np.asarray(sizes, dtype=float), np.asarray(errors, dtype=float)
    return np.round(-np.diff(np.log(e)) / np.diff(np.log(n)), 2).tolist()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8, 12], help="cells per edge")
    parser.add_argument("--degree", type=int, default=2, help="displacement degree")
    parser.add_argument("--law", default="bonded", help="bonded, frictionless, sticking, ...")
    parser.add_argument("--cell", default="tetrahedron", help="tetrahedron or hexahedron")
    parser.add_argument(
        "--levelset",
        default="quadric",
        choices=["distance", "quadric"],
        help="the sphere's level set: the quadric P2 holds exactly, or the signed distance",
    )
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    rows = []
    for n in args.sizes:
        start = time.perf_counter()
        problem = composite_sphere_problem(
            n, args.degree, args.law, args.cell, comm, levelset=args.levelset
        )
        report = problem.solve()
        errors = composite_sphere_errors(problem)
        e_n, e_t = composite_sphere_traction_errors(problem)
        elapsed = time.perf_counter() - start
        W = problem.space.W
        dofs = W.dofmap.index_map.size_global * W.dofmap.index_map_bs
        rows.append((n, errors[-1], errors[1], e_n))
        if comm.rank == 0:
            print(
                f"{args.law} {args.cell} P{args.degree} n={n}: displacement L2 errors "
                f"inside {errors[-1]:.3e}, outside {errors[1]:.3e}; pressure {e_n:.3e}, "
                f"tangential {e_t:.3e}; {dofs} dofs (with inactive), "
                f"{getattr(report, 'iterations', 1)} Newton iterations, {elapsed:.1f} s",
                flush=True,
            )
    if comm.rank == 0 and len(rows) > 1:
        sizes, inside, outside, pressure = zip(*rows, strict=True)
        print(
            f"rates: inside {rates(sizes, inside)}, outside {rates(sizes, outside)}, "
            f"pressure {rates(sizes, pressure)}"
        )


if __name__ == "__main__":
    main()
