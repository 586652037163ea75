"""What a cut contact solve costs against plain DOLFINx elasticity on the same mesh.

Paper case 2 (the main demo: circular inclusion, sticking, quadrilaterals) for P1 and
P2 at N = 20 ... 320 cells per side, each run as a process of its own, next to
``bench/plain_elasticity.py`` (no cut; the same mesh, loads, MUMPS controls and
factorisation: Cholesky where the demo's Jacobian is symmetric, else LU) in the same
session: dofs, whole-process wall time, peak resident memory, and the demo's
own breakdown into phases (its ``summary.json``). The ratio cut / plain is printed per N;
the JIT (cold FFCx cache) is measured apart, once per degree at the smallest N, in an
empty cache directory. ``--ranks 2`` adds the largest P2 case on 2 MPI ranks (speed-up
per phase, plain DOLFINx's next to it). Wall times vary from run to run on a shared
machine (10-50 % here), so from N = ``--repeat-from`` on each pair (cut, plain) runs
``--repeat`` times in turn and the run of median wall time stands for it (all walls
are kept in the JSON). Writes ``bench/results/scaling.{json,md,png}``.

Run: ``python bench/scaling.py [--sizes 20 40 80 160 320] [--degrees 1 2] [--ranks 2]
[--repeat 3]`` (``make bench``).
"""

import argparse
import functools
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import matplotlib
import numpy as np

from xfem_contact.io.progress import note, progress

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
#: The demo's phases (keys of its summary's ``timings``), in the order they run
PHASES = [
    ("cut", "level set + cut"),
    ("quadrature", "rules"),
    ("spaces", "spaces + problem"),
    ("forms", "forms"),
    ("sparsity", "sparsity"),
    ("assembly", "assembly"),
    ("scaling", "scaling"),
    ("linear_solve", "factorisation + solve"),
    ("status", "Newton status"),
    ("post_processing", "post-processing"),
    ("output", "output"),
]


def run(command: list[str], env: dict | None = None) -> tuple[float, float, str]:
    """Run a process to its end: (wall time s, peak RSS MB of that process, stdout)."""
    start = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out:
        proc = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        out.seek(0)
        text = out.read()
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(command)} failed:\n{text}")
    return wall, usage.ru_maxrss / 1024.0, text


def mumps_controls() -> list[str]:
    """The MUMPS controls xfem-contact's solvers set (``["icntl_7=4", ...]``), so that
    the plain solve uses them too."""
    code = (
        "from xfem_contact.solvers.options import SOLVER_OPTIONS as S;"
        "print(' '.join(f'{k[10:]}={o.default}' for k, o in S.items() "
        "if k.startswith('mat_mumps_')))"
    )
    return subprocess.check_output([sys.executable, "-c", code], text=True).split()


def demo(n, degree, work, env=None, ranks=1, samples=False, solver="direct") -> dict:
    summary = work / f"demo_{n}_{degree}_{ranks}.json"
    command = [sys.executable, str(ROOT / "demos" / "inclusion_contact.py")]
    command += ["--n", str(n), "--degree", str(degree), "--quiet", "--solver", solver]
    command += ["--out", str(work / "demo"), "--json", str(summary)]
    if ranks > 1:
        command = [str(pathlib.Path(sys.executable).parent / "mpiexec"), "-n", str(ranks)] + command
    wall, rss, _ = run(command, env)
    data = json.loads(summary.read_text())
    return {
        "wall": wall,
        "rss_mb": rss,
        "dofs": data["dofs"]["total"],
        "timings": data["timings"],
        "error": data["contact_pressure_rel_L2_error"],
        "newton_iterations": data["newton_iterations"],
        "factorisation": data["factorisation"],
    } | ({"_samples": data["interface_samples"]} if samples else {})


def max_difference(a: dict, b: dict) -> float:
    """Largest difference of ``lambda_n`` at the same interface points of two runs
    (points matched by sorted position), relative to the largest ``|lambda_n|``."""

    def by_position(s):
        x, y, lam = (np.asarray(s[k]) for k in ("x", "y", "lambda_n"))
        order = np.lexsort((np.round(y, 10), np.round(x, 10)))
        return np.c_[x, y][order], lam[order]

    (xa, la), (xb, lb) = by_position(a), by_position(b)
    if xa.shape != xb.shape or not np.allclose(xa, xb, rtol=0.0, atol=1e-12):
        return float("inf")
    return float(np.abs(la - lb).max() / np.abs(la).max())


def plain(n, degree, work, mumps, env=None, ranks=1, factor="lu", mesh="square") -> dict:
    command = [sys.executable, str(ROOT / "bench" / "plain_elasticity.py")]
    command += ["--n", str(n), "--degree", str(degree), "--out", str(work / "plain")]
    command += ["--factor", factor, "--mesh", mesh]
    command += ["--mumps", *mumps] if factor != "gamg" else []  # unused options: a warning
    if ranks > 1:
        command = [str(pathlib.Path(sys.executable).parent / "mpiexec"), "-n", str(ranks)] + command
    wall, rss, text = run(command, env)
    data = json.loads(text.strip().splitlines()[-1])
    return {"wall": wall, "rss_mb": rss, "dofs": data["dofs"], "timings": data["timings"]}


def cold_jit(degree, n, work, mumps) -> dict:
    """Process time with an empty FFCx cache minus the warm time (the JIT's cost)."""
    cache = work / f"cold_cache_{degree}"
    env = os.environ | {"XDG_CACHE_HOME": str(cache)}
    cold = demo(n, degree, work, env)["wall"]
    warm = demo(n, degree, work, env)["wall"]
    plain_cold = plain(n, degree, work, mumps, env | {"XDG_CACHE_HOME": str(cache) + "p"})
    plain_warm = plain(n, degree, work, mumps, env | {"XDG_CACHE_HOME": str(cache) + "p"})
    shutil.rmtree(cache, ignore_errors=True)
    shutil.rmtree(str(cache) + "p", ignore_errors=True)
    return {"cut": cold - warm, "plain": plain_cold["wall"] - plain_warm["wall"]}


def medians(runs: dict, repeat: int) -> dict:
    """Call each of ``runs`` (name to a function giving a run's dict) ``repeat`` times
    in turn; each name's run of median wall time, with every wall under ``walls``."""
    done = {name: [] for name in runs}
    for _ in range(repeat):
        for name, fn in runs.items():
            done[name].append(fn())
    out = {}
    for name, results in done.items():
        chosen = sorted(results, key=lambda r: r["wall"])[len(results) // 2]
        out[name] = chosen | {"walls": [r["wall"] for r in results]}
    return out


def line(row: dict) -> str:
    """One printed line per case: the ratios the goals are stated in."""
    c, p = row["cut"], row["plain"]
    t = c["timings"]
    solve = sum(
        t[k] for k in ("forms", "sparsity", "assembly", "scaling", "linear_solve", "status")
    )
    iterate = (t["assembly"] + t["linear_solve"] + t["status"]) / max(c["newton_iterations"], 1)
    after = t["post_processing"] + t["output"]
    return (
        f"P{row['degree']} N={row['n']:4d} dofs {c['dofs']:9,d}: cut {c['wall']:7.2f} s, "
        f"plain {p['wall']:6.2f} s, ratio {c['wall'] / p['wall']:.2f}; peak RSS "
        f"{c['rss_mb']:.0f} / {p['rss_mb']:.0f} MB ({c['rss_mb'] / p['rss_mb']:.2f}x); "
        f"post-processing + output {100 * after / solve:.0f} % of the solve; Newton status "
        f"{100 * t['status'] / max(c['newton_iterations'], 1) / iterate:.1f} % of an iterate"
    )


def table(rows: list[dict]) -> str:
    head = (
        "| P | N | dofs | cut process (s) | plain process (s) | ratio | peak RSS cut / plain (MB) |"
    )
    head += " " + " | ".join(label for _, label in PHASES) + " |"
    lines = [head, "|" + "---|" * (7 + len(PHASES))]
    for r in rows:
        c, p = r["cut"], r["plain"]
        cells = [
            f"{r['degree']}",
            f"{r['n']}",
            f"{c['dofs']:,}",
            f"{c['wall']:.2f}",
            f"{p['wall']:.2f}",
            f"**{c['wall'] / p['wall']:.2f}**",
            f"{c['rss_mb']:.0f} / {p['rss_mb']:.0f} ({c['rss_mb'] / p['rss_mb']:.2f}x)",
        ]
        cells += [f"{c['timings'].get(key, 0.0):.3f}" for key, _ in PHASES]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot(rows: list[dict], path: pathlib.Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharey=True)
    for ax, degree in zip(axes, (1, 2), strict=True):
        chosen = [r for r in rows if r["degree"] == degree]
        if not chosen:
            continue
        dofs = [r["cut"]["dofs"] for r in chosen]
        for k, (key, label) in enumerate(PHASES):
            times = [max(r["cut"]["timings"].get(key, 0.0), 1e-4) for r in chosen]
            ax.loglog(dofs, times, ".-", color=plt.cm.tab20(k), label=label)
        ax.loglog(dofs, [r["cut"]["wall"] for r in chosen], "k-", lw=2, label="cut: process")
        ax.loglog(dofs, [r["plain"]["wall"] for r in chosen], "k--", lw=2, label="plain: process")
        last = chosen[-1]["cut"]["wall"]
        ax.loglog(dofs, [last * d / dofs[-1] for d in dofs], ":", color="grey", label="O(dofs)")
        ax.set_title(f"Case 2, P{degree}, quadrilaterals")
        ax.set_xlabel("dofs")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("wall time (s)")
    axes[1].legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[20, 40, 80, 160, 320])
    parser.add_argument("--degrees", type=int, nargs="+", default=[1, 2])
    parser.add_argument(
        "--ranks", type=int, default=0, help="also run the largest P2 case on R ranks"
    )
    parser.add_argument("--repeat", type=int, default=3, help="runs per pair from --repeat-from")
    parser.add_argument("--repeat-from", type=int, default=160, help="smallest N repeated")
    parser.add_argument("--no-jit", action="store_true", help="skip the cold-cache runs")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument(
        "--solver",
        default="direct",
        choices=["direct", "iterative"],
        help="the demo's preset; plain DOLFINx then factors as it does, or runs CG + GAMG "
        "(results in scaling_iterative.*)",
    )
    args = parser.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    mumps = mumps_controls()
    name = "scaling" if args.solver == "direct" else f"scaling_{args.solver}"
    cut = functools.partial(demo, solver=args.solver)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        for degree in args.degrees:
            # warm the caches of this degree; the plain solve factors as the demo does
            factor = cut(args.sizes[0], degree, work)["factorisation"]
            factor = "gamg" if args.solver == "iterative" else factor
            plain(args.sizes[0], degree, work, mumps, factor=factor)
            for n in progress(args.sizes, f"P{degree} sizes", not args.no_progress):
                last = degree == 2 and n == args.sizes[-1]
                runs = {
                    "cut": functools.partial(cut, n, degree, work, samples=last and args.ranks > 1),
                    "plain": functools.partial(plain, n, degree, work, mumps, factor=factor),
                }
                repeat = args.repeat if n >= args.repeat_from else 1
                rows.append({"degree": degree, "n": n} | medians(runs, repeat))
                row = rows[-1]
                note(line(row))
        jit = (
            {}
            if args.no_jit
            else {d: cold_jit(d, args.sizes[0], work, mumps) for d in args.degrees}
        )
        for degree, cost in jit.items():
            print(
                f"P{degree} JIT (cold cache, N={args.sizes[0]}): cut {cost['cut']:.1f} s, "
                f"plain {cost['plain']:.1f} s"
            )
        parallel = None
        if args.ranks > 1:
            n = args.sizes[-1]
            row = next(r for r in rows if r["degree"] == 2 and r["n"] == n)
            serial = row["cut"]
            runs = {
                "cut": functools.partial(cut, n, 2, work, ranks=args.ranks, samples=True),
                "plain": functools.partial(
                    plain, n, 2, work, mumps, ranks=args.ranks, factor=factor
                ),
            }
            ran = medians(runs, args.repeat if n >= args.repeat_from else 1)
            distributed = ran["cut"]
            difference = max_difference(serial.pop("_samples"), distributed.pop("_samples"))
            parallel = {"n": n, "ranks": args.ranks, "serial": serial, "parallel": distributed}
            parallel["plain"] = {"serial": row["plain"], "parallel": ran["plain"]}
            parallel["lambda_n_max_relative_difference"] = difference
            plain_speedup = row["plain"]["wall"] / ran["plain"]["wall"]
            print(
                f"P2 N={n}: {args.ranks} ranks {distributed['wall']:.2f} s, 1 rank "
                f"{serial['wall']:.2f} s, speed-up {serial['wall'] / distributed['wall']:.2f} "
                f"(plain DOLFINx: {row['plain']['wall']:.2f} -> {ran['plain']['wall']:.2f} s, "
                f"{plain_speedup:.2f}); lambda_n at the same points differs by "
                f"{difference:.1e} (relative)"
            )
            for key, label in PHASES:
                s, p = serial["timings"].get(key, 0.0), distributed["timings"].get(key, 0.0)
                print(f"    {label:24s} {s:8.3f} s -> {p:8.3f} s  ({s / max(p, 1e-9):.2f}x)")
    (RESULTS / f"{name}.json").write_text(
        json.dumps({"rows": rows, "jit": jit, "parallel": parallel, "mumps": mumps}, indent=1)
    )
    text = table(rows)
    (RESULTS / f"{name}.md").write_text(text + "\n")
    plot(rows, RESULTS / f"{name}.png")
    print(text)
    print(f"wrote {RESULTS / name}.md, .json and .png")


if __name__ == "__main__":
    main()
