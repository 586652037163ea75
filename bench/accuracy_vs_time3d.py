"""What accuracy costs in 3D: the sticking sphere's pressure error against whole-process
time and peak memory, X-FEM against the body-fitted route, measured in the same run.

The case: :func:`xfem_contact.cases.solid.sphere_problem`, sticking, the quadric level
set (P2 holds the sphere exactly), one material, triaxial pressures; the exact contact
pressure is ``n.sigma.n`` of the uniform stress. X-FEM sweeps: displacement degree 1
and 2 on tetrahedra and hexahedra, direct (MUMPS) and iterative (band multigrid)
solves, several cells per edge ``n`` (``bench/scale3d.py``'s worker). Body-fitted
baseline: a gmsh mesh of the cube with the sphere as an internal surface (10-node
curved tetrahedra for P2), plain DOLFINx elasticity (the sphere and the matrix one
body: sticking and one material), CG + GAMG with the six rigid modes
(``bench/plain_elasticity.py``'s forms, loads and solver), the pressure
``n_h.sigma_h.n_h`` on the meshed sphere (the mean of its two sides, the mesh's
normal) against ``n.sigma.n`` with the exact sphere's normal at the same point; the
meshing is part of its time.

Each (sweep, size) runs in a process of its own (``bench/scale3d.py``'s
:func:`measured`): wall time from start to exit and peak resident memory. Writes
``bench/results/accuracy_vs_time3d.{json,md}`` and the Pareto plot (error against time
and against memory, the fronts circled) ``accuracy_vs_time3d.png``.

Run: ``python bench/accuracy_vs_time3d.py [--quick]`` (``make bench``: ``--quick``);
``--report-only`` redoes the report from the saved JSON, ``--only body-fitted`` (or
``X-FEM``) runs one method's sweeps again.
"""

import argparse
import json
import math
import pathlib
import sys

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from accuracy_vs_time import pareto, report
from scale3d import measured

from xfem_contact.io.progress import note

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
CASE = "sticking sphere"
X, FIT = "X-FEM", "body-fitted"
#: (method, option, worker arguments, sizes (full run), sizes (--quick)); X-FEM sizes are
#: cells per edge, body-fitted ones the gmsh cell size (m)
# fmt: off
SWEEPS = [
    (X, "P1 tetrahedra, direct", ["xfem", "direct", "1", "tetrahedron"], [4, 8, 12, 16], [4, 8]),
    (X, "P2 tetrahedra, direct", ["xfem", "direct", "2", "tetrahedron"], [4, 6, 8, 10, 12], [4, 6]),
    (X, "P2 tetrahedra, iterative", ["xfem", "iterative", "2", "tetrahedron"],
     [4, 8, 12, 16, 20], [4, 6]),
    (X, "Q1 hexahedra, direct", ["xfem", "direct", "1", "hexahedron"], [4, 8, 12, 16], [4]),
    (X, "Q2 hexahedra, direct", ["xfem", "direct", "2", "hexahedron"], [4, 6, 8], [4]),
    (FIT, "P2 curved tetrahedra, CG + GAMG", ["fitted", "2"], [0.14, 0.1, 0.07, 0.05], [0.14]),
    (FIT, "P1 tetrahedra, CG + GAMG", ["fitted", "1"], [0.1, 0.07, 0.05, 0.035], [0.1]),
]
# fmt: on

#: The cube with the sphere (centre cx, cy, cz; radius r) as an internal surface: one
#: volume group "solid", the surface group "interface", and the five points
#: ``bench/plain_elasticity.py``'s HELD_3D holds embedded in the faces (mesh nodes);
#: format with h, cx, cy, cz, r
SPHERE_GEO = """
SetFactory("OpenCASCADE");
Box(1) = {{0, 0, 0, 1, 1, 1}};
Sphere(2) = {{{cx}, {cy}, {cz}, {r}}};
BooleanFragments{{ Volume{{1}}; Delete; }}{{ Volume{{2}}; Delete; }}
e = 1e-6;
Point(1001) = {{0.5, 0, 0.5, {h}}}; Point(1002) = {{0.5, 1, 0.5, {h}}};
Point(1003) = {{0.5, 0.5, 0, {h}}}; Point(1004) = {{0.5, 0.5, 1, {h}}};
Point(1005) = {{0, 0.5, 0.5, {h}}};
sy0() = Surface In BoundingBox{{-e, -e, -e, 1 + e, e, 1 + e}};
sy1() = Surface In BoundingBox{{-e, 1 - e, -e, 1 + e, 1 + e, 1 + e}};
sz0() = Surface In BoundingBox{{-e, -e, -e, 1 + e, 1 + e, e}};
sz1() = Surface In BoundingBox{{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e}};
sx0() = Surface In BoundingBox{{-e, -e, -e, e, 1 + e, 1 + e}};
Point{{1001}} In Surface{{sy0(0)}}; Point{{1002}} In Surface{{sy1(0)}};
Point{{1003}} In Surface{{sz0(0)}}; Point{{1004}} In Surface{{sz1(0)}};
Point{{1005}} In Surface{{sx0(0)}};
sphere() = Surface In BoundingBox{{{cx} - {r} - e, {cy} - {r} - e, {cz} - {r} - e,
                                   {cx} + {r} + e, {cy} + {r} + e, {cz} + {r} + e}};
v() = Volume{{:}};
Physical Volume("solid") = {{v()}};
Physical Surface("interface") = {{sphere()}};
Mesh.MeshSizeMax = {h};
Mesh.MeshSizeMin = {h} / 2;
"""


def fitted(h: float, degree: int) -> dict:
    """The body-fitted route at cell size ``h`` (m): its pressure error and dofs.
    Collective."""
    import plain_elasticity
    import ufl
    from mpi4py import MPI

    from xfem_contact.cases.body_fitted import interface_pressure_error, mesh_geo
    from xfem_contact.cases.paper import integrate
    from xfem_contact.cases.solid import SOLID, SPHERE_CENTRE, SPHERE_RADIUS, TRIAXIAL

    assert (SOLID.E, SOLID.nu) == (plain_elasticity.SOLID_E, plain_elasticity.SOLID_NU)
    assert tuple(TRIAXIAL) == plain_elasticity.TRIAXIAL
    cx, cy, cz = SPHERE_CENTRE
    text = SPHERE_GEO.format(h=h, cx=cx, cy=cy, cz=cz, r=SPHERE_RADIUS)
    comm = MPI.COMM_WORLD
    gm = mesh_geo(text, degree, "tetrahedron", comm)
    result, u = plain_elasticity.solve(
        lambda: plain_elasticity.triaxial(gm.mesh, degree), None, {}, "gamg"
    )
    x = ufl.SpatialCoordinate(gm.mesh)("+")
    arm = x - ufl.as_vector(SPHERE_CENTRE)
    normal = arm / ufl.sqrt(ufl.dot(arm, arm))
    exact = ufl.dot(normal, ufl.dot(ufl.diag(ufl.as_vector(TRIAXIAL)), normal))
    error = interface_pressure_error(u, gm, SOLID, exact)
    misfit = SOLID.stress(u) - ufl.diag(ufl.as_vector(TRIAXIAL))
    size = integrate(ufl.inner(misfit, misfit) * ufl.dx) / integrate(
        sum(s**2 for s in TRIAXIAL) * ufl.dx(domain=gm.mesh)
    )
    return {
        "dofs": result["dofs"],
        "krylov": [result["krylov"]],
        "error": error,
        "stress_error": float(np.sqrt(size)),
    }


def run(sweep, size) -> dict | None:
    """One (sweep, size) in its own process; its row, or None (failed: said)."""
    method, option, worker, *_ = sweep
    if worker[0] == "xfem":
        command = [sys.executable, str(ROOT / "bench" / "scale3d.py"), "--case", str(size)]
        command += worker[1:]
    else:
        command = [sys.executable, __file__, "--fitted", str(size), worker[1]]
    row = measured(command)
    if "failed" in row:
        note(f"{method} / {option} / {size}: failed ({row['failed']})")
        return None
    return {
        "case": CASE,
        "method": method,
        "option": option,
        "size": size,
        "dofs": row["dofs"],
        "error": row["error"],
        "time_s": row["wall_s"],
        "peak_rss_mb": row["rss_mb"],
        "krylov": row["krylov"],
        "stress_error": row.get("stress_error"),
    }


def plot(rows: list[dict], path: pathlib.Path) -> None:
    """Error against time and against peak memory, one curve a sweep, the Pareto fronts
    circled."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), sharey=True)
    curves = {}
    for r in rows:
        curves.setdefault((r["method"], r["option"]), []).append(r)
    for ax, key, label in (
        (axes[0], "time_s", "whole-process wall time (s)"),
        (axes[1], "peak_rss_mb", "peak resident memory (MB)"),
    ):
        for (method, option), curve in curves.items():
            style = "o-" if method == X else "s--"
            values = [r[key] for r in curve]
            ax.loglog(values, [r["error"] for r in curve], style, markersize=4)
            ax.lines[-1].set_label(f"{method}: {option}")
        front = [rows[i] for i in pareto([r | {"time_s": r[key]} for r in rows])]
        front.sort(key=lambda r: r[key])
        ax.loglog(
            [r[key] for r in front],
            [r["error"] for r in front],
            "ko",
            markerfacecolor="none",
            markersize=10,
            label="Pareto front",
        )
        ax.set_xlabel(label)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("relative L2 error of the contact pressure")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle(f"{CASE} (R = 0.2 m, triaxial -1/-2/-3 Pa): accuracy against cost")
    fig.tight_layout(rect=(0, 0.12, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def memory_conclusions(rows: list[dict]) -> list[str]:
    """At the memory of each body-fitted run, which route reaches the lower error."""
    fitted = [r for r in rows if r["method"] == FIT]
    xfem = [r for r in rows if r["method"] == X]
    winners = []
    for budget in sorted(r["peak_rss_mb"] for r in fitted):
        a = min((r["error"] for r in xfem if r["peak_rss_mb"] <= budget), default=math.inf)
        b = min(r["error"] for r in fitted if r["peak_rss_mb"] <= budget)
        winner = X if a < b else FIT
        if not winners or winners[-1][1] != winner:
            winners.append((budget, winner))
    if not winners:
        return []
    spans = ", ".join(f"{w} from {m:.0f} MB" for m, w in winners)
    return [f"- {CASE}, by peak memory: lower error for the same memory: {spans}."]


def publish(rows: list[dict], out: pathlib.Path) -> str:
    """The plot and the markdown beside ``out``; returns the markdown."""
    plot(rows, out.with_suffix(".png"))
    lines = [report(rows, None), *memory_conclusions(rows), ""]
    lines += [
        "The body-fitted pressure is read with the meshed sphere's normal; its stress error "
        "in the volume (relative L2, last column) shows what is left once the normal is the "
        "exact one: the uniform stress lies in every body-fitted space.",
        "",
        "| method | option | size | dofs | Krylov | pressure error | time (s) | peak RSS (MB) "
        "| stress error in the volume |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        stress = "-" if r.get("stress_error") is None else f"{r['stress_error']:.1e}"
        lines.append(
            f"| {r['method']} | {r['option']} | {r['size']} | {r['dofs']:,} | {r['krylov']} | "
            f"{r['error']:.3e} | {r['time_s']:.1f} | {r['peak_rss_mb']:.0f} | {stress} |"
        )
    text = "\n".join(lines) + "\n"
    out.with_suffix(".md").write_text(text)
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the smallest sizes only")
    parser.add_argument("--report-only", action="store_true", help="the report from the JSON")
    parser.add_argument("--out", default=str(RESULTS / "accuracy_vs_time3d.json"))
    parser.add_argument(
        "--only", choices=[X, FIT], help="run this method's sweeps again, keep the saved others"
    )
    parser.add_argument("--fitted", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.fitted:
        from mpi4py import MPI

        result = fitted(float(args.fitted[0]), int(args.fitted[1]))
        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(result), flush=True)
        return
    out = pathlib.Path(args.out)
    if args.report_only:
        print(publish(json.loads(out.read_text()), out))
        return
    sweeps = [sweep for sweep in SWEEPS if args.only in (None, sweep[0])]
    for sweep in sweeps:  # JIT caches warm: no compilation in the measured runs
        run(sweep, sweep[4][0])
    rows = []
    if args.only is not None:
        rows = [r for r in json.loads(out.read_text()) if r["method"] != args.only]
    for sweep in sweeps:
        for size in sweep[4] if args.quick else sweep[3]:
            row = run(sweep, size)
            if row is not None:
                rows.append(row)
                note(
                    f"{row['method']} / {row['option']} / {size}: error {row['error']:.3e}, "
                    f"{row['dofs']:,} dofs, {row['time_s']:.1f} s, {row['peak_rss_mb']:.0f} MB"
                )
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(rows, indent=1))  # after each sweep: a long run keeps its rows
    print(publish(rows, out))


if __name__ == "__main__":
    main()
