"""The numerical inf-sup test of every 2D element: the discrete inf-sup constant
(:func:`xfem_contact.mechanics.inf_sup.inf_sup_constant`) of P1-P1 and P2-P1 on triangles
and quadrilaterals, for each LBB treatment (none, restriction, stabilized; stabilized
with the ghost penalty raised to the stabilisation's weight, 0.1, too), on n = 8, 16,
32, 64 cells per side of the unit square, over circles at random centres and radii (a
third of them passing within 1e-6 h of a mesh node: tiny cuts on purpose). Prints, per
element, treatment and n, the least and median beta and the count of indefinite pairs
(beta^2 < 0), and the slope of the least beta in log n over the last pair; then P1-P1
on tetrahedra cut by a sphere (``--tet-sizes``). Writes
``bench/results/inf_sup.{json,md,png}``.

Run: ``python bench/inf_sup.py [--circles 50] [--sizes 8 16 32 64]`` (``make bench``).
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import argparse
import json
import math
import pathlib
import time

import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.progress import note
from xfem_contact.mechanics.inf_sup import inf_sup_constant
from xfem_contact.mechanics.laws import Bonded
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
ELEMENTS = [("triangle", 1), ("triangle", 2), ("quadrilateral", 1), ("quadrilateral", 2)]
#: label: (lbb, ghost penalty; None: the default)
TREATMENTS = {
    "none": ("none", None),
    "restriction": ("restriction", None),
    "stabilized": ("stabilized", None),
    "stabilized, ghost 0.1": ("stabilized", 0.1),
}


def circles(count: int, n: int, rng) -> list[tuple[float, float, float]]:
    """Random circles inside the unit square; every third through a node to 1e-6 h."""
    out = []
    for k in range(count):
        cx, cy = rng.uniform(0.35, 0.65, 2)
        r = rng.uniform(0.12, 0.3)
        if k % 3 == 2:
            node = np.round(np.array([cx + r, cy]) * n) / n
            r = math.hypot(*(node - (cx, cy))) + 1e-6 / n
        out.append((float(cx), float(cy), float(r)))
    return out


def plot(rows: list[dict], path: pathlib.Path) -> None:
    """Least beta against n, one panel per element, one line per treatment."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(ELEMENTS), figsize=(4 * len(ELEMENTS), 3.6), sharey=True)
    for ax, (cell, degree) in zip(axes, ELEMENTS, strict=True):
        for lbb in TREATMENTS:
            sel = [r for r in rows if (r["cell"], r["degree"], r["lbb"]) == (cell, degree, lbb)]
            ns = [r["n"] for r in sel]
            ax.loglog(ns, [max(r["beta_min"], 1e-8) for r in sel], "o-", label=f"{lbb} (least)")
        ax.set_title(f"{cell}, P{degree}-P1")
        ax.set_xlabel("cells per side n")
    axes[0].set_ylabel("discrete inf-sup constant beta")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def tetrahedra(sizes: list[int]) -> list[str]:
    """P1-P1 on the unit cube's tetrahedra (6 n^3) cut by the sphere of radius 0.2 about
    its centre, without LBB treatment and stabilised (the restriction is 2D only):
    lines of a Markdown table of beta^2."""
    if not sizes:
        return []
    lines = [
        "",
        "P1-P1 tetrahedra, sphere R = 0.2 in the unit cube (beta^2; multipliers):",
        "",
        "| lbb | " + " | ".join(f"n={n}" for n in sizes) + " |",
        "|---|" + "---|" * len(sizes),
    ]
    for lbb in ("none", "stabilized"):
        cells = []
        for n in sizes:
            mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, n, n, n)
            sphere = lambda x: np.sqrt(((x.T - 0.5) ** 2).sum(axis=1)) - 0.2  # noqa: E731
            cut = CutMesh(mesh, sphere, degree=2)
            result = inf_sup_constant(Problem(cut, 1, Material(100e6, 0.3), Bonded(lbb=lbb)))
            cells.append(f"{result.beta_squared:.3e} ({result.multipliers})")
            note(f"tetrahedra P1-P1 {lbb:11s} n={n:3d}: beta^2 {result.beta_squared:.3e}")
        lines.append(f"| {lbb} | " + " | ".join(cells) + " |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--circles", type=int, default=12, help="circles per mesh")
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32, 64], help="n")
    parser.add_argument(
        "--tet-sizes", type=int, nargs="*", default=[4, 8, 12], help="n of the P1-P1 tetrahedra"
    )
    args = parser.parse_args()
    rows = []
    for cell, degree in ELEMENTS:
        for lbb, (treatment, ghost_penalty) in TREATMENTS.items():
            for n in args.sizes:
                mesh = dolfinx.mesh.create_unit_square(
                    MPI.COMM_WORLD, n, n, dolfinx.mesh.CellType[cell]
                )
                start, b2 = time.perf_counter(), []
                for cx, cy, r in circles(args.circles, n, np.random.default_rng(n)):
                    circle = lambda x, c=(cx, cy), r=r: np.hypot(x[0] - c[0], x[1] - c[1]) - r  # noqa: E731
                    cut = CutMesh(mesh, circle, degree=2)
                    law = Bonded(lbb=treatment)
                    material = Material(100e6, 0.3)
                    problem = Problem(cut, degree, material, law, ghost_penalty=ghost_penalty)
                    b2.append(inf_sup_constant(problem).beta_squared)
                b = np.sqrt(np.maximum(b2, 0.0))
                rows.append(
                    {
                        "cell": cell,
                        "degree": degree,
                        "lbb": lbb,
                        "n": n,
                        "beta_min": float(b.min()),
                        "beta_median": float(np.median(b)),
                        "indefinite": int((np.array(b2) < 0).sum()),
                        "beta_squared": b2,
                    }
                )
                note(
                    f"{cell:13s} P{degree}-P1 {lbb:21s} n={n:3d}: beta min {b.min():.3e} "
                    f"median {np.median(b):.3e}, indefinite {rows[-1]['indefinite']}/"
                    f"{len(b2)} ({time.perf_counter() - start:.1f} s)"
                )
    lines = [
        "| cell | element | lbb | "
        + " | ".join(f"n={n}: min / median beta" for n in args.sizes)
        + " | slope of min (last pair) | indefinite |",
        "|---|---|---|" + "---|" * len(args.sizes) + "---|---|",
    ]
    for cell, degree in ELEMENTS:
        for lbb in TREATMENTS:
            sel = [r for r in rows if (r["cell"], r["degree"], r["lbb"]) == (cell, degree, lbb)]
            mins = [r["beta_min"] for r in sel]
            slope = (
                math.log(mins[-1] / mins[-2]) / math.log(args.sizes[-1] / args.sizes[-2])
                if len(mins) > 1 and min(mins[-2:]) > 0
                else float("nan")
            )
            cells = " | ".join(f"{r['beta_min']:.2e} / {r['beta_median']:.2e}" for r in sel)
            lines.append(
                f"| {cell} | P{degree}-P1 | {lbb} | {cells} | {slope:.2f} | "
                f"{sum(r['indefinite'] for r in sel)}/{args.circles * len(sel)} |"
            )
    lines += tetrahedra(args.tet_sizes)
    RESULTS.mkdir(exist_ok=True)
    plot(rows, RESULTS / "inf_sup.png")
    (RESULTS / "inf_sup.md").write_text("\n".join(lines) + "\n")
    (RESULTS / "inf_sup.json").write_text(json.dumps({"rows": rows, "args": vars(args)}))
    print("\n".join(lines))
    print(f"wrote {RESULTS / 'inf_sup.md'} and .json")


if __name__ == "__main__":
    main()
