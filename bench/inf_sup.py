"""The numerical inf-sup test of every 2D element: the discrete inf-sup constant
(:func:`xfem_contact.mechanics.inf_sup.inf_sup_constant`) of P1-P1, P2-P1 and P2-P2 on
triangles and quadrilaterals, for each LBB treatment (none, restriction, stabilized; stabilized
with the ghost penalty raised to the stabilisation's weight, 0.1, too), on n = 8, 16,
32, 64 cells per side of the unit square, over circles at random centres and radii (a
third of them passing within 1e-6 h of a mesh node: tiny cuts on purpose). Prints, per
element, treatment and n, the least and median beta and the count of indefinite pairs
(beta^2 < 0), and the slope of the least beta in log n over the last pair; then P1-P1
on tetrahedra cut by a sphere (``--tet-sizes``) without LBB treatment, restricted and
stabilised. Writes ``bench/results/inf_sup.{json,md,png}``.

Run: ``python bench/inf_sup.py [--circles 50] [--sizes 8 16 32 64] [--elements P2-P2]``
(``make bench``; default P1-P1 and P2-P1, with the tetrahedra; other ``--elements``
write ``bench/results/inf_sup_<elements>.{json,md,png}``). The sphere alone, for
other elements and cells: ``python bench/inf_sup.py --solid --cells tetrahedron
hexahedron --elements P2-P1 --treatments none restriction stabilized --tet-sizes 4 8
12`` (``bench/results/inf_sup_3d_<cells>_<elements>.{json,md}``, Q for P on hexahedra;
with fewer treatments the treatments and sizes join the name).
"""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import argparse
import json
import math
import pathlib
import sys
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
#: (cell, displacement degree, multiplier degree)
ELEMENTS = [
    (cell, degree, multiplier)
    for cell in ("triangle", "quadrilateral")
    for degree, multiplier in ((1, 1), (2, 1), (2, 2))
]


#: The elements of ``bench/results/inf_sup.*``
DEFAULT_ELEMENTS = ("P1-P1", "P2-P1")


def label(degree: int, multiplier: int) -> str:
    """``P2-P1``: the displacement and multiplier degrees."""
    return f"P{degree}-P{multiplier}"


#: label: (lbb, ghost penalty, cell aggregation; None: the default)
TREATMENTS = {
    "none": ("none", None, None),
    "restriction": ("restriction", None, None),
    "stabilized": ("stabilized", None, None),
    "stabilized, ghost 0.1": ("stabilized", 0.1, None),
    "stabilized, aggregation 0.25": ("stabilized", None, 0.25),
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


def plot(rows: list[dict], elements: list, path: pathlib.Path) -> None:
    """Least beta against n, one panel per element, one line per treatment."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        1, len(elements), figsize=(4 * len(elements), 3.6), sharey=True, squeeze=False
    )
    for ax, element in zip(axes[0], elements, strict=True):
        cell, degree, multiplier = element
        for lbb in dict.fromkeys(r["lbb"] for r in rows):
            sel = [r for r in rows if _key(r) == (*element, lbb)]
            ns = [r["n"] for r in sel]
            ax.loglog(ns, [max(r["beta_min"], 1e-8) for r in sel], "o-", label=f"{lbb} (least)")
        ax.set_title(f"{cell}, {label(degree, multiplier)}")
        ax.set_xlabel("cells per side n")
    axes[0][0].set_ylabel("discrete inf-sup constant beta")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _key(row: dict) -> tuple:
    return row["cell"], row["degree"], row.get("multiplier_degree", 1), row["lbb"]


#: LBB treatments of the sphere in the unit cube (the 2D rows' others are 2D studies)
SOLID_TREATMENTS = ("none", "restriction", "stabilized")
#: Cell of each 3D element label's family: P on tetrahedra, Q on hexahedra
SOLID_CELLS = {"tetrahedron": "P", "hexahedron": "Q"}


def solids(
    sizes: list[int], cells: list[str], elements: list[tuple[int, int]], treatments
) -> tuple[list[str], list[dict]]:
    """The unit cube's tetrahedra (6 n^3) or hexahedra (n^3) cut by the sphere of radius
    0.2 about its centre, each element ``(degree, multiplier degree)`` and treatment:
    lines of a Markdown table of beta (least eigenvalue beta^2 when negative; reduced
    multiplier unknowns) with the slope of beta in log n over the last pair, and the
    rows."""
    if not sizes:
        return [], []
    lines = [
        "",
        "Sphere R = 0.2 about the centre of the unit cube (beta; reduced multiplier unknowns):",
        "",
        "| cell | element | lbb | " + " | ".join(f"n={n}" for n in sizes) + " | slope |",
        "|---|---|---|" + "---|" * len(sizes) + "---|",
    ]
    rows = []
    for cell in cells:
        family = SOLID_CELLS[cell]
        for degree, multiplier in elements:
            name = f"{family}{degree}-{family}{multiplier}"
            for lbb in treatments:
                found = []
                for n in sizes:
                    start = time.perf_counter()
                    mesh = dolfinx.mesh.create_unit_cube(
                        MPI.COMM_WORLD, n, n, n, dolfinx.mesh.CellType[cell]
                    )
                    sphere = lambda x: np.sqrt(((x.T - 0.5) ** 2).sum(axis=1)) - 0.2  # noqa: E731
                    cut = CutMesh(mesh, sphere, degree=2)
                    law = Bonded(lbb=lbb, multiplier_degree=multiplier)
                    result = inf_sup_constant(Problem(cut, degree, Material(100e6, 0.3), law))
                    found.append(result)
                    rows.append(
                        {
                            "cell": cell,
                            "degree": degree,
                            "multiplier_degree": multiplier,
                            "lbb": lbb,
                            "n": n,
                            "beta": result.beta,
                            "beta_squared": result.beta_squared,
                            "multipliers": result.multipliers,
                        }
                    )
                    note(
                        f"{cell} {name} {lbb:11s} n={n:3d}: beta {result.beta:.3e} "
                        f"({result.multipliers} multipliers, {time.perf_counter() - start:.1f} s)"
                    )
                slope = (
                    math.log(found[-1].beta / found[-2].beta) / math.log(sizes[-1] / sizes[-2])
                    if len(found) > 1 and min(r.beta for r in found[-2:]) > 0
                    else float("nan")
                )
                values = " | ".join(
                    (f"{r.beta:.3f}" if r.beta_squared > 0 else f"beta^2 {r.beta_squared:.2e}")
                    + f" ({r.multipliers})"
                    for r in found
                )
                lines.append(f"| {cell} | {name} | {lbb} | {values} | {slope:.2f} |")
    return lines, rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--circles", type=int, default=12, help="circles per mesh")
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32, 64], help="n")
    parser.add_argument(
        "--tet-sizes", type=int, nargs="*", default=[4, 8, 12], help="n of the sphere's cube"
    )
    parser.add_argument(
        "--solid",
        action="store_true",
        help="the sphere only, for --elements and --cells (results in inf_sup_3d_<...>.*)",
    )
    parser.add_argument(
        "--cells",
        nargs="+",
        choices=list(SOLID_CELLS),
        default=["tetrahedron"],
        help="cells of the sphere's cube (with --solid)",
    )
    parser.add_argument(
        "--elements",
        nargs="+",
        choices=sorted({label(d, m) for _, d, m in ELEMENTS}),
        default=list(DEFAULT_ELEMENTS),
        help="these elements (default P1-P1 P2-P1; others: results in inf_sup_<elements>.*)",
    )
    parser.add_argument(
        "--treatments",
        nargs="+",
        choices=list(TREATMENTS),
        default=list(TREATMENTS),
        help="these LBB treatments (default all; fewer: results in inf_sup_<...>_<treatments>.*)",
    )
    args = parser.parse_args()
    if args.solid:
        solid_only(args)
        return
    elements = [e for e in ELEMENTS if label(*e[1:]) in args.elements]
    treatments = {k: v for k, v in TREATMENTS.items() if k in args.treatments}
    default = sorted(args.elements) == sorted(DEFAULT_ELEMENTS) and len(treatments) == len(
        TREATMENTS
    )
    rows = []
    for cell, degree, multiplier in elements:
        for lbb, (treatment, ghost_penalty, aggregation) in treatments.items():
            for n in args.sizes:
                mesh = dolfinx.mesh.create_unit_square(
                    MPI.COMM_WORLD, n, n, dolfinx.mesh.CellType[cell]
                )
                start, b2 = time.perf_counter(), []
                for cx, cy, r in circles(args.circles, n, np.random.default_rng(n)):
                    circle = lambda x, c=(cx, cy), r=r: np.hypot(x[0] - c[0], x[1] - c[1]) - r  # noqa: E731
                    cut = CutMesh(mesh, circle, degree=2)
                    law = Bonded(lbb=treatment, multiplier_degree=multiplier)
                    material = Material(100e6, 0.3)
                    problem = Problem(
                        cut,
                        degree,
                        material,
                        law,
                        ghost_penalty=ghost_penalty,
                        aggregation=aggregation,
                    )
                    b2.append(inf_sup_constant(problem).beta_squared)
                b = np.sqrt(np.maximum(b2, 0.0))
                rows.append(
                    {
                        "cell": cell,
                        "degree": degree,
                        "multiplier_degree": multiplier,
                        "lbb": lbb,
                        "n": n,
                        "beta_min": float(b.min()),
                        "beta_median": float(np.median(b)),
                        "indefinite": int((np.array(b2) < 0).sum()),
                        "beta_squared": b2,
                    }
                )
                note(
                    f"{cell:13s} {label(degree, multiplier)} {lbb:21s} n={n:3d}: beta min "
                    f"{b.min():.3e} median {np.median(b):.3e}, indefinite {rows[-1]['indefinite']}/"
                    f"{len(b2)} ({time.perf_counter() - start:.1f} s)"
                )
    lines = [
        "| cell | element | lbb | "
        + " | ".join(f"n={n}: min / median beta" for n in args.sizes)
        + " | slope of min (last pair) | indefinite |",
        "|---|---|---|" + "---|" * len(args.sizes) + "---|---|",
    ]
    for cell, degree, multiplier in elements:
        for lbb in treatments:
            sel = [r for r in rows if _key(r) == (cell, degree, multiplier, lbb)]
            mins = [r["beta_min"] for r in sel]
            slope = (
                math.log(mins[-1] / mins[-2]) / math.log(args.sizes[-1] / args.sizes[-2])
                if len(mins) > 1 and min(mins[-2:]) > 0
                else float("nan")
            )
            cells = " | ".join(f"{r['beta_min']:.2e} / {r['beta_median']:.2e}" for r in sel)
            lines.append(
                f"| {cell} | {label(degree, multiplier)} | {lbb} | {cells} | {slope:.2f} | "
                f"{sum(r['indefinite'] for r in sel)}/{args.circles * len(sel)} |"
            )
    parts = list(args.elements)
    if len(treatments) < len(TREATMENTS):
        parts += [t.replace(", ", "_").replace(" ", "_") for t in treatments]
    name = "inf_sup" if default else "_".join(["inf_sup", *parts])
    if default:
        lines += solids(args.tet_sizes, ["tetrahedron"], [(1, 1)], SOLID_TREATMENTS)[0]
    RESULTS.mkdir(exist_ok=True)
    plot(rows, elements, RESULTS / f"{name}.png")
    (RESULTS / f"{name}.md").write_text("\n".join(lines) + "\n")
    (RESULTS / f"{name}.json").write_text(json.dumps({"rows": rows, "args": vars(args)}))
    print("\n".join(lines))
    print(f"wrote {RESULTS / name}.md and .json")


def solid_only(args) -> None:
    """The sphere's table alone (``--solid``), written with its command to
    ``bench/results/inf_sup_3d_<cells>_<elements>.{md,json}``."""
    elements = sorted({(d, m) for _, d, m in ELEMENTS if label(d, m) in args.elements})
    treatments = [t for t in args.treatments if t in SOLID_TREATMENTS]
    lines, rows = solids(args.tet_sizes, args.cells, elements, treatments)
    command = "python bench/inf_sup.py " + " ".join(sys.argv[1:])
    lines = [f"`{command}`", *lines]
    parts = [*args.cells, *args.elements]
    if len(treatments) < len(SOLID_TREATMENTS):
        parts += [*treatments, *map(str, args.tet_sizes)]
    name = "_".join(["inf_sup_3d", *parts])
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{name}.md").write_text("\n".join(lines) + "\n")
    (RESULTS / f"{name}.json").write_text(json.dumps({"rows": rows, "args": vars(args)}))
    print("\n".join(lines))
    print(f"wrote {RESULTS / name}.md and .json")


if __name__ == "__main__":
    main()
