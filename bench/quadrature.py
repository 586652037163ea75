"""Cost of cut-cell integration against plain DOLFINx assembly (issue: foundation).

For a disc on N x N quadrilateral meshes: time to cut + build rules (CutMesh),
time to bind the compiled form to the rules (tabulating runtime tables), time to
assemble a P2 vector-elasticity matrix over both sides, and the ratio of
(cut + rules + tables + assembly) to the plain DOLFINx assembly of the same
matrix on the same mesh, all measured in this run; one-time compilation is
excluded (both forms are compiled on a small mesh first).

Run: ``python bench/quadrature.py [--sizes 32 64 128 256 512] [--json out.json]``.
"""

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import argparse
import json
import time

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI


def levelset(x):
    return np.hypot(x[0] - 0.51, x[1] - 0.47) - 0.3


def elasticity(V, dx):
    """P2 vector-elasticity bilinear form over the measure ``dx``."""
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = ufl.sym(ufl.grad(u))
    return (2.0 * ufl.inner(eps, ufl.sym(ufl.grad(v))) + ufl.div(u) * ufl.div(v)) * dx


def best_of(repeats, fn):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def run(n, repeats):
    comm = MPI.COMM_WORLD
    mesh = dolfinx.mesh.create_unit_square(comm, n, n, dolfinx.mesh.CellType.quadrilateral)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    plain_form = dolfinx.fem.form(elasticity(V, ufl.dx))
    t_plain, _ = best_of(repeats, lambda: dolfinx.fem.petsc.assemble_matrix(plain_form).destroy())
    t_cut, cut = best_of(repeats, lambda: xfem_contact.CutMesh(mesh, levelset, degree=2))
    ufl_form = elasticity(V, cut.dx(-1)) + elasticity(V, cut.dx(1))
    t_form, form = best_of(repeats, lambda: xfem_contact.form(ufl_form))
    t_asm, _ = best_of(repeats, lambda: dolfinx.fem.petsc.assemble_matrix(form).destroy())
    ncut = comm.allreduce(cut.cut_cells.size)
    return {
        "N": n,
        "cells": comm.allreduce(mesh.topology.index_map(2).size_local),
        "cut_cells": ncut,
        "cut_and_rules_s": t_cut,
        "form_and_tables_s": t_form,
        "assembly_cut_s": t_asm,
        "assembly_plain_s": t_plain,
        "per_cut_cell_us": 1e6 * (t_cut + t_form) / max(ncut, 1),
        "ratio": (t_cut + t_form + t_asm) / t_plain,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[32, 64, 128, 256, 512])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", type=str, default=None)
    args = parser.parse_args()
    run(8, 1)  # compile both forms once, outside the timings
    rows = []
    header = (
        f"{'N':>5} {'cells':>7} {'cut':>6} {'cut+rules':>10} {'form+tab':>9} "
        f"{'asm cut':>8} {'asm plain':>9} {'us/cut cell':>11} {'ratio':>6}"
    )
    if MPI.COMM_WORLD.rank == 0:
        print(header)
    for n in args.sizes:
        r = run(n, args.repeats)
        rows.append(r)
        if MPI.COMM_WORLD.rank == 0:
            print(
                f"{r['N']:5d} {r['cells']:7d} {r['cut_cells']:6d} {r['cut_and_rules_s']:10.4f} "
                f"{r['form_and_tables_s']:9.4f} {r['assembly_cut_s']:8.4f} "
                f"{r['assembly_plain_s']:9.4f} {r['per_cut_cell_us']:11.1f} {r['ratio']:6.2f}",
                flush=True,
            )
    if args.json and MPI.COMM_WORLD.rank == 0:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=2)


if __name__ == "__main__":
    main()
