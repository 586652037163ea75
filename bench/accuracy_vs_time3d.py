"""What accuracy costs in 3D: the contact pressure error of the sticking sphere and of the
concentric spheres against whole-process time and peak memory, X-FEM against the
body-fitted route, measured in the same run.

The cases (:mod:`xfem_contact.cases.solid`, SI units): the ``sticking sphere``
(:func:`~xfem_contact.cases.solid.sphere_problem`, R = 0.2 m in the unit cube, one
material, triaxial pressures -1/-2/-3 Pa, ``sticking``: the exact contact pressure is
``n.sigma.n`` of the uniform stress) and the ``concentric spheres``
(:func:`~xfem_contact.cases.solid.composite_sphere_problem`, a ball R = 0.35 m of another
material in the cube, ``frictionless``, the cube's boundary held by the exact radial field
of 3D Lame under hydrostatic compression: a uniform exact contact pressure).

X-FEM's level set is the one a user has: the signed distance of the sphere, interpolated
in P2 (``levelset="distance"``), so the interface and its normal are approximations of
the sphere. (The quadric ``(|x - c|^2 - R^2) / (2 R)``, which P2 holds exactly, makes the
sticking sphere a patch test, its error that of the cut rules' quadrature at 1e-7
whatever the mesh: ``bench/sphere_triaxial.py``; no cost study.) X-FEM sweeps:
displacement degree 1 and 2 on tetrahedra and hexahedra, the ``direct`` (MUMPS) and
``iterative`` (band multigrid) presets, several cells per edge ``n``.

Body-fitted baseline: gmsh meshes of the cube with the sphere as an internal surface
(10-node curved tetrahedra for P2), plain DOLFINx elasticity with the interface a mesh
surface of shared nodes (CG + GAMG with the six rigid modes). Both cases are closed
with a continuous displacement and, for the concentric spheres, no tangential traction:
the contact solution is the bonded one, so a conforming mesh is one body-fitted route
(as ``xfem_contact.cases.body_fitted`` does in 2D). The sticking sphere's loads and
point constraints are ``bench/plain_elasticity.py``'s; the concentric spheres' two
materials are piecewise constant by cell, the cube's boundary held by the exact field
interpolated. The pressure is ``n_h.sigma_h.n_h`` on the meshed sphere (the mean of its
two sides, the mesh's normal) against the exact one at the same point; the meshing is
part of its time.

Each (case, sweep, size) runs in a process of its own (``bench/scale3d.py``'s
:func:`measured`): wall time from start to exit, the process's CPU time (user +
system) and its peak resident memory; the load average is read before each run. On a
host shared with other jobs the wall time measures the load: the Pareto fronts and
conclusions use the CPU time. Writes ``bench/results/accuracy_vs_time3d.{json,md}`` and
the plot ``accuracy_vs_time3d.png`` (per case: error against CPU time and against peak
memory, the fronts circled).

Run: ``python bench/accuracy_vs_time3d.py [--quick] [--cases ...]`` (``make bench``:
``--quick``); ``--report-only`` redoes the report from the saved JSON, ``--resume`` keeps
the saved rows and runs the missing ones (without warming the JIT caches again).
"""

import argparse
import json
import math
import os
import pathlib
import shlex
import sys

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np
from accuracy_vs_time import digit_cost, pareto
from scale3d import measured

from xfem_contact.io.progress import note

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results"
STICKING, CONCENTRIC = "sticking sphere", "concentric spheres"
CASES = (STICKING, CONCENTRIC)
X, FIT = "X-FEM", "body-fitted"
#: (method, option, worker arguments, sizes (full run), sizes (--quick)); X-FEM sizes are
#: cells per edge, body-fitted ones the gmsh cell size (m)
# fmt: off
SWEEPS = [
    (FIT, "P2 curved tetrahedra, CG + GAMG", ["2"], [0.14, 0.1, 0.07], [0.14]),
    (FIT, "P1 tetrahedra, CG + GAMG", ["1"], [0.1, 0.07, 0.05], [0.1]),
    (X, "P1 tetrahedra, direct", ["direct", "1", "tetrahedron"], [4, 8, 12], [4]),
    (X, "P2 tetrahedra, direct", ["direct", "2", "tetrahedron"], [4, 6, 8], [4]),
    (X, "P2 tetrahedra, iterative", ["iterative", "2", "tetrahedron"], [8, 12], []),
    (X, "Q1 hexahedra, direct", ["direct", "1", "hexahedron"], [4, 8, 12], [4]),
    (X, "Q2 hexahedra, direct", ["direct", "2", "hexahedron"], [4, 6], []),
]
# fmt: on

#: The cube with the sphere (centre cx, cy, cz; radius r) as an internal surface: the
#: ball the volume group 1 ("ball"), the rest 2 ("matrix"), the sphere the surface group
#: "interface", and the five points ``bench/plain_elasticity.py``'s HELD_3D holds
#: embedded in the faces (mesh nodes); format with h, cx, cy, cz, r
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
ball() = Volume In BoundingBox{{{cx} - {r} - e, {cy} - {r} - e, {cz} - {r} - e,
                                {cx} + {r} + e, {cy} + {r} + e, {cz} + {r} + e}};
v() = Volume{{:}};
v() -= ball();
Physical Volume("ball", 1) = {{ball()}};
Physical Volume("matrix", 2) = {{v()}};
Physical Surface("interface") = {{sphere()}};
Mesh.MeshSizeMax = {h};
Mesh.MeshSizeMin = {h} / 2;
"""


def xfem(case: str, n: int, solver: str, degree: int, cell: str) -> dict:
    """The X-FEM solve of ``case`` (signed-distance level set) in this process: its
    pressure error, dofs, Newton and Krylov iterations. Collective."""
    from xfem_contact.cases.solid import (
        composite_sphere_problem,
        composite_sphere_traction_errors,
        sphere_errors,
        sphere_problem,
    )
    from xfem_contact.solvers.options import preset

    options = {"levelset": "distance", "petsc_options": preset(solver)}
    if case == STICKING:
        problem = sphere_problem(n, degree, "sticking", cell, **options)
    else:
        problem = composite_sphere_problem(n, degree, "frictionless", cell, **options)
    report = problem.solve()
    errors = sphere_errors if case == STICKING else composite_sphere_traction_errors
    return {
        "dofs": problem.space.dof_counts().total,
        "newton": report.iterations,
        "krylov": report.linear_iterations,
        "error": errors(problem)[0],
    }


def fitted(case: str, h: float, degree: int) -> dict:
    """The body-fitted route of ``case`` at cell size ``h`` (m): its pressure error and
    dofs. Collective."""
    import plain_elasticity
    import ufl
    from mpi4py import MPI

    from xfem_contact.cases.body_fitted import mesh_geo
    from xfem_contact.cases.paper import integrate
    from xfem_contact.cases.solid import (
        COMPOSITE_RADIUS,
        INCLUSION,
        SOLID,
        SPHERE_CENTRE,
        SPHERE_RADIUS,
        TRIAXIAL,
        composite_sphere_exact,
        composite_sphere_pressure,
    )

    assert (SOLID.E, SOLID.nu) == (plain_elasticity.SOLID_E, plain_elasticity.SOLID_NU)
    assert tuple(TRIAXIAL) == plain_elasticity.TRIAXIAL
    cx, cy, cz = SPHERE_CENTRE
    r = SPHERE_RADIUS if case == STICKING else COMPOSITE_RADIUS
    text = SPHERE_GEO.format(h=h, cx=cx, cy=cy, cz=cz, r=r)
    gm = mesh_geo(text, degree, "tetrahedron", MPI.COMM_WORLD)
    mesh = gm.mesh
    x = ufl.SpatialCoordinate(mesh)("+")
    arm = x - ufl.as_vector(SPHERE_CENTRE)
    normal = arm / ufl.sqrt(ufl.dot(arm, arm))
    if case == STICKING:
        setup = lambda: plain_elasticity.triaxial(mesh, degree)  # noqa: E731
        exact = ufl.dot(normal, ufl.dot(ufl.diag(ufl.as_vector(TRIAXIAL)), normal))
        moduli = {1: SOLID, 2: SOLID}
    else:
        setup = lambda: concentric(gm, degree, composite_sphere_exact(1))  # noqa: E731
        exact = composite_sphere_pressure()
        moduli = {1: INCLUSION, 2: SOLID}
    result, u = plain_elasticity.solve(setup, None, {}, "gamg")
    sigma = ufl.avg(stress(u, gm, moduli))
    n = ufl.FacetNormal(mesh)("+")
    dS = ufl.Measure("dS", domain=mesh, subdomain_data=gm.facet_tags)(gm.parts["interface"])
    p = ufl.dot(n, sigma * n)
    error = math.sqrt(integrate((p - exact) ** 2 * dS) / integrate(exact**2 * dS))
    stress_error = None
    if case == STICKING:  # the uniform stress lies in every body-fitted space
        misfit = SOLID.stress(u) - ufl.diag(ufl.as_vector(TRIAXIAL))
        size = integrate(ufl.inner(misfit, misfit) * ufl.dx) / integrate(
            sum(s**2 for s in TRIAXIAL) * ufl.dx(domain=mesh)
        )
        stress_error = float(np.sqrt(size))
    return {
        "dofs": result["dofs"],
        "newton": 1,
        "krylov": [result["krylov"]],
        "error": error,
        "stress_error": stress_error,
    }


def moduli_functions(gm, moduli: dict) -> tuple:
    """``(mu, lmbda)`` (Pa) as cellwise-constant functions on ``gm``'s mesh from
    ``moduli`` (volume group tag -> Material). Collective."""
    import basix.ufl
    import dolfinx.fem

    Q = dolfinx.fem.functionspace(gm.mesh, basix.ufl.element("DG", gm.mesh.basix_cell(), 0))
    mu, lmbda = dolfinx.fem.Function(Q), dolfinx.fem.Function(Q)
    for tag, material in moduli.items():
        cells = gm.cell_tags.find(tag)
        mu.x.array[cells], lmbda.x.array[cells] = material.mu, material.lmbda
    mu.x.scatter_forward()
    lmbda.x.scatter_forward()
    return mu, lmbda


def stress(u, gm, moduli: dict):
    """The stress (Pa, UFL) of ``u`` with ``moduli`` (volume group tag -> Material)."""
    import ufl

    mu, lmbda = moduli_functions(gm, moduli)
    eps = ufl.sym(ufl.grad(u))
    return 2 * mu * eps + lmbda * ufl.tr(eps) * ufl.Identity(3)


def concentric(gm, degree: int, exact):
    """The concentric spheres on the body-fitted mesh ``gm``: ``(V, a, L, bcs)``, the ball
    (group 1) ``INCLUSION``, the matrix (group 2) ``SOLID``, the cube's boundary held by
    ``exact`` (numpy callable of ``x`` ``(3, n)``) interpolated. Collective."""
    import basix.ufl
    import dolfinx.fem
    import dolfinx.mesh
    import ufl

    from xfem_contact.cases.solid import INCLUSION, SOLID

    mesh = gm.mesh
    V = dolfinx.fem.functionspace(
        mesh, basix.ufl.element("Lagrange", mesh.basix_cell(), degree, shape=(3,))
    )
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(stress(u, gm, {1: INCLUSION, 2: SOLID}), ufl.sym(ufl.grad(v))) * ufl.dx
    L = ufl.dot(dolfinx.fem.Constant(mesh, np.zeros(3)), v) * ufl.dx
    mesh.topology.create_connectivity(2, 3)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    held = dolfinx.fem.Function(V)
    held.interpolate(exact)
    bcs = [dolfinx.fem.dirichletbc(held, dolfinx.fem.locate_dofs_topological(V, 2, facets))]
    return V, a, L, bcs


def run(case: str, sweep, size) -> dict | None:
    """One (case, sweep, size) in its own process; its row, or None (failed: said)."""
    method, option, worker, *_ = sweep
    flag = "--xfem" if method == X else "--fitted"
    command = [sys.executable, __file__, flag, case, str(size), *worker]
    load = os.getloadavg()[0]
    row = measured(command)
    if "failed" in row:
        note(f"{case} / {method} / {option} / {size}: failed ({row['failed']})")
        return None
    return {
        "case": case,
        "method": method,
        "option": option,
        "size": size,
        "dofs": row["dofs"],
        "newton": row["newton"],
        "krylov": row["krylov"],
        "error": row["error"],
        "wall_s": row["wall_s"],
        "cpu_s": row["cpu_s"],
        "time_s": row["cpu_s"],  # the fronts' time
        "peak_rss_mb": row["rss_mb"],
        "load": load,
        "stress_error": row.get("stress_error"),
    }


def plot(rows: list[dict], path: pathlib.Path) -> None:
    """Per case, the error against CPU time and against peak memory, one curve a sweep,
    the Pareto fronts circled."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    cases = list(dict.fromkeys(r["case"] for r in rows))
    fig, axes = plt.subplots(len(cases), 2, figsize=(12, 4.4 * len(cases) + 1), squeeze=False)
    options = list(dict.fromkeys((r["method"], r["option"]) for r in rows))
    colours = dict(zip(options, plt.rcParams["axes.prop_cycle"].by_key()["color"], strict=False))
    for row_axes, case in zip(axes, cases, strict=True):
        chosen = [r for r in rows if r["case"] == case]
        for ax, key, label in (
            (row_axes[0], "cpu_s", "whole-process CPU time, user + system (s)"),
            (row_axes[1], "peak_rss_mb", "peak resident memory (MB)"),
        ):
            for method, option in options:
                curve = [r for r in chosen if (r["method"], r["option"]) == (method, option)]
                style = "o-" if method == X else "s--"
                ax.loglog(
                    [r[key] for r in curve],
                    [r["error"] for r in curve],
                    style,
                    color=colours[(method, option)],
                    markersize=4,
                    label=f"{method}: {option}",
                )
            front = [chosen[i] for i in pareto([r | {"time_s": r[key]} for r in chosen])]
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
            ax.set_title(case, fontsize=10)
            ax.xaxis.set_minor_locator(matplotlib.ticker.LogLocator(subs=(2.0, 5.0)))
            for axis in (ax.xaxis.set_major_formatter, ax.xaxis.set_minor_formatter):
                axis(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
            ax.grid(True, which="both", alpha=0.3)
        row_axes[0].set_ylabel("relative L2 error of the contact pressure")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8)
    fig.suptitle("3D contact, signed-distance level set: accuracy against cost")
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def winners(chosen: list[dict], key: str) -> list[tuple[float, str]]:
    """At the cost ``key`` of each run, which route has reached the lower error within
    it: the ``(budget, method)`` changes."""
    fit = [r for r in chosen if r["method"] == FIT]
    xf = [r for r in chosen if r["method"] == X]
    out = []
    for budget in sorted(r[key] for r in chosen):
        a = min((r["error"] for r in xf if r[key] <= budget), default=math.inf)
        b = min((r["error"] for r in fit if r[key] <= budget), default=math.inf)
        winner = X if a < b else FIT
        if not out or out[-1][1] != winner:
            out.append((budget, winner))
    return out


def summary(rows: list[dict]) -> list[str]:
    """Per case and sweep: its sizes, finest error, cost and the Pareto members; then
    per case the front and who wins at each body-fitted budget."""
    lines = [
        "| case | method | option | sizes | finest error | its CPU time (s) | dofs "
        "| peak RSS (MB) | one more digit costs (CPU) | on the CPU-time front |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    said = []
    for case in dict.fromkeys(r["case"] for r in rows):
        chosen = [r for r in rows if r["case"] == case]
        front = {id(chosen[i]) for i in pareto(chosen)}
        for key in dict.fromkeys((r["method"], r["option"]) for r in chosen):
            curve = [r for r in chosen if (r["method"], r["option"]) == key]
            last, cost = curve[-1], digit_cost(curve)
            on = [str(r["size"]) for r in curve if id(r) in front]
            lines.append(
                f"| {case} | {key[0]} | {key[1]} | {curve[0]['size']}..{last['size']} | "
                f"{last['error']:.2e} | {last['cpu_s']:.1f} | {last['dofs']:,} | "
                f"{last['peak_rss_mb']:.0f} | "
                + ("-" if math.isnan(cost) else f"x {cost:.1f}")
                + f" | {', '.join(on) or '-'} |"
            )
        members = [chosen[i] for i in sorted(pareto(chosen), key=lambda i: chosen[i]["cpu_s"])]
        text = ", ".join(
            f"{r['method']} {r['option']} {r['size']} ({r['error']:.1e}, {r['cpu_s']:.1f} s)"
            for r in members
        )
        said.append(f"- {case}, the CPU-time front: {text}.")
        for key, unit, what in (("cpu_s", "s", "CPU time"), ("peak_rss_mb", "MB", "memory")):
            spans = ", ".join(f"{w} from {b:.1f} {unit}" for b, w in winners(chosen, key))
            if spans:
                said.append(f"- {case}, lower error for the same {what}: {spans}.")
    return lines + [""] + said


def ordered(rows: list[dict]) -> list[dict]:
    """The rows by case, sweep (as :data:`SWEEPS`) and dofs."""
    order = {(c, s[1]): (i, j) for i, c in enumerate(CASES) for j, s in enumerate(SWEEPS)}
    return sorted(rows, key=lambda r: (*order[(r["case"], r["option"])], r["dofs"]))


def publish(rows: list[dict], out: pathlib.Path, command: str) -> str:
    """The plot and the markdown beside ``out``; returns the markdown."""
    rows = ordered(rows)
    plot(rows, out.with_suffix(".png"))
    loads = [r["load"] for r in rows]
    lines = [
        f"Command: `{command}`. Each row a process of its own: wall time from start to exit, "
        "CPU time (user + system of the process), peak resident memory. The host was "
        f"shared with other jobs (1-minute load average before the runs: {min(loads):.1f} "
        f"to {max(loads):.1f} on 2 cores), so the wall time measures the load too: the "
        "fronts and the statements use the CPU time.",
        "",
        "X-FEM's level set is the signed distance of the sphere interpolated in P2 (what a "
        "user has): the interface and its normal approximate the sphere. With the quadric "
        "level set, which P2 holds exactly, the sticking sphere is a patch test (errors "
        "about 1e-7 at every size, `bench/results/sphere_triaxial.md`), no cost study. The "
        "body-fitted route meshes the sphere (curved 10-node tetrahedra for P2) and solves "
        "plain DOLFINx elasticity with the interface a surface of shared nodes: both "
        "cases are closed with no slip (the concentric spheres have no tangential "
        "traction), so their contact solution is the bonded one; its pressure is read with "
        "the meshed sphere's normal.",
        "",
        *summary(rows),
        "",
        "| case | method | option | size | dofs | Newton | Krylov | pressure error "
        "| wall (s) | CPU (s) | peak RSS (MB) | load | stress error in the volume |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        stress_error = "-" if r.get("stress_error") is None else f"{r['stress_error']:.1e}"
        lines.append(
            f"| {r['case']} | {r['method']} | {r['option']} | {r['size']} | {r['dofs']:,} | "
            f"{r['newton']} | {r['krylov']} | {r['error']:.3e} | {r['wall_s']:.1f} | "
            f"{r['cpu_s']:.1f} | {r['peak_rss_mb']:.0f} | {r['load']:.1f} | {stress_error} |"
        )
    lines += [
        "",
        "The last column (the sticking sphere's body-fitted runs): the stress error in the "
        "volume (relative L2); the uniform stress lies in every body-fitted space, so the "
        "pressure error is that of the meshed sphere's normal.",
    ]
    text = "\n".join(lines) + "\n"
    out.with_suffix(".md").write_text(text)
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the smallest sizes only")
    parser.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    parser.add_argument("--report-only", action="store_true", help="the report from the JSON")
    parser.add_argument("--resume", action="store_true", help="keep the saved rows, run the rest")
    parser.add_argument("--out", default=str(RESULTS / "accuracy_vs_time3d.json"))
    parser.add_argument("--xfem", nargs=5, help=argparse.SUPPRESS)
    parser.add_argument("--fitted", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.xfem or args.fitted:
        from mpi4py import MPI

        if args.xfem:
            case, n, solver, degree, cell = args.xfem
            result = xfem(case, int(n), solver, int(degree), cell)
        else:
            case, h, degree = args.fitted
            result = fitted(case, float(h), int(degree))
        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(result), flush=True)
        return
    out = pathlib.Path(args.out)
    command = shlex.join(
        ["python", "bench/accuracy_vs_time3d.py"]
        + [a for a in sys.argv[1:] if a not in ("--resume", "--report-only")]
    )
    if args.report_only:
        record = json.loads(out.read_text())
        print(publish(record["rows"], out, record["command"]))
        return
    rows = json.loads(out.read_text())["rows"] if args.resume else []
    done = {(r["case"], r["option"], r["size"]) for r in rows}
    for sweep in SWEEPS if not args.resume else []:  # JIT caches warm: no compilation
        for case in args.cases:  # in the measured runs (a resumed run's are)
            if sweep[4] or not args.quick:
                run(case, sweep, (sweep[4] or sweep[3])[0])
    for case in args.cases:
        for sweep in SWEEPS:
            for size in sweep[4] if args.quick else sweep[3]:
                if (case, sweep[1], size) in done:
                    continue
                row = run(case, sweep, size)
                if row is None:
                    continue
                rows.append(row)
                note(
                    f"{case} / {row['option']} / {size}: error {row['error']:.3e}, "
                    f"{row['dofs']:,} dofs, wall {row['wall_s']:.1f} s, CPU "
                    f"{row['cpu_s']:.1f} s, {row['peak_rss_mb']:.0f} MB, load {row['load']:.1f}"
                )
                out.parent.mkdir(parents=True, exist_ok=True)  # a long run keeps its rows
                out.write_text(json.dumps({"command": command, "rows": rows}, indent=1))
    rows = ordered(rows)
    out.write_text(json.dumps({"command": command, "rows": rows}, indent=1))
    print(publish(rows, out, command))


if __name__ == "__main__":
    main()
