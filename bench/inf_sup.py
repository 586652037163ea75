"""The numerical inf-sup test of every element: the discrete inf-sup constant
(:func:`xfem_contact.mechanics.inf_sup.inf_sup_constant`) of P1-P1, P2-P1 and P2-P2 on
triangles and quadrilaterals and of P1-P1 and P2-P1 (Q1-Q1, Q2-Q1) on tetrahedra and
hexahedra, for each LBB treatment, on interfaces cut at random (tiny cuts on purpose), on
cracks and on a sphere.

The studies (``--study``):

- ``circles`` (default): the unit square, n = 8, 16, 32, 64 cells a side, cut by circles
  at random centres and radii (50 a mesh; a third of them passing within 1e-6 h of a
  mesh node);
- ``crack``: the unit square cut by straight cracks at random centres, directions and
  half lengths (12 a mesh; a third of them along a line 1e-6 h from a node), the lips
  bonded, with topological tip enrichment (the smallest displacement space: the least
  ``beta``); a crack refuses the stabilisation;
- ``3d``: the unit cube (tetrahedra or hexahedra, n cells a side) cut by the sphere of
  radius 0.2 about its centre (``--spheres K``: and K - 1 random ones, every third
  through a node to 1e-6 h).

The treatments (``--treatments``): none, restriction, stabilized; stabilized with the
ghost penalty raised to the stabilisation's weight (0.1), with cell aggregation, or with
the scale of the cut (``stabilization_length="cut"``, or ``"patch"``, credited through
the ghost penalty, also with its higher derivatives' factor ``ghost_penalty_higher``
0.01); ``--weight`` sets the stabilisation's weight ``gamma``.
Prints, per element, treatment and n, the least and median beta, the count of
indefinite pairs (beta^2 < 0; without a treatment, round-off of a zero eigenvalue: a
spurious multiplier), the count of samples whose displacement block has a negative
eigenvalue (unstable even where beta^2 > 0: the stabilisation took more than the bulk
energy) and the slope of the least beta in log n over the last pair.
Writes ``bench/results/<name>.{json,md,png}`` after each element and treatment (``name``:
``inf_sup``, ``inf_sup_crack``, ``inf_sup_3d``, with the elements and treatments that
differ from the study's default, or ``--name``). BLAS runs on one thread (the dense
eigenproblems are small; threads only contend).

Run: ``python bench/inf_sup.py [--study circles|crack|3d] [--circles 50] [--sizes 8 16
32 64] [--elements P2-P2] [--treatments ...] [--weight 0.75]``.
"""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # before numpy: one BLAS thread
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import xfem_contact  # noqa: E402, F401  (before dolfinx)

# isort: split
import argparse
import json
import math
import pathlib
import shlex
import sys
import time
from collections.abc import Callable, Iterator

import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.meshes import ghosted_partitioner
from xfem_contact.io.progress import note
from xfem_contact.mechanics.defaults import DEFAULT
from xfem_contact.mechanics.inf_sup import InfSup, inf_sup_constant
from xfem_contact.mechanics.laws import Bonded
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
MATERIAL = Material(100e6, 0.3)
#: (cell, displacement degree, multiplier degree) of each study
ELEMENTS = {
    "circles": [
        (cell, degree, multiplier)
        for cell in ("triangle", "quadrilateral")
        for degree, multiplier in ((1, 1), (2, 1), (2, 2))
    ],
    "crack": [
        (cell, degree, multiplier)
        for cell in ("triangle", "quadrilateral")
        for degree, multiplier in ((1, 1), (2, 1), (2, 2))
    ],
    "3d": [(cell, degree, 1) for cell in ("tetrahedron", "hexahedron") for degree in (1, 2)],
}
#: The elements of each study's default result
DEFAULT_ELEMENTS = {
    "circles": ("P1-P1", "P2-P1"),
    "crack": ("P1-P1", "P2-P1", "P2-P2"),
    "3d": ("P1-P1", "P2-P1"),
}
#: label: (lbb, ghost penalty, cell aggregation, stabilisation length, the ghost
#: penalty's factor of higher derivatives; None: the default)
TREATMENTS = {
    "none": ("none", None, None, "cell", None),
    "restriction": ("restriction", None, None, "cell", None),
    "stabilized": ("stabilized", None, None, "cell", None),
    "stabilized, ghost 0.1": ("stabilized", 0.1, None, "cell", None),
    "stabilized, aggregation 0.25": ("stabilized", None, 0.25, "cell", None),
    "stabilized, cut length": ("stabilized", None, None, "cut", None),
    "stabilized, patch length": ("stabilized", None, None, "patch", None),
    "stabilized, patch length, higher 0.01": ("stabilized", None, None, "patch", 0.01),
}
#: The treatments of each study's default result (the others: ``--treatments``); a crack
#: refuses the stabilisation (it squares the tip's singular traction on the lips)
DEFAULT_TREATMENTS = {
    "circles": ("none", "restriction", "stabilized"),
    "crack": ("none", "restriction"),
    "3d": ("none", "restriction", "stabilized"),
}
DEFAULT_SIZES = {"circles": (8, 16, 32, 64), "crack": (8, 16, 32, 64), "3d": (4, 8, 12)}


def label(degree: int, multiplier: int) -> str:
    """``P2-P1``: the displacement and multiplier degrees."""
    return f"P{degree}-P{multiplier}"


def circles(count: int, n: int, rng) -> list[tuple[float, float, float]]:
    """Random circles ``(cx, cy, r)`` inside the unit square; every third through a node
    to 1e-6 h."""
    out = []
    for k in range(count):
        cx, cy = rng.uniform(0.35, 0.65, 2)
        r = rng.uniform(0.12, 0.3)
        if k % 3 == 2:
            node = np.round(np.array([cx + r, cy]) * n) / n
            r = math.hypot(*(node - (cx, cy))) + 1e-6 / n
        out.append((float(cx), float(cy), float(r)))
    return out


def cracks(count: int, n: int, rng) -> list[tuple[float, float, float, float]]:
    """Random straight cracks ``(cx, cy, angle, a)`` (centre, direction in rad, half
    length) inside the unit square; every third along a line 1e-6 h from a node."""
    out = []
    for k in range(count):
        cx, cy = rng.uniform(0.4, 0.6, 2)
        angle, a = rng.uniform(0.0, math.pi), rng.uniform(0.15, 0.3)
        if k % 3 == 2:
            node = np.round(np.array([cx, cy]) * n) / n
            normal = np.array([-math.sin(angle), math.cos(angle)])
            cx, cy = node + 1e-6 / n * normal
        out.append((float(cx), float(cy), float(angle), float(a)))
    return out


def circle_cuts(n: int, cell: str, degree: int, count: int) -> Iterator[CutMesh]:
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, n, n, dolfinx.mesh.CellType[cell])
    for cx, cy, r in circles(count, n, np.random.default_rng(n)):
        circle = lambda x, c=(cx, cy), r=r: np.hypot(x[0] - c[0], x[1] - c[1]) - r  # noqa: E731
        yield CutMesh(mesh, circle, degree=2)


def crack_cuts(n: int, cell: str, degree: int, count: int) -> Iterator[CutMesh]:
    mesh = dolfinx.mesh.create_unit_square(
        MPI.COMM_WORLD, n, n, dolfinx.mesh.CellType[cell], partitioner=ghosted_partitioner()
    )
    for cx, cy, angle, a in cracks(count, n, np.random.default_rng(n)):
        d = np.array([math.cos(angle), math.sin(angle)])
        yield CutMesh(
            mesh,
            lambda x, c=(cx, cy), d=d: (x[1] - c[1]) * d[0] - (x[0] - c[0]) * d[1],
            degree=degree,
            tangent=lambda x, c=(cx, cy), d=d, a=a: (
                np.abs((x[0] - c[0]) * d[0] + (x[1] - c[1]) * d[1]) - a
            ),
        )


def spheres(count: int, n: int, rng) -> list[tuple[float, float, float, float]]:
    """``(cx, cy, cz, r)``: the sphere of radius 0.2 about the unit cube's centre, then
    random ones inside it, every third through a node to 1e-6 h."""
    out = [(0.5, 0.5, 0.5, 0.2)]
    for k in range(1, count):
        centre, r = rng.uniform(0.35, 0.65, 3), rng.uniform(0.12, 0.3)
        if k % 3 == 2:
            node = np.round((centre + (r, 0.0, 0.0)) * n) / n
            r = float(np.linalg.norm(node - centre)) + 1e-6 / n
        out.append((*map(float, centre), float(r)))
    return out


def sphere_cuts(n: int, cell: str, degree: int, count: int) -> Iterator[CutMesh]:
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, n, n, n, dolfinx.mesh.CellType[cell])
    for *c, r in spheres(count, n, np.random.default_rng(n)):
        sphere = lambda x, c=tuple(c), r=r: np.sqrt(((x.T - c) ** 2).sum(axis=1)) - r  # noqa: E731
        yield CutMesh(mesh, sphere, degree=2)


#: study: the cuts of one mesh ``(n, cell, displacement degree, count)``
CUTS: dict[str, Callable[..., Iterator[CutMesh]]] = {
    "circles": circle_cuts,
    "crack": crack_cuts,
    "3d": sphere_cuts,
}


def sample(
    study: str,
    cell: str,
    degree: int,
    multiplier: int,
    lbb: str,
    n: int,
    count: int,
    weight: float | None = None,
) -> tuple[list[InfSup] | None, str]:
    """The :class:`InfSup` of each cut of one mesh and ``""``; or None and the reason the
    problem refuses the treatment. ``weight``: the stabilisation's ``gamma`` (None: the
    default of the treatment's length)."""
    treatment, ghost_penalty, aggregation, length, higher = TREATMENTS[lbb]
    law = Bonded(
        lbb=treatment,
        multiplier_degree=multiplier,
        stabilization_length=length,
        multiplier_stabilization=weight,
    )
    out = []
    for cut in CUTS[study](n, cell, degree, count):
        try:
            problem = Problem(
                cut,
                degree,
                MATERIAL,
                law,
                ghost_penalty=ghost_penalty,
                ghost_penalty_higher=DEFAULT.ghost_penalty_higher if higher is None else higher,
                aggregation=aggregation,
                tip_radius=None,
            )
            out.append(inf_sup_constant(problem))
        except ValueError as refused:  # a treatment the problem refuses, e.g. on a crack
            return None, str(refused)
    return out, ""


def plot(rows: list[dict], path: pathlib.Path) -> None:
    """Least beta against n, one panel per element, one line per treatment."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    elements = list(dict.fromkeys((r["cell"], r["element"]) for r in rows))
    fig, axes = plt.subplots(
        1, len(elements), figsize=(4 * len(elements), 3.6), sharey=True, squeeze=False
    )
    for ax, (cell, element) in zip(axes[0], elements, strict=True):
        for lbb in dict.fromkeys(r["lbb"] for r in rows):
            sel = [r for r in rows if (r["cell"], r["element"], r["lbb"]) == (cell, element, lbb)]
            sel = [r for r in sel if r["beta_squared"]]
            if sel:
                ns, least = [r["n"] for r in sel], [max(r["beta_min"], 1e-8) for r in sel]
                ax.loglog(ns, least, "o-", label=f"{lbb} (least)")
        ax.set_title(f"{cell}, {element}")
        ax.set_xlabel("cells per side n")
    axes[0][0].set_ylabel("discrete inf-sup constant beta")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def table(rows: list[dict], sizes: list[int]) -> list[str]:
    """Markdown lines: per element and treatment, least / median beta of each n, the
    slope of the least beta over the last pair and the count of indefinite pairs."""
    lines = [
        "| cell | element | lbb | "
        + " | ".join(f"n={n}: min / median beta" for n in sizes)
        + " | slope of min (last pair) | indefinite | displacement block indefinite"
        " | multipliers (largest n) |",
        "|---|---|---|" + "---|" * len(sizes) + "---|---|---|---|",
    ]
    for cell, element, lbb in dict.fromkeys((r["cell"], r["element"], r["lbb"]) for r in rows):
        sel = [r for r in rows if (r["cell"], r["element"], r["lbb"]) == (cell, element, lbb)]
        if sel[0]["refused"]:
            lines.append(
                f"| {cell} | {element} | {lbb} | refused: {sel[0]['refused']} |"
                + " |" * (len(sizes) + 3)
            )
            continue
        mins = [r["beta_min"] for r in sel]
        slope = (
            math.log(mins[-1] / mins[-2]) / math.log(sel[-1]["n"] / sel[-2]["n"])
            if len(mins) > 1 and min(mins[-2:]) > 0
            else float("nan")
        )
        cells = " | ".join(f"{r['beta_min']:.2e} / {r['beta_median']:.2e}" for r in sel)
        indefinite = sum(r["indefinite"] for r in sel)
        total = sum(len(r["beta_squared"]) for r in sel)
        modes = sum(sum(m > 0 for m in r.get("negative_displacement_modes", [])) for r in sel)
        lines.append(
            f"| {cell} | {element} | {lbb} | {cells} | {slope:.2f} | {indefinite}/{total} | "
            f"{modes}/{total} | {max(sel[-1]['multipliers'], default='')} |"
        )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--study", choices=list(CUTS), default="circles", help="the cuts")
    parser.add_argument("--circles", type=int, default=50, help="circles per mesh")
    parser.add_argument("--cracks", type=int, default=12, help="cracks per mesh")
    parser.add_argument("--spheres", type=int, default=1, help="spheres per mesh (3d)")
    parser.add_argument("--sizes", type=int, nargs="+", help="n (default per study)")
    parser.add_argument(
        "--elements",
        nargs="+",
        choices=sorted({label(d, m) for elements in ELEMENTS.values() for _, d, m in elements}),
        help="these elements (default per study)",
    )
    parser.add_argument(
        "--cells", nargs="+", help="these cells only (default: both of the study's)"
    )
    parser.add_argument("--treatments", nargs="+", choices=list(TREATMENTS), help="LBB treatments")
    parser.add_argument(
        "--weight", type=float, help="the stabilisation's weight gamma (default: the length's)"
    )
    parser.add_argument("--name", help="results bench/results/NAME.* (default: see above)")
    args = parser.parse_args()
    study = args.study
    sizes = args.sizes or list(DEFAULT_SIZES[study])
    chosen = args.elements or list(DEFAULT_ELEMENTS[study])
    treatments = args.treatments or list(DEFAULT_TREATMENTS[study])
    elements = [e for e in ELEMENTS[study] if label(*e[1:]) in chosen]
    cells = {cell for cell, _, _ in ELEMENTS[study]}
    if args.cells is not None:
        if not set(args.cells) <= cells:
            raise ValueError(f"--cells of the {study} study must be among {sorted(cells)}")
        elements = [e for e in elements if e[0] in args.cells]
    if not elements:
        raise ValueError(f"--elements {chosen} has none in the {study} study: {ELEMENTS[study]}")
    count = {"circles": args.circles, "crack": args.cracks, "3d": args.spheres}[study]
    parts = [] if study == "circles" else [study]
    if sorted(chosen) != sorted(DEFAULT_ELEMENTS[study]):
        parts += chosen
    if list(treatments) != list(DEFAULT_TREATMENTS[study]):
        parts += [t.replace(", ", "_").replace(" ", "_") for t in treatments]
    if args.weight is not None:
        parts.append(f"weight_{args.weight:g}")
    name = args.name or "_".join(["inf_sup", *parts, *(args.cells or [])])
    command = shlex.join(["python", "bench/inf_sup.py", *sys.argv[1:]])
    rows = []
    for cell, degree, multiplier in elements:
        for lbb in treatments:
            for n in sizes:
                start = time.perf_counter()
                results, refused = sample(
                    study, cell, degree, multiplier, lbb, n, count, args.weight
                )
                b2 = [r.beta_squared for r in results or []]
                b = np.sqrt(np.maximum(b2, 0.0)) if b2 else np.zeros(1)
                rows.append(
                    {
                        "cell": cell,
                        "element": label(degree, multiplier),
                        "lbb": lbb,
                        "n": n,
                        "beta_min": float(b.min()),
                        "beta_median": float(np.median(b)),
                        "indefinite": int((np.array(b2) < 0).sum()),
                        "beta_squared": b2,
                        "multipliers": [r.multipliers for r in results or []],
                        "negative_displacement_modes": [
                            r.negative_displacement_modes for r in results or []
                        ],
                        "refused": refused,
                    }
                )
                note(
                    f"{cell:13s} {label(degree, multiplier)} {lbb:21s} n={n:3d}: "
                    + (
                        f"refused ({refused})"
                        if refused
                        else f"beta min {b.min():.3e} median {np.median(b):.3e}, indefinite "
                        f"{rows[-1]['indefinite']}/{len(b2)}"
                    )
                    + f" ({time.perf_counter() - start:.1f} s)"
                )
                if refused:
                    break
            write(rows, sizes, name, command, vars(args))  # each block: a long run's partial table
    print((RESULTS / f"{name}.md").read_text())
    print(f"wrote {RESULTS / name}.md and .json")


def write(rows: list[dict], sizes: list[int], name: str, command: str, args: dict) -> None:
    """``bench/results/<name>.{md,json,png}`` of ``rows``."""
    lines = [f"Command: `{command}`", "", *table(rows, sizes)]
    RESULTS.mkdir(exist_ok=True)
    plot(rows, RESULTS / f"{name}.png")
    (RESULTS / f"{name}.md").write_text("\n".join(lines) + "\n")
    (RESULTS / f"{name}.json").write_text(json.dumps({"rows": rows, "args": args}))


if __name__ == "__main__":
    main()
