"""Cracks against exact solutions: convergence, stress intensity factors, time and conditioning.

The studies (``--parts``, all by default), on the cases of ``xfem_contact.cases.cracks``:

- ``williams``: the exact mixed-mode Williams field on [-1, 1]^2, relative energy error
  and its rate over four meshes, P1 and P2, triangles and quadrilaterals, geometric
  enrichment (r_e = 0.3) and, as the baseline of the same run, topological enrichment
  (the tip cells' nodes only);
- ``griffith``: the Griffith crack (half length a = 1, plate of half width 2a,
  Westergaard's displacement on its boundary), K_I and K_II errors at both tips, the
  ring-to-ring spread, dofs, the time of assembly + solve and of the whole case;
- ``friction``: the closed crack inclined at 45 degrees under compression, Coulomb
  friction 0.3 on its lips: K_II error, |K_I| / |K_II|, slip error in L2 along the lips;
- ``edge``: a single-edge crack in a strip under tension against Tada's geometry factor;
- ``growth``: an inclined crack growing under tension, its path on two meshes;
- ``defaults``: the Griffith crack with the default tip radius and rings (lengths of the
  crack) against the former ones (the tip cells, rings in tip cell sizes), signed K_I
  errors, plates of half width 2a and 4a;
- ``p1_error``: where P1's error lies (squared energy error in annuli around a tip) next
  to its K error;
- ``tip_basis``: the Williams field with P2 on triangles and quadrilaterals (r_e = 0.3,
  n = 32, 64, 128), the tip enrichment's bases ``"plain"`` and the default ``"auto"``
  (``"shifted"`` for P2; one space): energy error, rate, and the condition number of the
  matrix the solver factors (n <= 64);
- ``conditioning``: the condition number of the scaled reduced stiffness (power and
  inverse iterations) against h at fixed r_e, and against r_e / h at fixed h: Jacobi
  scaling alone (``kappa_jacobi``) and the tip enrichment's change of unknowns the
  solvers use (``kappa``, :mod:`xfem_contact.solvers.block_scaling`).

Prints and writes ``bench/results/crack_convergence.{json,md}``.
Run: ``python bench/crack_convergence.py [--parts williams griffith] [--quick]``.
"""

import argparse
import json
import math
import pathlib
import time

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact.cases.cracks import (
    MATERIAL,
    frictional_crack_case,
    frictional_slip,
    griffith_case,
    plate_in_tension,
    williams_case,
    williams_energy_error,
)
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.fracture import TipIntegrals
from xfem_contact.solvers.block_scaling import scaled, tip_transform
from xfem_contact.solvers.linear import assemble_reduced
from xfem_contact.solvers.scaling import saddle_point_scaling

RESULTS = pathlib.Path(__file__).parent / "results"
#: Figures of the issue's open-source peer (P2 triangles, r_e = 0.3a, ring 0.2a..0.6a,
#: measured on this machine by the issue's author): K_I error, dofs, assembly + solve (s)
PEER = {
    ("P2", 8): (2.0e-6, 48518, 1.1),
    ("P2", 16): (1.2e-7, 195000, 3.5),
    ("P1", 16): (2.9e-5, 50000, None),
}


def rates(errors: list[float]) -> list[float | None]:
    return [None] + [
        math.log(a / b) / math.log(2) for a, b in zip(errors[:-1], errors[1:], strict=True)
    ]


def williams(say, quick: bool) -> list[dict]:
    rows = []
    meshes = {1: [16, 32, 64, 128], 2: [16, 32, 64, 128]}
    if quick:
        meshes = {1: [16, 32], 2: [16, 32]}
    for cell in ("triangle", "quadrilateral"):
        for degree, ns in meshes.items():
            for enrichment, radius in (("geometric", 0.3), ("topological", None)):
                errors = []
                for n in ns:
                    start = time.perf_counter()
                    case = williams_case(n, degree, tip_radius=radius, cell=cell)
                    try:
                        case.problem.solve()
                    except RuntimeError as error:  # the factorisation of an ill-conditioned system
                        rows.append(
                            dict(
                                case="williams",
                                cell=cell,
                                degree=degree,
                                enrichment=enrichment,
                                n=n,
                                failed=str(error),
                            )
                        )
                        say(f"Williams {cell} P{degree} {enrichment} n = {n}: {error}")
                        break
                    errors.append(williams_energy_error(case))
                    row = dict(
                        case="williams",
                        cell=cell,
                        degree=degree,
                        enrichment=enrichment,
                        n=n,
                        dofs=case.problem.space.dof_counts().total,
                        energy_error=errors[-1],
                        time=time.perf_counter() - start,
                    )
                    row["rate"] = rates(errors)[-1]
                    rows.append(row)
                    rate = "" if row["rate"] is None else f", rate {row['rate']:.2f}"
                    say(
                        f"Williams {cell} P{degree} {enrichment} n = {n}: {row['dofs']} dofs, "
                        f"energy error {errors[-1]:.3e}{rate} ({row['time']:.1f} s)"
                    )
    return rows


def tip_basis(say, quick: bool) -> list[dict]:
    rows = []
    for cell in ("triangle", "quadrilateral"):
        for basis in ("plain", "auto"):
            errors = []
            for n in [16, 32] if quick else [32, 64, 128]:
                case = williams_case(n, 2, tip_radius=0.3, cell=cell, tip_basis=basis)
                resolved = case.problem.space.tip_basis  # "auto": the default's
                label = basis if basis == resolved else f"{basis} ({resolved})"
                case.problem.solve()
                errors.append(williams_energy_error(case))
                kappa = condition_number(case.problem) if n <= 64 else math.nan
                row = dict(
                    case="tip_basis",
                    cell=cell,
                    basis=label,
                    n=n,
                    energy_error=errors[-1],
                    rate=rates(errors)[-1],
                    kappa=kappa,
                )
                rows.append(row)
                rate = "" if row["rate"] is None else f", rate {row['rate']:.2f}"
                say(
                    f"Williams {cell} P2 {label} n = {n}: energy error {errors[-1]:.3e}{rate}, "
                    f"condition number {kappa:.2e}"
                )
    return rows


def stress_intensity(case, rings):
    results = TipIntegrals(case.problem, rings).evaluate()
    return results


def griffith(say, quick: bool) -> list[dict]:
    rows = []
    a = 1.0
    rings = [(0.2 * a, 0.6 * a), (0.3 * a, 0.8 * a), (0.25 * a, 0.7 * a)]
    for degree, Ns in ((2, [8, 16, 32]), (1, [16, 32])):
        for N in Ns[:1] if quick else Ns:
            start = time.perf_counter()
            case = griffith_case(N, degree, tip_radius=0.3 * a)
            report = case.problem.solve()
            solve = time.perf_counter() - start
            results = stress_intensity(case, rings)
            whole = time.perf_counter() - start
            K_I = case.K[0][0]
            for k, per_ring in enumerate(results):
                errors_I = [abs(r.K_I - K_I) / K_I for r in per_ring]
                errors_II = [abs(r.K_II) / K_I for r in per_ring]
                spread = (max(r.K_I for r in per_ring) - min(r.K_I for r in per_ring)) / K_I
                row = dict(
                    case="griffith",
                    degree=degree,
                    h=f"a/{N}",
                    tip=k,
                    dofs=case.problem.space.dof_counts().total,
                    K_I_error=errors_I[0],
                    K_II_error=errors_II[0],
                    ring_spread=spread,
                    J_over_G=per_ring[0].J / per_ring[0].G,
                    build_solve_time=solve,
                    total_time=whole,
                    solve_total_time=report.total_time,
                )
                peer = PEER.get((f"P{degree}", N))
                row["peer"] = peer
                rows.append(row)
                say(
                    f"Griffith P{degree} h = a/{N}, tip {k}: {row['dofs']} dofs, K_I error "
                    f"{errors_I[0]:.2e} (rings {', '.join(f'{e:.1e}' for e in errors_I)}), "
                    f"K_II {errors_II[0]:.1e}, ring spread {spread:.1e}, J/G - 1 "
                    f"{row['J_over_G'] - 1:.1e}; build + solve {solve:.1f} s, with K {whole:.1f} s"
                    + (f"; peer: {peer[0]:.1e} at {peer[1]} dofs" if peer else "")
                )
    return rows


def defaults(say, quick: bool) -> list[dict]:
    """The Griffith crack with the defaults (tip radius ``"auto"`` = a / 2, the rings of
    the scenes in units of a) against the former ones (the tip cells' nodes, rings 2..5
    and 3..7 tip cell sizes), signed K_I errors per tip and ring, plates of half width 2a
    and 4a."""
    from xfem_contact.mechanics.fracture import tip_cell_size
    from xfem_contact.scenes.crack_builder import default_rings

    rows = []
    runs = [(2.0, 1, [4, 8, 16, 32]), (2.0, 2, [8, 16]), (4.0, 1, [4, 8, 16])]
    for width, degree, Ns in runs:
        for N in Ns[:2] if quick else Ns:
            for name, radius in (("auto", "auto"), ("mesh (former)", None)):
                start = time.perf_counter()
                case = griffith_case(N, degree, tip_radius=radius, width=width)
                case.problem.solve()
                if radius is None:
                    mesh, tips = case.problem.mesh, case.problem.cut.crack.tips
                    h = max(tip_cell_size(mesh, tip) for tip in tips)
                    rings = [(2 * h, 5 * h), (3 * h, 7 * h)]
                else:
                    rings = default_rings(case.problem)
                try:
                    results = stress_intensity(case, rings)
                except ValueError as error:  # a former ring reaching the boundary
                    say(f"defaults {name}, half width {width:g}a, P{degree} h = a/{N}: {error}")
                    continue
                K_I = case.K[0][0]
                errors = [[(r.K_I - K_I) / K_I for r in tip] for tip in results]
                row = dict(
                    case="defaults",
                    defaults=name,
                    width=width,
                    degree=degree,
                    h=f"a/{N}",
                    dofs=case.problem.space.dof_counts().total,
                    tip_radius=case.problem.space.tip_radius,
                    rings=[[round(a, 4), round(b, 4)] for a, b in rings],
                    K_I_errors=[[float(f"{e:.3e}") for e in tip] for tip in errors],
                    time=time.perf_counter() - start,
                )
                rows.append(row)
                say(
                    f"defaults {name}, half width {width:g}a, P{degree} h = a/{N}: "
                    f"{row['dofs']} dofs, K_I errors per tip and ring {row['K_I_errors']} "
                    f"({row['time']:.1f} s)"
                )
    return rows


def energy_error_annuli(case, bins: list[float]) -> list[tuple[float, float]]:
    """Per annulus ``bins[k] <= r < bins[k + 1]`` (m) around tip 0 of a solved
    :func:`griffith_case` (``beta = pi / 2``): the squared energy-norm error against
    Westergaard's field and the exact energy (both sides). Collective."""
    import dolfinx.fem
    import ufl

    from xfem_contact.mechanics.fracture import UFL, GriffithCrack

    problem = case.problem
    crack = problem.cut.crack
    tip, d = crack.tips[0], crack.directions[0]
    centre = 0.5 * (crack.tips[0] + crack.tips[1])
    exact = GriffithCrack.uniaxial(
        1.0, 1.0, 0.5 * math.pi, center=tuple(centre), direction=tuple(d)
    )
    x = ufl.SpatialCoordinate(problem.mesh)
    u = problem.space.split(problem.w)
    r = ufl.sqrt((x[0] - tip[0]) ** 2 + (x[1] - tip[1]) ** 2)
    E, nu = MATERIAL.E, MATERIAL.nu

    def strain(S):  # the plane strain compliance
        return (1 + nu) / E * (S - nu * ufl.tr(S) * ufl.Identity(2))

    def total(expr) -> float:
        return MPI.COMM_WORLD.allreduce(dolfinx.fem.assemble_scalar(form(expr)), op=MPI.SUM)

    out = []
    for lo, hi in zip(bins[:-1], bins[1:], strict=True):
        inside = ufl.conditional(ufl.And(ufl.ge(r, lo), ufl.lt(r, hi)), 1.0, 0.0)
        err, whole = 0.0, 0.0
        for i, side in enumerate((-1, 1)):
            S = exact.stress(x, UFL, side=side)
            e = MATERIAL.stress(u[i]) - S
            err += total(ufl.inner(e, strain(e)) * inside * problem.cut.dx(side))
            whole += total(ufl.inner(S, strain(S)) * inside * problem.cut.dx(side))
        out.append((err, whole))
    return out


def p1_error(say, quick: bool) -> list[dict]:
    """Where P1's error lies: the squared energy-norm error of the Griffith crack (plate
    2a, r_e = 0.3a) in annuli around tip 0 (share of the whole), the relative energy
    error squared and the K_I error (ring 0.2a..0.6a), at a/16 and a/32; P2 at a/8 for
    comparison."""
    bins = [0.0, 0.1, 0.3, 0.45, 0.6, 1.0, 1.5, 100.0]
    rows = []
    for degree, N in [(1, 16)] if quick else [(1, 16), (1, 32), (2, 8)]:
        case = griffith_case(N, degree, tip_radius=0.3)
        case.problem.solve()
        ring = stress_intensity(case, [(0.2, 0.6)])[0][0]
        annuli = energy_error_annuli(case, bins)
        err = sum(e for e, _ in annuli)
        row = dict(
            case="p1_error",
            degree=degree,
            h=f"a/{N}",
            K_I_error=(ring.K_I - case.K[0][0]) / case.K[0][0],
            energy_error_squared=err / sum(w for _, w in annuli),
            shares={
                f"{lo:g}..{hi:g}a": round(e / err, 3)
                for lo, hi, (e, _) in zip(bins[:-1], bins[1:], annuli, strict=True)
            },
        )
        rows.append(row)
        say(
            f"P{degree} h = a/{N}: K_I error {row['K_I_error']:+.2e}, relative energy error "
            f"squared {row['energy_error_squared']:.2e}, its shares by distance to tip 0 "
            f"{row['shares']}"
        )
    return rows


def friction(say, quick: bool) -> list[dict]:
    rows = []
    for degree, Ns in ((2, [8, 16]), (1, [16])):
        for N in Ns[:1] if quick else Ns:
            start = time.perf_counter()
            case = frictional_crack_case(N, degree, friction=0.3, tip_radius=0.3)
            report = case.problem.solve()
            results = stress_intensity(case, [(0.2, 0.6), (0.3, 0.8)])
            samples = case.problem.interface_samples(case.problem.w)
            centre, d = np.array([0.0123, 0.0271]), np.array([math.cos(0.3), math.sin(0.3)])
            s = (np.asarray(samples["x"]) - centre[0]) * d[0]
            s += (np.asarray(samples["y"]) - centre[1]) * d[1]
            slip, _ = frictional_slip(s)
            # the law's tangent is -d; discrete L2 over the rule points
            slip_error = np.linalg.norm(-np.asarray(samples["slip"]) - slip) / np.linalg.norm(slip)
            K_II = case.K[0][1]
            for k, per_ring in enumerate(results):
                ring = per_ring[0]
                row = dict(
                    case="friction",
                    degree=degree,
                    h=f"a/{N}",
                    tip=k,
                    dofs=case.problem.space.dof_counts().total,
                    K_II_error=abs(ring.K_II - K_II) / abs(K_II),
                    K_I_over_K_II=abs(ring.K_I) / abs(K_II),
                    slip_error=slip_error,
                    newton=report.iterations,
                    time=time.perf_counter() - start,
                )
                rows.append(row)
                say(
                    f"Frictional crack P{degree} h = a/{N}, tip {k}: {row['dofs']} dofs, "
                    f"K_II error {row['K_II_error']:.2e}, |K_I|/|K_II| "
                    f"{row['K_I_over_K_II']:.2e}, slip L2 error {slip_error:.2e}, "
                    f"{report.iterations} Newton steps ({row['time']:.1f} s)"
                )
    return rows


def condition_number(problem, iterations: int = 60, tip_scaling: bool = True) -> float:
    """Condition number of the scaled reduced stiffness the solver factors (power
    iteration for the largest eigenvalue, inverse iteration with an LU for the
    smallest): ``Z^T A Z`` with a crack's tip enrichment
    (:mod:`xfem_contact.solvers.block_scaling`), else (or without ``tip_scaling``) the
    Jacobi-scaled ``D A D``. Collective."""
    R = problem.prolongation()
    a, L = form(problem.bilinear_form()), form(problem.loads.linear_form())
    A, b = assemble_reduced(a, L, problem.loads.bcs, R)
    transform = tip_transform(problem.space, off=not tip_scaling)
    if transform is None:
        D = saddle_point_scaling(A)
        A.diagonalScale(D, D)
    else:
        D = transform(R, A)
        unscaled, A = A, scaled(A, D)
        unscaled.destroy()
    x, y = A.createVecRight(), A.createVecRight()
    x.setRandom()
    for _ in range(iterations):
        A.mult(x, y)
        top = y.norm()
        y.copy(x)
        x.scale(1 / top)
    ksp = PETSc.KSP().create(A.getComm())
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    x.setRandom()
    for _ in range(iterations // 2):
        ksp.solve(x, y)
        if ksp.getConvergedReason() < 0:  # MUMPS failed (its workspace): no estimate
            low = 0.0
            break
        low = 1 / y.norm()
        y.copy(x)
        x.scale(low)
    for obj in (ksp, A, b, D, R, x, y):
        obj.destroy()
    return top / low if low > 0 else math.inf


def conditioning(say, quick: bool) -> list[dict]:
    rows = []

    def measure(n, degree, radius, factor):
        case = williams_case(n, degree, tip_radius=radius)
        kappa = condition_number(case.problem)
        jacobi = condition_number(case.problem, tip_scaling=False)
        row = dict(case="conditioning", degree=degree, n=n, r_e=radius, r_e_over_h=factor)
        rows.append(dict(row, kappa=kappa, kappa_jacobi=jacobi))
        say(
            f"condition number P{degree}, h = 2/{n}, r_e = {radius:.3g} = {factor:.3g} h: "
            f"{kappa:.2e} (Jacobi scaling alone: {jacobi:.2e})"
        )

    for degree in (1, 2):
        for n in [8, 16] if quick else [8, 16, 32, 64]:
            measure(n, degree, 0.4, 0.4 * n / 2)
        n = 16
        for factor in (1.5, 2, 3, 4, 6):
            measure(n, degree, factor * 2 / n, factor)
    return rows


def edge(say, quick: bool) -> list[dict]:
    """A single-edge crack (a = 0.3013 m) in a strip 1 m wide and 4 m high pulled by 1 Pa
    at its ends, against Tada's geometry factor F(a/W) (0.5 % accurate for a/W <= 0.6):
    K_I = sigma sqrt(pi a) F."""
    import dolfinx.mesh

    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.io.meshes import ghosted_partitioner
    from xfem_contact.mechanics.fracture import GrowthPath
    from xfem_contact.mechanics.problem import Problem

    H, a, y0, rows = 2.0, 0.3013, 0.0127, []
    F = 1.12 - 0.231 * a + 10.55 * a**2 - 21.72 * a**3 + 30.39 * a**4
    K = math.sqrt(math.pi * a) * F
    for degree in (1, 2):
        for nx in (40,) if quick else (40, 60):
            start = time.perf_counter()
            path = GrowthPath([[-0.1, y0], [a, y0]], moving=(False, True))
            mesh = dolfinx.mesh.create_rectangle(
                MPI.COMM_WORLD, [[0, -H], [1, H]], [nx, 4 * nx], partitioner=ghosted_partitioner()
            )
            cut = CutMesh(mesh, path.phi, degree=degree, tangent=path.psi)
            problem = Problem(cut, degree, MATERIAL, "free", ghost_penalty=0.0, tip_radius=0.1)
            problem.loads.add_traction(lambda x: np.isclose(x[1], H), (0.0, 1.0))
            problem.loads.add_traction(lambda x: np.isclose(x[1], -H), (0.0, -1.0))
            for point, component in (((1.0, -H), 0), ((1.0, -H), 1), ((1.0, H), 0)):
                problem.loads.add_point_displacement(point, 0.0, component)
            problem.solve()
            (ring,) = TipIntegrals(problem, [(0.06, 0.18)]).evaluate()[0]
            row = dict(
                case="edge",
                degree=degree,
                h=1 / nx,
                dofs=problem.space.dof_counts().total,
                K_I=ring.K_I,
                tada=K,
                relative=(ring.K_I - K) / K,
                K_II=ring.K_II,
                time=time.perf_counter() - start,
            )
            rows.append(row)
            say(
                f"edge crack P{degree} h = 1/{nx}: K_I {ring.K_I:.5f} against Tada's {K:.5f} "
                f"({row['relative']:+.1e}), K_II {ring.K_II:.1e}, {row['dofs']} dofs, "
                f"{row['time']:.1f} s"
            )
    return rows


def growth(say, quick: bool) -> list[dict]:
    """An inclined crack (half length 0.5 m, 0.5 rad) in a plate of half width 2 m under
    a tension of 1 Pa (tractions top and bottom): three steps of 0.25 m on two meshes;
    the paths' largest distance apart, and a PNG and JSON of both."""
    from xfem_contact.mechanics.fracture import GrowthPath, grow

    W, a, angle, da, steps = 2.0, 0.5, 0.5, 0.25, 3
    centre = np.array([0.0123, 0.0271])
    d = np.array([math.cos(angle), math.sin(angle)])
    paths, rows = {}, []
    for n in (32, 48):
        start = time.perf_counter()
        path = GrowthPath([centre - a * d, centre + a * d])
        problem = plate_in_tension(path, n, tip_radius=0.3, width=W)
        problem.solve()
        for step in range(steps):
            record = grow(problem, path, da, [(0.2, 0.45)])
            ratio = max(abs(K[1] / K[0]) for K in record.K)
            angles = [math.degrees(x) for x in record.angles]
            rows.append(
                dict(
                    case="growth",
                    n=n,
                    step=step,
                    K_II_over_K_I=ratio,
                    kink_deg=angles,
                    time=time.perf_counter() - start,
                )
            )
            say(
                f"growth h = {2 * W / n:.3f} m, step {step}: max |K_II/K_I| {ratio:.3f}, "
                f"kink angles {', '.join(f'{x:.2f}' for x in angles)} deg"
            )
        paths[n] = path.points
    gap = float(np.abs(paths[32] - paths[48]).max())
    rows.append(dict(case="growth", n="32 vs 48", path_difference=gap, relative_to_da=gap / da))
    say(f"growth: the paths on h = 1/8 and 1/12 m are {gap:.1e} m apart ({gap / da:.1e} da)")
    if MPI.COMM_WORLD.rank == 0:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5, 3))
        for n, points in paths.items():
            ax.plot(points[:, 0], points[:, 1], "o-", label=f"h = {2 * W / n:.3f} m")
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend()
        fig.tight_layout()
        RESULTS.mkdir(exist_ok=True)
        fig.savefig(RESULTS / "crack_growth_path.png", dpi=120)
        paths_json = {str(n): p.tolist() for n, p in paths.items()}
        (RESULTS / "crack_growth_path.json").write_text(json.dumps(paths_json, indent=1))
    return rows


PARTS = {
    "edge": edge,
    "williams": williams,
    "griffith": griffith,
    "friction": friction,
    "conditioning": conditioning,
    "tip_basis": tip_basis,
    "growth": growth,
    "defaults": defaults,
    "p1_error": p1_error,
}


def markdown(rows: list[dict]) -> str:
    lines = ["# Cracks against exact solutions", ""]
    for part in PARTS:
        mine = [
            r for r in rows if r["case"] == part or (part == "conditioning" and r["case"] == part)
        ]
        if not mine:
            continue
        keys = [k for k in mine[0] if k not in ("case", "peer")]
        lines += [f"## {part}", "", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
        for r in mine:
            cells = [
                f"{r[k]:.3g}" if isinstance(r.get(k), float) else str(r.get(k, r.get("failed", "")))
                for k in keys
            ]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", nargs="*", default=list(PARTS), choices=list(PARTS))
    parser.add_argument("--quick", action="store_true", help="the smallest meshes only")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args()
    rank0 = MPI.COMM_WORLD.rank == 0
    say = print if rank0 and not args.no_progress else (lambda *a: None)
    saved = RESULTS / "crack_convergence.json"
    # the rows of the parts not rerun are kept (a run of some parts updates only theirs)
    kept = json.loads(saved.read_text()) if saved.exists() else []
    rows = [r for r in kept if r["case"] not in args.parts]
    for part in args.parts:  # results saved after each part
        rows += PARTS[part](say, args.quick)
        if rank0:
            RESULTS.mkdir(exist_ok=True)
            (RESULTS / "crack_convergence.json").write_text(json.dumps(rows, indent=1, default=str))
            (RESULTS / "crack_convergence.md").write_text(markdown(rows))
    if rank0:
        print(markdown(rows))


if __name__ == "__main__":
    main()
