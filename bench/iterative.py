"""Krylov iterations and memory of the iterative Newton solve against the direct one.

Paper case 2 (P2-P1, sticking, quadrilaterals) for N = 40 ... 320 cells per side, and
with a radius that leaves cut cells with tiny parts (``--tiny``: r = 0.2 + 1e-7 h,
so the circle passes a hair's breadth from mesh nodes), each case a process of its
own solved with ``LINEAR_PRESETS["direct"]`` (MUMPS LU) and ``["iterative"]`` (GMRES +
band multigrid, :mod:`xfem_contact.solvers.band_multigrid`): Newton steps, Krylov iterations per
step, wall time of the solve, peak resident memory and the contact-pressure error.
The baseline, measured in the same run: plain DOLFINx P2 elasticity on the same mesh
solved by CG + GAMG (``bench/plain_elasticity.py --factor gamg``, no cut); the table
gives the iterative preset's peak memory over the baseline's and its time over MUMPS's.
A size that fails (memory) is reported as such.
Writes ``bench/results/iterative.{json,md}`` (``--name``: another stem).

Run: ``python bench/iterative.py [--sizes 40 80 160 320 640] [--tiny]`` (``make bench``);
the largest sizes: ``--sizes 1024 1280 --solvers plain iterative --memory-gb 21 --name
iterative_large`` (``--memory-gb``: each case's address-space limit, so that a size
that does not fit fails on its allocation, not by the kernel's out-of-memory killer).
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

from xfem_contact.io.progress import note, progress

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
SOLVERS = ["plain", "direct", "iterative"]


def case(n: int, solver: str, tiny: bool) -> dict:
    """Solve one case in this process; returns its numbers. Collective."""
    from xfem_contact.cases.paper import INCLUSION_RADIUS, inclusion_errors, inclusion_problem
    from xfem_contact.solvers.options import preset

    radius = INCLUSION_RADIUS + (1e-7 / n if tiny else 0.0)
    problem = inclusion_problem(n, 2, "sticking", radius=radius, petsc_options=preset(solver))
    start = time.perf_counter()
    report = problem.solve()
    wall = time.perf_counter() - start
    return {
        "n": n,
        "solver": solver,
        "tiny": tiny,
        "dofs": problem.space.dof_counts().total,
        "newton": report.iterations,
        "krylov": report.linear_iterations,
        "solve_s": wall,
        "error": inclusion_errors(problem, problem.w).pressure,
    }


def run(n: int, solver: str, tiny: bool, memory_gb: float | None = None) -> dict:
    """:func:`case` in a process of its own (``solver == "plain"``: the baseline), with
    that process's peak RSS (MB); ``{"failed": ...}`` if it failed. ``memory_gb``: the
    process's address-space limit (GB; None: none)."""
    command = [sys.executable, __file__, "--case", str(n), solver, str(int(tiny))]
    if solver == "plain":
        plain = ROOT / "bench" / "plain_elasticity.py"
        out = tempfile.mkdtemp()
        command = [sys.executable, str(plain), "--n", str(n), "--factor", "gamg", "--out", out]
    with tempfile.TemporaryFile("w+") as out:
        proc = subprocess.Popen(
            command, stdout=out, stderr=subprocess.STDOUT, preexec_fn=_limit(memory_gb)
        )
        _, status, usage = os.wait4(proc.pid, 0)
        out.seek(0)
        text = out.read()
    rss = usage.ru_maxrss / 1024.0
    if os.waitstatus_to_exitcode(status) != 0:
        reason = text.strip().splitlines()[-1] if text.strip() else "killed (out of memory?)"
        return {"n": n, "solver": solver, "tiny": tiny, "failed": reason, "rss_mb": rss}
    result = json.loads(text.strip().splitlines()[-1])
    result["rss_mb"] = rss
    if solver == "plain":
        timings = result.pop("timings")
        result |= {"n": n, "solver": solver, "tiny": tiny, "newton": 1, "error": None}
        result["krylov"], result["solve_s"] = [result["krylov"]], timings["solve"]
    return result


def _limit(memory_gb: float | None):
    """A ``preexec_fn`` limiting the child's address space to ``memory_gb`` GB (or None)."""
    if memory_gb is None:
        return None
    size = int(memory_gb * 2**30)
    return lambda: resource.setrlimit(resource.RLIMIT_AS, (size, size))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[40, 80, 160, 320])
    parser.add_argument("--tiny", action="store_true", help="also the tiny-cut radius")
    parser.add_argument("--solvers", nargs="+", default=SOLVERS, choices=SOLVERS)
    parser.add_argument("--memory-gb", type=float, help="each case's address-space limit")
    parser.add_argument("--name", default="iterative", help="stem of the results' files")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--case", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.case:
        n, solver, tiny = args.case
        print(json.dumps(case(int(n), solver, bool(int(tiny)))))
        return
    rows = []
    for tiny in (False, True) if args.tiny else (False,):
        for n in progress(args.sizes, "sizes", not args.no_progress):
            for solver in args.solvers:
                r = run(n, solver, tiny, args.memory_gb)
                rows.append(r)
                if "failed" in r:
                    note(
                        f"N={n:4d} {solver}: failed ({r['failed']}), peak RSS {r['rss_mb']:.0f} MB"
                    )
                    continue
                note(
                    f"N={n:4d}{' tiny cut' if tiny else ''} {solver:9s} dofs {r['dofs']:9,d}: "
                    f"Newton {r['newton']}, Krylov per step {r['krylov']}, solve "
                    f"{r['solve_s']:7.2f} s, peak RSS {r['rss_mb']:6.0f} MB"
                    + ("" if r["error"] is None else f", error {r['error']:.4e}")
                )
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"{args.name}.json").write_text(json.dumps(rows, indent=1))
    (RESULTS / f"{args.name}.md").write_text(table(rows))
    print(table(rows))


def table(rows: list[dict]) -> str:
    """The markdown table; ratios against the same N's plain (memory) and direct (time)."""
    done = {(r["n"], r["tiny"], r["solver"]): r for r in rows if "failed" not in r}
    lines = [
        "| N | cut | solver | dofs | Newton | Krylov per step | solve (s) | peak RSS (MB) "
        "| RSS / plain | time / direct | error |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        cut = "tiny" if r["tiny"] else "generic"
        if "failed" in r:
            lines.append(f"| {r['n']} | {cut} | {r['solver']} | failed: {r['failed']} |" + 7 * " |")
            continue
        plain = done.get((r["n"], r["tiny"], "plain"))
        direct = done.get((r["n"], r["tiny"], "direct"))
        memory = f"{r['rss_mb'] / plain['rss_mb']:.2f}" if plain else "-"
        speed = f"{r['solve_s'] / direct['solve_s']:.2f}" if direct else "-"
        error = "-" if r["error"] is None else f"{r['error']:.4e}"
        lines.append(
            f"| {r['n']} | {cut} | {r['solver']} | {r['dofs']:,} | {r['newton']} | "
            f"{r['krylov']} | {r['solve_s']:.2f} | {r['rss_mb']:.0f} | {memory} | {speed} | "
            f"{error} |"
        )
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
