"""The sticking sphere in 3D at scale: X-FEM's solver presets against plain DOLFINx.

For each ``--sizes`` n (cells per edge of the unit cube, P2 tetrahedra): the triaxial
sticking sphere of :func:`xfem_contact.cases.solid.sphere_problem` (quadric level set)
solved with the ``iterative`` preset (FGMRES + band multigrid: GMRES + GAMG with the six
rigid modes per side on the coarse level) and, up to ``--direct-max``, the ``direct`` one
(MUMPS LDL^T), and the floor: plain DOLFINx P2 elasticity on the same mesh by CG + GAMG
with the six rigid modes (``bench/plain_elasticity.py --mesh cube``: the same loads and
point constraints, no sphere). Each solve is a process of its own, measured from the
outside: whole-process wall time (start to exit: imports, JIT cache reads, mesh, cut,
assembly, solve) and peak resident memory (``wait4``'s ``ru_maxrss``; under
``mpiexec`` the largest process's), and each rank's CPU time (user + system, read by
the rank itself at its end). Printed and written per row: dofs, Newton steps, Krylov
iterations per step, time and memory and their ratios to plain DOLFINx's on the same
mesh and ranks, memory per dof, the pressure error, and the X-FEM phases (DOLFINx
timers ``xfem_contact: ...``). With ``--ranks 1 2`` every solve also runs on 2 ranks:
the speed-up of each preset against plain DOLFINx's, by wall time and by the busiest
rank's CPU time, each the best of ``--repeat`` interleaved solves. On a machine shared
with other jobs the wall time measures the load; with ``--sleep-waits`` (MPICH's waiting
ranks sleep) a rank's CPU time is its work, and the CPU speed-up that of the work and
its balance between the ranks.

Writes ``bench/results/scale3d.{json,md}`` (``--name``: another stem).

Run: ``python bench/scale3d.py [--sizes 4 8] [--ranks 1] [--direct-max 8]`` (``make
bench``); the measured studies: ``--sizes 8 16 24 --direct-max 12 --name
scale3d_large``, ``--sizes 34 --solvers plain iterative --name scale3d_1m`` (over a
million dofs; ``scale3d_1m_memory`` the same again), ``--sizes 40 --solvers plain
iterative --name scale3d_1_6m``, ``--sizes 50 --solvers plain iterative --name scale3d_3m``
(3.1 M dofs: about 13 GB for the iterative preset), ``--sizes 12 --ranks 1 2
--direct-max 12 --name scale3d_ranks``, ``--sizes 20 --ranks 1 2 --solvers plain iterative
--repeat 2 --sleep-waits --name scale3d_ranks20_band3d`` (n = 24: ``--sizes 24 ... --name
scale3d_ranks24_band3d``; n = 34: ``--sizes 34 --ranks 1 2 --solvers plain iterative
--sleep-waits --name scale3d_1m_ranks``), ``--sizes 16 --ranks 1 2
--solvers plain direct --direct-max 16 --sleep-waits --name scale3d_direct16``, and with
the coarse level solved to a tolerance under FGMRES ``--sizes 16 24 34 --solvers plain
iterative --name scale3d_flexible``, ``--sizes 50 --solvers plain iterative --name
scale3d_3m_flexible`` and the GMRES preset again (``--sizes 24 --solvers iterative
--option ksp_type=gmres --name scale3d_24_gmres``, n = 34: ``--name scale3d_1m_gmres``).
``bench/memory3d.py`` shows where the memory goes.
"""

import argparse
import json
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
PLAIN = ROOT / "bench" / "plain_elasticity.py"
SOLVERS = ("plain", "iterative", "direct")
#: The package's phase timers read (``xfem_contact._timers``: DOLFINx's table, by name)
PHASES = (
    "cut",
    "cut rules",
    "Newton set-up: selection",
    "Newton set-up: forms",
    "Newton set-up: sparsity",
    "Newton set-up: first Jacobian",
    "Newton set-up: scaling",
    "Newton assembly",
    "Newton interface status",
    "Newton solve",
)


def case(n: int, solver: str, degree: int, cell: str, options: dict) -> dict:
    """Solve the sphere with ``solver``'s preset (and ``options``, PETSc options over it)
    in this process; its numbers (rank 0's phases, every rank's CPU time). Collective."""
    import dolfinx.common
    from mpi4py import MPI
    from plain_elasticity import cpu_seconds

    from xfem_contact.cases.solid import sphere_errors, sphere_problem
    from xfem_contact.solvers.options import preset

    start = time.perf_counter()
    problem = sphere_problem(
        n, degree, "sticking", cell, levelset="quadric", petsc_options=preset(solver) | options
    )
    report = problem.solve()
    solved = time.perf_counter() - start
    pressure, _ = sphere_errors(problem)
    phases = {}
    for name in PHASES:
        try:
            phases[name] = dolfinx.common.timing(f"xfem_contact: {name}")[1].total_seconds()
        except RuntimeError:  # a phase this solve did not run
            continue
    return {
        "dofs": problem.space.dof_counts().total,
        "newton": report.iterations,
        "krylov": report.linear_iterations,
        "xfem_s": solved,
        "error": pressure,
        "phases": phases,
        "rank_cpu_s": MPI.COMM_WORLD.gather(cpu_seconds()),
    }


def measured(command: list[str], memory_gb: float | None = None, env: dict | None = None) -> dict:
    """Run ``command`` as a process of its own: its last output line (JSON) and its
    wall time (s), CPU time (s, user + system of it and its children: under ``mpiexec``
    every rank's) and peak resident memory (MB), or ``{"failed": ...}``. ``memory_gb``:
    the process's address-space limit (GB; None: none); ``env``: its environment (None:
    this process's)."""
    limit = None
    if memory_gb is not None:
        size = int(memory_gb * 2**30)

        def limit():
            resource.setrlimit(resource.RLIMIT_AS, (size, size))

    start = time.perf_counter()
    with tempfile.TemporaryFile("w+") as errors:
        with subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=errors, text=True, preexec_fn=limit, env=env
        ) as proc:
            text = proc.stdout.read()
            _, status, usage = os.wait4(proc.pid, 0)
            proc.returncode = os.waitstatus_to_exitcode(status)
        errors.seek(0)
        said = [s for s in errors.read().splitlines() if s.strip()]
    wall = time.perf_counter() - start
    rss = usage.ru_maxrss / 1024.0
    cpu = usage.ru_utime + usage.ru_stime
    lines = text.strip().splitlines()
    if proc.returncode != 0 or not lines:
        reason = said[-1] if said else "killed (out of memory?)"
        return {"failed": f"exit code {proc.returncode}: {reason}", "wall_s": wall, "rss_mb": rss}
    return json.loads(lines[-1]) | {"wall_s": wall, "cpu_s": cpu, "rss_mb": rss}


def run(n: int, solver: str, ranks: int, args) -> dict:
    """One solve measured in its own process (:func:`measured`)."""
    launcher = [] if ranks == 1 else [str(pathlib.Path(sys.executable).parent / "mpiexec")]
    launcher += [] if ranks == 1 else ["-n", str(ranks)]
    if solver == "plain":
        command = [sys.executable, str(PLAIN), "--mesh", "cube", "--n", str(n)]
        command += ["--degree", str(args.degree), "--cell", args.cell, "--factor", "gamg"]
        command += ["--out", ""]
    else:
        command = [sys.executable, __file__, "--case", str(n), solver]
        command += [str(args.degree), args.cell, *args.option]
    env = None
    if args.sleep_waits:  # MPICH's ranks sleep while they wait: CPU time is then work
        env = os.environ | {"MPIR_CVAR_ENABLE_HEAVY_YIELD": "1"}
    row = measured(launcher + command, args.memory_gb, env)
    row |= {"n": n, "solver": solver, "ranks": ranks}
    if solver == "plain" and "failed" not in row:
        row |= {"newton": 1, "krylov": [row["krylov"]], "error": None}
        row["phases"] = row.pop("timings")
    return row


def busiest(row: dict) -> float | None:
    """The largest CPU time of the row's ranks (s), or None (a row measured without)."""
    return max(row["rank_cpu_s"]) if row.get("rank_cpu_s") else None


def line(row: dict, plain: dict | None) -> str:
    """One row in words."""
    head = f"n={row['n']:3d} {row['solver']:9s} {row['ranks']} rank(s)"
    if "failed" in row:
        return f"{head}: failed ({row['failed']}), peak RSS {row['rss_mb']:.0f} MB"
    text = (
        f"{head}: {row['dofs']:10,d} dofs, Krylov {row['krylov']}, {row['wall_s']:7.1f} s, "
        f"CPU per rank {row['rank_cpu_s']} s, "
        f"peak RSS {row['rss_mb']:6.0f} MB ({1024 * row['rss_mb'] / row['dofs']:.2f} KB/dof)"
    )
    if plain is not None and row is not plain:
        text += (
            f", time / plain {row['wall_s'] / plain['wall_s']:.2f}, "
            f"RSS / plain {row['rss_mb'] / plain['rss_mb']:.2f}"
        )
    if row["error"] is not None:
        text += f", pressure error {row['error']:.3e}"
    return text


def best(rows: list[dict]) -> dict:
    """Per (n, solver, ranks): the least wall time and the least busiest-rank CPU time
    (s) over the repetitions that did not fail."""
    out = {}
    for r in rows:
        if "failed" in r:
            continue
        key = (r["n"], r["solver"], r["ranks"])
        wall, cpu = out.get(key, (float("inf"), float("inf")))
        out[key] = (min(wall, r["wall_s"]), min(cpu, busiest(r) or float("inf")))
    return out


def speedup_table(rows: list[dict]) -> list[str]:
    """The 2-rank speed-ups (the best of the repetitions: :func:`best`) by wall time and
    by the busiest rank's CPU time, and their ratio to plain DOLFINx's."""
    times = best(rows)
    speedups = {}
    for (n, solver, ranks), (wall, cpu) in times.items():
        one = times.get((n, solver, 1))
        if ranks > 1 and one is not None:
            speedups[n, solver, ranks] = (one[0] / wall, one[1] / cpu)
    if not speedups:
        return []
    out = [
        "",
        "Speed-ups (the least time over the repetitions; CPU: the busiest rank's user + "
        "system time):",
        "",
        "| n | solver | ranks | speed-up (wall) | over plain DOLFINx's | speed-up (CPU) "
        "| over plain DOLFINx's |",
        "|---|---|---|---|---|---|---|",
    ]
    for (n, solver, ranks), (wall, cpu) in speedups.items():
        base = speedups.get((n, "plain", ranks))
        relative = ["-", "-"]
        if base is not None and solver != "plain":
            relative = [f"{wall / base[0]:.2f}", f"{cpu / base[1]:.2f}"]
        out.append(
            f"| {n} | {solver} | {ranks} | {wall:.2f} | {relative[0]} | {cpu:.2f} | {relative[1]} |"
        )
    return out


def table(rows: list[dict]) -> str:
    """The markdown tables: every solve, the X-FEM phases, the 2-rank speed-ups."""
    done = {(r["n"], r["solver"], r["ranks"]): r for r in rows if "failed" not in r}
    out = [
        "| n | solver | ranks | dofs | Newton | Krylov per step | wall (s) | CPU per rank (s) "
        "| peak RSS (MB) | KB/dof | time / plain | RSS / plain | pressure error |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        key = f"| {r['n']} | {r['solver']} | {r['ranks']} |"
        if "failed" in r:
            out.append(f"{key} failed: {r['failed']} (peak RSS {r['rss_mb']:.0f} MB) |" + 9 * " |")
            continue
        plain = done.get((r["n"], "plain", r["ranks"]))
        ratios = "- | - |"
        if plain is not None and r["solver"] != "plain":
            ratios = f"{r['wall_s'] / plain['wall_s']:.2f} | {r['rss_mb'] / plain['rss_mb']:.2f} |"
        error = "-" if r["error"] is None else f"{r['error']:.3e}"
        cpu = ", ".join(f"{t:.1f}" for t in r.get("rank_cpu_s", [])) or "-"
        out.append(
            f"{key} {r['dofs']:,} | {r['newton']} | {r['krylov']} | {r['wall_s']:.1f} | {cpu} | "
            f"{r['rss_mb']:.0f} | {1024 * r['rss_mb'] / r['dofs']:.2f} | {ratios} {error} |"
        )
    phased = [r for r in rows if "failed" not in r and r["solver"] != "plain"]
    if phased:
        names = list(dict.fromkeys(k for r in phased for k in r["phases"]))
        out += ["", "X-FEM phases (s, rank 0; DOLFINx timers, summed over calls):", ""]
        out.append("| n | solver | ranks | wall (s) | " + " | ".join(names) + " |")
        out.append("|---" * (len(names) + 4) + "|")
        for r in phased:
            values = " | ".join(f"{r['phases'].get(k, 0.0):.1f}" for k in names)
            out.append(
                f"| {r['n']} | {r['solver']} | {r['ranks']} | {r['wall_s']:.1f} | {values} |"
            )
    return "\n".join(out + speedup_table(rows)) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[4, 8], help="cells per edge")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1], help="MPI process counts")
    parser.add_argument("--solvers", nargs="+", default=list(SOLVERS), choices=SOLVERS)
    parser.add_argument("--direct-max", type=int, default=8, help="largest n of 'direct'")
    parser.add_argument("--degree", type=int, default=2, choices=[1, 2])
    parser.add_argument("--cell", default="tetrahedron", choices=["tetrahedron", "hexahedron"])
    parser.add_argument("--memory-gb", type=float, help="each process's address-space limit")
    parser.add_argument("--name", default="scale3d", help="stem of the results' files")
    parser.add_argument(
        "--repeat", type=int, default=1, help="solves of each size, ranks and solver (interleaved)"
    )
    parser.add_argument(
        "--option",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="PETSc options over the presets of X-FEM's solves, e.g. bmg_band_mat_mumps_icntl_7=5",
    )
    parser.add_argument(
        "--sleep-waits",
        action="store_true",
        help="MPICH's waiting ranks sleep instead of spinning (MPIR_CVAR_ENABLE_HEAVY_YIELD): "
        "a rank's CPU time is then its work, not its waits; the waits last longer (to the "
        "next wake-up), so such runs' wall times are not the ones to compare",
    )
    parser.add_argument("--case", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

        # isort: split
        from mpi4py import MPI

        n, solver, degree, cell, *options = args.case
        options = dict(item.split("=", 1) for item in options)
        result = case(int(n), solver, int(degree), cell, options)
        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(result), flush=True)
        return
    for solver in args.solvers:  # JIT caches warm: no compilation in the measured runs
        run(4, solver, 1, args)
    rows = []
    for n in args.sizes:
        for _ in range(args.repeat):  # interleaved: a change of the machine's load hits all
            for ranks in args.ranks:
                plain = None
                for solver in args.solvers:
                    if solver == "direct" and n > args.direct_max:
                        continue
                    row = run(n, solver, ranks, args)
                    rows.append(row)
                    plain = row if solver == "plain" and "failed" not in row else plain
                    print(line(row, plain), flush=True)
        RESULTS.mkdir(parents=True, exist_ok=True)  # after each size: a long run keeps its rows
        (RESULTS / f"{args.name}.json").write_text(json.dumps(rows, indent=1))
        (RESULTS / f"{args.name}.md").write_text(table(rows))
    print(table(rows))


if __name__ == "__main__":
    main()
