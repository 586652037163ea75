"""The contact pressure's oscillation on a sphere with and without the LBB treatment:
the concentric spheres in frictionless contact (uniform exact pressure) and the
sticking sphere under triaxial compression, with the stabilised default, the vital-vertex
restriction and ``lbb="none"``.

Concentric spheres: ``R int |grad_Gamma lambda_n| dA / (|p| 4 pi R^2)`` (0 for the
exact pressure) and the pressure error; sticking sphere: the surface total variation of
``lambda_n`` over the exact pressure's (1 for the exact one) and the pressure error.
Run: ``python bench/sphere_oscillation.py [--sizes 4 8] [--degrees 1 2] [--lbb none]``.
"""

import argparse
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.solid import (
    COMPOSITE_RADIUS,
    TRIAXIAL,
    composite_sphere_pressure,
    composite_sphere_problem,
    composite_sphere_traction_errors,
    sphere_errors,
    sphere_problem,
)
from xfem_contact.cases.sphere_interface import (
    exact_surface_total_variation,
    pressure_oscillation,
    surface_total_variation,
)

TREATMENTS = ("stabilized", "restriction", "none")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8], help="cells per edge")
    parser.add_argument("--degrees", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--lbb", nargs="+", choices=TREATMENTS, default=list(TREATMENTS))
    args = parser.parse_args()
    rank = MPI.COMM_WORLD.rank
    for degree in args.degrees:
        for n in args.sizes:
            for lbb in args.lbb:
                start = time.perf_counter()
                problem = composite_sphere_problem(n, degree, "frictionless", lbb=lbb)
                report = problem.solve()
                index = pressure_oscillation(problem, composite_sphere_pressure(), COMPOSITE_RADIUS)
                e_n, _ = composite_sphere_traction_errors(problem)
                if rank == 0:
                    print(
                        f"concentric spheres frictionless P{degree} n={n} lbb={lbb}: "
                        f"oscillation {index:.3f}, pressure error {e_n:.3e}, "
                        f"{report.iterations} Newton iterations, "
                        f"{time.perf_counter() - start:.1f} s",
                        flush=True,
                    )
                start = time.perf_counter()
                problem = sphere_problem(n, degree, "sticking", levelset="quadric", lbb=lbb)
                report = problem.solve()
                ratio = surface_total_variation(problem) / exact_surface_total_variation(
                    problem, np.diag(TRIAXIAL)
                )
                e_n, _ = sphere_errors(problem)
                if rank == 0:
                    print(
                        f"sticking sphere triaxial P{degree} n={n} lbb={lbb}: total variation "
                        f"/ exact {ratio:.5f}, pressure error {e_n:.3e}, "
                        f"{report.iterations} Newton iterations, "
                        f"{time.perf_counter() - start:.1f} s",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
