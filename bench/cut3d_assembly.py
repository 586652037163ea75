"""Assembly cost of cut 3D forms against stock DOLFINx, in the same run.

The matrix of a vector Laplacian (P2 on tetrahedra, Q2 on hexahedra) over both sides of a
sphere (R = 0.3, centred in the unit cube, degree-2 level set) plus an interface mass
term, assembled through the runtime rules (``cut.dx(-1) + cut.dx(+1)`` and
``cut.dGamma``), against stock DOLFINx's assembly of the Laplacian on the uncut mesh with
``ufl.dx``. Both forms are compiled first; the times are the best of ``--repeat``
assemblies into an existing matrix. Also printed: the cut (level set, classification and
rules), the number of cut cells, the points per cut cell of the rules the cut form
integrates with, the time of the form's rule compression (``CutMesh``'s ``compression``,
on by default for P2 and affine P1 tetrahedra: the sides' rules of the stiffness's degree
2; the interface mass's degree 4 keeps the full rules on P2 tetrahedra and gets the
planar cut's degree-4 rules on P1 ones), and the relative errors of the sphere's volume
and area (how much the rules' degree buys)::

    python bench/cut3d_assembly.py --sizes 16 --degrees 1 2 --quadrature-degrees 2 6

(``P2`` in the table means Q2 on hexahedra; ``--compression on/off`` forces it on
tetrahedra.)
"""

from __future__ import annotations

import argparse
import time

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import dolfinx.common
import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact import CutMesh
from xfem_contact.fem.forms import integrand_degree

R = 0.3


def sphere(x: np.ndarray) -> np.ndarray:
    return np.sqrt(((x - 0.5) ** 2).sum(axis=0)) - R


def best_time(assemble, repeat: int) -> float:
    """The shortest wall time (s) of ``repeat`` calls, the slowest rank's."""
    times = []
    for _ in range(repeat):
        MPI.COMM_WORLD.Barrier()
        start = time.perf_counter()
        assemble()
        times.append(MPI.COMM_WORLD.allreduce(time.perf_counter() - start, op=MPI.MAX))
    return min(times)


def run(
    cell: str, n: int, degree: int, q: int, repeat: int, compression: bool | None
) -> dict[str, float]:
    """Times (s) of the cut, of the cut and the stock assembly, their ratio and the
    sphere's errors, for a level set of ``degree`` and rules of ``quadrature_degree=q``."""
    comm = MPI.COMM_WORLD
    mesh = dolfinx.mesh.create_unit_cube(comm, n, n, n, dolfinx.mesh.CellType[cell])
    start = time.perf_counter()
    if cell == "hexahedron":
        compression = False
    cut = CutMesh(mesh, sphere, degree=degree, quadrature_degree=q, compression=compression)
    cut_time = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    stiffness = ufl.inner(ufl.grad(u), ufl.grad(v))
    cut_form = stiffness * cut.dx(-1) + stiffness * cut.dx(1) + ufl.inner(u, v) * cut.dGamma
    compressed_before = _compression_seconds()
    forms = {"cut": xfem_contact.form(cut_form), "stock": dolfinx.fem.form(stiffness * ufl.dx)}
    compression_time = comm.allreduce(_compression_seconds() - compressed_before, op=MPI.MAX)
    times = {}
    for name, form in forms.items():
        A = dolfinx.fem.create_matrix(form)

        def assemble(A=A, form=form):
            A.set_value(0.0)
            dolfinx.fem.assemble_matrix(A, form)
            A.scatter_reverse()

        times[name] = best_time(assemble, repeat)
    dofs = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    one = dolfinx.fem.Constant(mesh, 1.0)
    volume, area = (
        comm.allreduce(dolfinx.fem.assemble_scalar(xfem_contact.form(one * m)))
        for m in (cut.dx(-1), cut.dGamma)
    )
    return {
        "cells": mesh.topology.index_map(3).size_global,
        "cut cells": cut.num_cut_cells_global,
        "points per cut cell": _points_per_cut_cell(cut, cut_form),
        "dofs": dofs,
        "cut (s)": cut_time,
        "compression (s)": compression_time,
        "cut assembly (s)": times["cut"],
        "stock assembly (s)": times["stock"],
        "ratio": times["cut"] / times["stock"],
        "volume error": abs(volume / (4 / 3 * np.pi * R**3) - 1),
        "area error": abs(area / (4 * np.pi * R**2) - 1),
    }


def _compression_seconds() -> float:
    """Wall time (s) of this process's rule compressions so far."""
    try:
        return dolfinx.common.timing("xfem_contact: rule compression")[1].total_seconds()
    except RuntimeError:  # none yet
        return 0.0


def _points_per_cut_cell(cut: CutMesh, cut_form: ufl.Form) -> float:
    """Mean number of points per cut cell of the runtime rules the integrals of
    ``cut_form`` (both sides, interface) integrate with."""
    points = 0
    for integral in cut_form.integrals():
        parts = cut.integration_parts(integral.subdomain_id(), integrand_degree(integral))
        points += sum(part.rules.num_points for part in parts if part.rules is not None)
    return cut.mesh.comm.allreduce(points) / max(cut.num_cut_cells_global, 1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--cells", nargs="+", default=["tetrahedron", "hexahedron"], help="cell kinds"
    )
    parser.add_argument("--sizes", nargs="+", type=int, default=[8, 16], help="cubes per side")
    parser.add_argument("--degrees", nargs="+", type=int, default=[1, 2], help="level set")
    parser.add_argument(
        "--quadrature-degrees", nargs="+", type=int, default=[2, 6], help="CutMesh rules"
    )
    parser.add_argument("--repeat", type=int, default=5, help="assemblies per form")
    parser.add_argument(
        "--compression",
        choices=["default", "on", "off"],
        default="default",
        help="CutMesh's rule compression on tetrahedra (hexahedra: off)",
    )
    args = parser.parse_args()
    if MPI.COMM_WORLD.rank == 0:
        print(f"ranks: {MPI.COMM_WORLD.size}")
    header = False
    for cell in args.cells:
        for degree in args.degrees:
            for q in args.quadrature_degrees:
                for n in args.sizes:
                    compression = {"default": None, "on": True, "off": False}[args.compression]
                    row = run(cell, n, degree, q, args.repeat, compression)
                    if MPI.COMM_WORLD.rank:
                        continue
                    if not header:
                        keys = ["cell", "level set", "q", "n", *row]
                        print("| " + " | ".join(keys) + " |")
                        print("| --- " * len(keys) + "|")
                        header = True
                    values = [f"{v:.3g}" if isinstance(v, float) else str(v) for v in row.values()]
                    print(
                        f"| {cell} | P{degree} | {q} | {n} | " + " | ".join(values) + " |",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
