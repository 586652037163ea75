"""The sticking sphere of ``bench/sphere_triaxial.py`` on unstructured tetrahedra: the
unit cube meshed by gmsh (:func:`xfem_contact.cases.solid.unstructured_cube`, a node at
each face's centre for the point constraints), the pressure error of the multiplier
against the exact ``n.sigma.n`` for each LBB treatment, with its rates in the cell size.

Run: ``python bench/sphere_unstructured.py [--sizes 0.15 0.12 0.1 0.085 0.07 0.06]
[--degree 2] [--treatments stabilized restriction] [--levelset distance|quadric]
[--no-solve] [--inf-sup] [--name NAME]``; prints one row per treatment and size (cells,
reduced unknowns, time) and the table; writes ``bench/results/<name>.{md,json}``
(default ``sphere_unstructured``).

Beside the solution's pressure error, the best one the multiplier space holds (the L2
projection of the exact traction on the interface, one process): the space's
approximation apart from the pair's stability; with ``--inf-sup`` the inf-sup constant
of the bonded sphere's pair (:func:`xfem_contact.mechanics.inf_sup.inf_sup_constant`).
Single unstructured meshes scatter: the rates between consecutive sizes vary, the table
adds the least-squares rate over all of them.
"""

import argparse
import json
import pathlib
import shlex
import sys
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from mpi4py import MPI

from xfem_contact.cases.solid import (
    SPHERE_CENTRE,
    sphere_errors,
    sphere_problem,
    unstructured_cube,
)
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.inf_sup import inf_sup_constant
from xfem_contact.mechanics.laws.multiplier import LBB_OPTIONS

RESULTS = pathlib.Path(__file__).resolve().parent / "results"


def best_pressure_error(problem) -> float:
    """The pressure error (as :func:`sphere_errors`) of the L2(interface) projection of
    the exact traction ``sigma n`` on the problem's multiplier space (restricted with
    ``lbb="restriction"``): the multiplier space's approximation error alone. Serial;
    overwrites ``problem.w``."""
    import dolfinx.fem.petsc
    import ufl
    from petsc4py import PETSc

    if problem.mesh.comm.size > 1:
        raise ValueError("best_pressure_error runs on one process")
    (name,) = problem.laws
    law, ctx = problem.law(name), problem.contexts[name]
    lam, mu = problem.space.trial()[ctx.field], problem.space.test()[ctx.field]
    x = ufl.SpatialCoordinate(problem.mesh)
    arm = x - ufl.as_vector(SPHERE_CENTRE)
    n = arm / ufl.sqrt(ufl.dot(arm, arm))
    traction = ufl.dot(ufl.diag(ufl.as_vector(problem.stress)), n)
    M = dolfinx.fem.petsc.assemble_matrix(form(ufl.inner(lam, mu) * ctx.measure))
    M.assemble()
    b = dolfinx.fem.petsc.assemble_vector(form(ufl.inner(traction, mu) * ctx.measure))
    p = law.prolongation(ctx, problem.space)
    if p is None:  # the full multiplier space: the dofs the interface sees
        dofs = np.flatnonzero(M.getDiagonal().array > 0.0)
        rows, cols, vals, size = np.arange(dofs.size), np.arange(dofs.size), 1.0, dofs.size
    else:
        dofs, rows, cols, vals, size = p.dofs, p.rows, p.cols, p.vals, p.num_owned
    index = PETSc.IS().createGeneral(dofs.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
    Md = M.createSubMatrix(index, index)
    P = PETSc.Mat().createAIJ((dofs.size, size), comm=PETSc.COMM_SELF)
    P.setUp()
    for i, j, v in zip(rows, cols, np.broadcast_to(vals, rows.shape), strict=True):
        P.setValue(int(i), int(j), float(v), addv=True)
    P.assemble()
    A = Md.PtAP(P)
    rhs, y = P.createVecRight(), P.createVecRight()
    P.multTranspose(PETSc.Vec().createWithArray(b.array[dofs].copy()), rhs)
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.solve(rhs, y)
    values = P.createVecLeft()
    P.mult(y, values)
    problem.w.x.array[:] = 0.0
    problem.w.x.array[dofs] = values.array
    for obj in (M, b, index, Md, P, A, rhs, y, ksp, values):
        obj.destroy()
    return sphere_errors(problem)[0]


def run(
    h: float, degree: int, lbb: str, levelset: str, comm, solve: bool = True, beta: bool = False
) -> dict:
    """One solve (if ``solve``) of the sticking sphere on the gmsh cube of size ``h``: its
    errors and counts; with ``beta`` the inf-sup constant of the bonded sphere's pair."""
    start = time.perf_counter()
    mesh = unstructured_cube(h, comm)
    inf_sup = float("nan")
    if beta:
        bonded = sphere_problem(
            None, degree, "bonded", comm=comm, levelset=levelset, mesh=mesh, lbb=lbb
        )
        inf_sup = inf_sup_constant(bonded).beta
    problem = sphere_problem(
        None, degree, "sticking", comm=comm, levelset=levelset, mesh=mesh, lbb=lbb
    )
    e_n = e_t = float("nan")
    report = None
    if solve:
        report = problem.solve()
        e_n, e_t = sphere_errors(problem)
    R = problem.prolongation()
    unknowns = R.getSize()[1]
    R.destroy()
    best = best_pressure_error(problem) if comm.size == 1 else float("nan")
    return {
        "h": h,
        "lbb": lbb,
        "cells": mesh.topology.index_map(3).size_global,
        "unknowns": unknowns,
        "pressure": e_n,
        "tangential": e_t,
        "best": best,
        "beta": inf_sup,
        "newton": getattr(report, "iterations", 1) if solve else 0,
        "seconds": time.perf_counter() - start,
    }


def rates(rows: list[dict], key: str) -> tuple[np.ndarray, float]:
    """The rates of ``key`` in the cell size (``cells^(-1/3)``) between consecutive rows
    and the least-squares slope over all of them (single unstructured meshes scatter)."""
    e = np.array([r[key] for r in rows])
    h = np.array([r["cells"] for r in rows], dtype=float) ** (-1.0 / 3.0)
    slope = np.polyfit(np.log(h), np.log(e), 1)[0] if len(rows) > 1 else float("nan")
    return np.diff(np.log(e)) / np.diff(np.log(h)), float(slope)


def table(rows: list[dict], sizes: list[float]) -> list[str]:
    """Markdown: per treatment and error (the solution's pressure error, and the best
    the multiplier space holds) the values of each size, the rates and their fit."""
    lines = [
        "| lbb | quantity | "
        + " | ".join(f"h = {h}" for h in sizes)
        + " | rates (inf-sup: slope in log 1/h) | least-squares rate (slope) |",
        "|---|---|" + "---|" * len(sizes) + "---|---|",
    ]
    for label in dict.fromkeys(r["label"] for r in rows):
        sel = [r for r in rows if r["label"] == label]
        keys = ("pressure", "solution"), ("best", "best in the space"), ("beta", "inf-sup")
        for key, name in keys:
            if np.isnan([r[key] for r in sel]).all():
                continue
            pairs, fit = rates(sel, key)
            if key == "beta":  # the slope in log 1/h, as bench/inf_sup.py's in log n
                pairs, fit = -pairs, -fit
            cells = " | ".join(f"{r[key]:.3g} ({r['cells']} cells)" for r in sel)
            lines.append(
                f"| {label} | {name} | {cells} | {', '.join(f'{x:.2f}' for x in pairs)} "
                f"| {fit:.2f} |"
            )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sizes",
        type=float,
        nargs="+",
        default=[0.15, 0.12, 0.1, 0.085, 0.07, 0.06],
        help="gmsh sizes (m)",
    )
    parser.add_argument("--degree", type=int, default=2, help="displacement degree")
    parser.add_argument(
        "--treatments",
        nargs="+",
        default=["stabilized", "restriction"],
        choices=LBB_OPTIONS,
        help="LBB treatments",
    )
    parser.add_argument(
        "--levelset", default="distance", choices=["distance", "quadric"], help="the sphere's"
    )
    parser.add_argument(
        "--no-solve",
        action="store_true",
        help="only the best pressure error the multiplier space holds (no solve)",
    )
    parser.add_argument(
        "--inf-sup", action="store_true", help="the bonded pair's inf-sup constant too"
    )
    parser.add_argument("--name", default="sphere_unstructured", help="bench/results/NAME.*")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    rows = []
    for label in args.treatments:
        for h in args.sizes:
            rows.append(
                run(h, args.degree, label, args.levelset, comm, not args.no_solve, args.inf_sup)
            )
            rows[-1]["label"] = label
            r = rows[-1]
            if comm.rank == 0:
                print(
                    f"sticking P{args.degree}-P1 {label} h={h}: pressure error "
                    f"{r['pressure']:.3e} (best in the multiplier space {r['best']:.3e}), "
                    f"tangential {r['tangential']:.3e}, {r['cells']} cells, {r['unknowns']} "
                    f"reduced unknowns (all fields), {r['newton']} Newton iterations, "
                    f"inf-sup constant {r['beta']:.3f}, {r['seconds']:.1f} s",
                    flush=True,
                )
    if comm.rank == 0:
        command = shlex.join(["python", "bench/sphere_unstructured.py", *sys.argv[1:]])
        lines = [f"Command: `{command}`", "", *table(rows, args.sizes)]
        print("\n".join(lines))
        RESULTS.mkdir(exist_ok=True)
        (RESULTS / f"{args.name}.md").write_text("\n".join(lines) + "\n")
        (RESULTS / f"{args.name}.json").write_text(json.dumps({"rows": rows, "args": vars(args)}))


if __name__ == "__main__":
    main()
