"""Moving interface: X-FEM re-cutting one mesh against gmsh remeshing, case 2, P2.

The inclusion of paper case 2 (two materials: inside 300 MPa, nu 0.2; outside 100 MPa,
nu 0, so the solution depends on where the inclusion is) is moved and resized over 10
positions: the centre on a line from (0.42, 0.46) to (0.58, 0.54) m, the radius from
0.15 to 0.25 m (a start position before them, solved untimed). Per mesh (n x n
quadrilaterals, h = 1/n) and law (sticking; Coulomb, friction 0.3, with ``accept_step``
after each solve):

- X-FEM: one problem built once; per position ``update_interface`` then ``solve``
  (timed together: cut, space, Newton set-up, Newton from the carried solution). A
  warm Newton that fails is recorded and the position solved again from zero without
  the history (``w = w_old = 0``), both attempts in its time.
- One solve of the same system (the baseline of the first ratio): a problem built at
  that position (``inclusion_problem`` moved there once, untimed: the same active dofs
  as a problem built there, ``tests/test_moving_interface.py``), its first ``solve``
  from zero (Newton set-up included), and a second from zero (Newton alone).
- Remeshing (the baseline of the second ratio): per position a gmsh mesh fitted to the
  circle (:func:`xfem_contact.cases.body_fitted.mesh_geo`, triangles of size h, P2
  geometry), the two materials on the two surfaces bonded (conforming nodes: the
  sticking-equivalent body-fitted solve; no body-fitted Coulomb solve exists, so the
  Coulomb rows are compared with it too), MUMPS LDL^T as the X-FEM sticking solve.
  Timed: meshing + mesh creation + forms + assembly + solve. One untimed warm-up
  solve per mesh first (JIT warm for both routes).

Run: ``python bench/moving_interface.py [--sizes 40 160] [--no-progress] [--json PATH]``;
writes ``bench/results/moving_interface.{json,md}`` (other sizes or positions: only
with ``--json``; ``--sizes 20`` is a quick check).
"""

import argparse
import json
import pathlib
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.cases.body_fitted import INCLUSION_GEO, mesh_geo
from xfem_contact.cases.paper import LOADINGS, inclusion_problem
from xfem_contact.fem.forms import form
from xfem_contact.io.progress import note, progress
from xfem_contact.mechanics.loads import Loads, PlainFields
from xfem_contact.mechanics.materials import Material
from xfem_contact.solvers.newton import NewtonFailure
from xfem_contact.solvers.options import defaults, remove_options, unique_prefix

RESULTS = pathlib.Path(__file__).parent / "results"
#: Inside (-1) and outside (1) materials
MATERIALS = {-1: Material(300e6, 0.2), 1: Material(100e6, 0.0)}
#: Laws and their options
LAWS = {"sticking": {}, "coulomb": {"friction": 0.3}}
POSITIONS = 10
#: Goals: per position / one solve, X-FEM / remeshing
GOALS = {"solve": 1.3, "remesh": 0.5}


def position(k: int, positions: int = POSITIONS) -> tuple[tuple[float, float], float]:
    """Centre (m) and radius (m) of position ``k`` (0 = the start, 1..positions timed)."""
    t = k / positions
    return (0.42 + 0.16 * t, 0.46 + 0.08 * t), 0.15 + 0.10 * t


def circle(centre, radius):
    cx, cy = centre
    return lambda x: np.hypot(x[0] - cx, x[1] - cy) - radius


def dofs(problem) -> int:
    return problem.space.dof_counts().total


def displacement(problem) -> np.ndarray:
    """A copy of both sides' displacement dofs of the solution (local, m)."""
    parents = [problem.space.field_space(i)[1] for i in (0, 1)]
    return problem.w.x.array[np.concatenate(parents)].copy()


# -- X-FEM ---------------------------------------------------------------------------------
def xfem_route(n: int, law: str, positions: int, log) -> list[dict]:
    """The problem built once and moved through the positions (warm starts)."""
    problem = inclusion_problem(n, 2, law, materials=MATERIALS, **LAWS[law])
    problem.update_interface(circle(*position(0, positions)))
    problem.solve()
    problem.accept_step()
    rows = []
    for k in range(1, positions + 1):
        centre, radius = position(k, positions)
        start = time.perf_counter()
        problem.update_interface(circle(centre, radius))
        update = time.perf_counter() - start
        row = {"k": k, "centre": centre, "radius": radius, "update_s": update}
        try:
            report = problem.solve()
        except NewtonFailure as failure:  # recorded; restart from zero, history dropped
            row["warm_failure"] = str(failure).splitlines()[0]
            row["failed_iterations"] = failure.report.iterations
            problem.w.x.array[:] = 0.0
            problem.w_old.x.array[:] = 0.0
            report = problem.solve()
        row["time_s"] = time.perf_counter() - start
        row["setup"] = problem.solver_timings
        row["newton_s"] = report.total_time
        row["iterations"] = report.iterations
        row["dofs"] = dofs(problem)
        row["_u"] = displacement(problem)
        problem.accept_step()
        rows.append(row)
        log(
            f"  xfem n={n} {law} k={k}: {row['time_s']:.3f} s (update {update:.3f}, "
            f"Newton {report.total_time:.3f}), {report.iterations} iterations"
        )
    return rows


def one_solve(n: int, law: str, centre, radius) -> dict:
    """A problem at that position solved from zero: its first solve (Newton set-up
    included) and a second one from zero (Newton alone)."""
    problem = inclusion_problem(n, 2, law, materials=MATERIALS, **LAWS[law])
    problem.update_interface(circle(centre, radius))
    out = {}
    for key in ("first", "again"):
        problem.w.x.array[:] = 0.0
        problem.w_old.x.array[:] = 0.0
        start = time.perf_counter()
        report = problem.solve()
        out[f"{key}_s"] = time.perf_counter() - start
        out["iterations"] = report.iterations
    out["dofs"] = dofs(problem)
    out["_u"] = displacement(problem)
    return out


# -- remeshing -----------------------------------------------------------------------------
def remeshed_solve(n: int, centre, radius, comm) -> dict:
    """Case 2 with the two materials on a gmsh mesh fitted to the circle (bonded), P2;
    wall times (s) of meshing (gmsh + mesh creation), forms and solve."""
    start = time.perf_counter()
    gm = mesh_geo(
        INCLUSION_GEO.format(h=1.0 / n, cx=centre[0], cy=centre[1], r=radius), 2, "triangle", comm
    )
    times = {"mesh_s": time.perf_counter() - start}
    start = time.perf_counter()
    mesh = gm.mesh
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    loads = Loads(PlainFields(V))
    sxx, syy = LOADINGS["paper"]
    loads.add_pressure(lambda x: np.isclose(x[0], 0.0) | np.isclose(x[0], 1.0), -sxx)
    loads.add_pressure(lambda x: np.isclose(x[1], 0.0) | np.isclose(x[1], 1.0), -syy)
    loads.add_point_displacement([0.5, 0.0], 0.0, 0)
    loads.add_point_displacement([0.5, 1.0], 0.0, 0)
    loads.add_point_displacement([0.0, 0.5], 0.0, 1)
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=gm.cell_tags)
    # surfaces: 1 the plate (outside, side 1), 2 the inclusion (inside, side -1)
    a = sum(
        ufl.inner(MATERIALS[side].stress(u), ufl.sym(ufl.grad(v))) * dx(tag)
        for tag, side in ((1, 1), (2, -1))
    )
    prefix = unique_prefix("moving_fitted_")
    problem = dolfinx.fem.petsc.LinearProblem(
        form(a),
        form(loads.linear_form()),
        bcs=loads.bcs,
        u=dolfinx.fem.Function(V, name="u"),
        petsc_options_prefix=prefix,
        petsc_options=defaults("linear") | {"pc_type": "cholesky"},
    )
    problem.A.setOption(PETSc.Mat.Option.SPD, True)
    times["forms_s"] = time.perf_counter() - start
    start = time.perf_counter()
    uh = problem.solve()
    times["solve_s"] = time.perf_counter() - start
    remove_options(prefix)
    times["time_s"] = times["mesh_s"] + times["forms_s"] + times["solve_s"]
    times["dofs"] = V.dofmap.index_map.size_global * V.dofmap.index_map_bs
    times["max_u"] = comm.allreduce(float(np.abs(uh.x.array).max()), op=MPI.MAX)
    return times


# -- the run -------------------------------------------------------------------------------
def run(sizes, positions: int, show: bool, comm, save=None) -> dict:
    """Every mesh and law; ``save(result)`` (if given) after each (rank 0)."""

    def log(line: str) -> None:
        if show and comm.rank == 0:
            note(line)

    results = []
    result = {"ranks": comm.size, "positions": positions, "sizes": list(sizes), "cases": results}
    cases = [(n, law) for n in sizes for law in LAWS]
    fitted = {}
    for n, law in progress(cases, "moving interface", show, comm):
        if n not in fitted:
            remeshed_solve(n, *position(0, positions), comm)  # warm-up (JIT), untimed
            fitted[n] = []
            for k in range(1, positions + 1):
                fitted[n].append(remeshed_solve(n, *position(k, positions), comm))
                log(f"  remesh n={n} k={k}: {fitted[n][-1]['time_s']:.3f} s")
        rows = xfem_route(n, law, positions, log)
        for row, body in zip(rows, fitted[n], strict=True):
            row["cold"] = one_solve(n, law, row["centre"], row["radius"])
            warm, cold = row.pop("_u"), row["cold"].pop("_u")  # same mesh, same dof layout
            row["difference"] = comm.allreduce(
                float(np.abs(warm - cold).max(initial=0.0)), op=MPI.MAX
            ) / comm.allreduce(float(np.abs(cold).max(initial=0.0)), op=MPI.MAX)
            row["remesh"] = body
            row["ratio_solve"] = row["time_s"] / row["cold"]["first_s"]
            row["ratio_remesh"] = row["time_s"] / body["time_s"]
        results.append({"n": n, "law": law, "rows": rows, "totals": totals(rows)})
        if comm.rank == 0:
            print(summary_line(results[-1]), flush=True)
            if save is not None:
                save(result)
    return result


def totals(rows: list[dict]) -> dict:
    """Sums over the positions (s) and their ratios."""
    out = {
        "xfem_s": sum(r["time_s"] for r in rows),
        "update_s": sum(r["update_s"] for r in rows),
        "setup_s": sum(sum(r["setup"].values()) for r in rows),
        "warm_newton_s": sum(r["newton_s"] for r in rows),
        "solve_s": sum(r["cold"]["first_s"] for r in rows),
        "newton_alone_s": sum(r["cold"]["again_s"] for r in rows),
        "remesh_s": sum(r["remesh"]["time_s"] for r in rows),
        "iterations_warm": [r["iterations"] for r in rows],
        "iterations_cold": [r["cold"]["iterations"] for r in rows],
        "warm_failures": [r["k"] for r in rows if "warm_failure" in r],
        "difference": max(r["difference"] for r in rows),
    }
    out["ratio_solve"] = out["xfem_s"] / out["solve_s"]
    out["ratio_newton_alone"] = out["xfem_s"] / out["newton_alone_s"]
    out["ratio_remesh"] = out["xfem_s"] / out["remesh_s"]
    return out


def summary_line(case: dict) -> str:
    t = case["totals"]
    return (
        f"n={case['n']} {case['law']}: X-FEM {t['xfem_s']:.2f} s over "
        f"{len(case['rows'])} positions, one solve each {t['solve_s']:.2f} s "
        f"(x{t['ratio_solve']:.2f}), remeshing {t['remesh_s']:.2f} s "
        f"(x{t['ratio_remesh']:.2f}); Newton iterations warm "
        f"{t['iterations_warm']}, cold {t['iterations_cold']}"
    )


def markdown(result: dict) -> str:
    """The report: a summary per mesh and law, then every position."""
    goal_s, goal_r = GOALS["solve"], GOALS["remesh"]
    lines = [
        f"Case 2, P2, two materials, {result['positions']} positions, {result['ranks']} "
        "rank(s). X-FEM: per position `update_interface` + `solve` (warm start). One solve: the "
        "first `solve` from zero of a problem at that position (Newton set-up included); "
        "Newton alone: a second solve from zero. Remeshing: gmsh + mesh + forms + solve, "
        "bonded (sticking-equivalent; the Coulomb rows are compared with it too), JIT warm. "
        "Times in s, summed over the positions. Warm - cold: the largest difference of the "
        "displacements (both sides) of the two solves at one position, relative to the "
        "largest displacement (Coulomb: the carried history restarts at the new interface, "
        "so both solve the same equations, but the warm Newton can end at another solution, "
        "with slipping points, than the cold one, all stuck).",
        "",
        "| h | law | X-FEM | update | set-up | warm Newton | one solve | x one solve "
        f"(goal <= {goal_s}) | Newton alone | x Newton alone | remeshing | x remeshing "
        f"(goal <= {goal_r}) | iterations warm | iterations cold | warm failures "
        "| warm - cold |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case in result["cases"]:
        t = case["totals"]
        lines.append(
            f"| 1/{case['n']} | {case['law']} | {t['xfem_s']:.2f} | {t['update_s']:.2f} | "
            f"{t['setup_s']:.2f} | {t['warm_newton_s']:.2f} | {t['solve_s']:.2f} | "
            f"{t['ratio_solve']:.2f} | {t['newton_alone_s']:.2f} | "
            f"{t['ratio_newton_alone']:.2f} | {t['remesh_s']:.2f} | {t['ratio_remesh']:.2f} | "
            f"{sum(t['iterations_warm'])} | {sum(t['iterations_cold'])} | "
            f"{t['warm_failures'] or '-'} | {t['difference']:.1e} |"
        )
    lines += [
        "",
        "Per position (s): X-FEM = update + solve; dofs X-FEM (active) / body-fitted.",
        "",
        "| h | law | k | centre | radius | X-FEM | update | one solve | x one solve | "
        "remeshing (mesh + forms + solve) | x remeshing | iterations warm / cold | dofs |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case in result["cases"]:
        for r in case["rows"]:
            m, c = r["remesh"], r["centre"]
            failed = f" (warm failed after {r['failed_iterations']})" if "warm_failure" in r else ""
            lines.append(
                f"| 1/{case['n']} | {case['law']} | {r['k']} | ({c[0]:.3f}, {c[1]:.3f}) | "
                f"{r['radius']:.3f} | {r['time_s']:.3f} | {r['update_s']:.3f} | "
                f"{r['cold']['first_s']:.3f} | {r['ratio_solve']:.2f} | {m['time_s']:.3f} "
                f"({m['mesh_s']:.3f} + {m['forms_s']:.3f} + {m['solve_s']:.3f}) | "
                f"{r['ratio_remesh']:.2f} | {r['iterations']}{failed} / "
                f"{r['cold']['iterations']} | {r['dofs']} / {m['dofs']} |"
            )
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[40, 160], metavar="N")
    parser.add_argument("--positions", type=int, default=POSITIONS)
    parser.add_argument("--no-progress", action="store_true", help="no per-position lines")
    parser.add_argument(
        "--json",
        help="where to write (default: bench/results/moving_interface.json, "
        "written only for the default sizes and positions)",
    )
    args = parser.parse_args()
    if any(n < 2 or n % 2 for n in args.sizes):
        parser.error(f"--sizes: even numbers of cells per side >= 2, got {args.sizes}")
    if args.positions < 1:
        parser.error(f"--positions: at least 1, got {args.positions}")
    default = args.sizes == [40, 160] and args.positions == POSITIONS
    path = None  # a quick run leaves the published results alone
    if args.json is not None or default:
        path = pathlib.Path(args.json or RESULTS / "moving_interface.json")

    def save(result: dict) -> None:  # after every case: a run cut short keeps its cases
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(result, indent=1))
        path.with_suffix(".md").write_text(markdown(result))

    comm = MPI.COMM_WORLD
    result = run(args.sizes, args.positions, not args.no_progress, comm, path and save)
    if comm.rank == 0:
        print(markdown(result))


if __name__ == "__main__":
    main()
