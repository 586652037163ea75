"""Cell aggregation against small cuts: conditioning, accuracy, the Williams crack.

Part ``conditioning``: the 2-norm condition number of the Jacobi-scaled reduced matrix
(:mod:`xfem_contact.solvers.scaling`) of a bonded circle (paper case 2's setting: unit
square, E = 100 MPa, nu = 0.3, rigid modes removed at three points) on n = 8, 16, 32
cells per side, over circles at random centres and radii, two thirds of them passing
within ``eps h`` of a mesh node (``eps`` log-uniform in 1e-10 .. 1e-2; the node inside,
or outside: tiny cuts of either side on purpose), for P1 and P2 on triangles and
quadrilaterals, four treatments of small cuts: none (``ghost_penalty=0``), cell
aggregation (``aggregation=0.25``, ``ghost_penalty=0``), the default ghost penalty
alone, and both (the ghost penalty with ``aggregation=0.15``). Prints, per element,
treatment and n, the largest ``C = cond h^2`` (h = 1/n) and its median, and the count
of outliers (``C`` above ten times the median of the ``aggregation 0.25`` samples of
that element and n, else of the first treatment run).
Each circle moves the interface of one problem (``update_interface``: forms compiled
once); the condition number comes from all eigenvalues of the dense matrix below
``--dense-below`` unknowns (default 1500), else from the extreme ones (SLEPc); BLAS runs
on one thread.

Part ``crack_conditioning``: the same over random straight cracks of the unit square
(tip uniform in [0.3, 0.7]^2, any direction, running back to the boundary; two thirds
passing within ``eps h`` of a node behind the tip), free lips, the boundary clamped,
geometric tip enrichment of the default radius, set on the first crack (tip (0.5, 0.5),
0.3 rad: ``r_e = 0.262``) and kept as the crack moves; the matrix is the one the solver
factors, ``Z^T A Z`` of the tip transform (:mod:`xfem_contact.solvers.block_scaling`).
``--treatments`` picks the treatments of both parts, ``--tip-basis`` the cracks' tip
basis (default ``"auto"``; another is written to
``aggregation_crack_conditioning_BASIS``), ``--tip-radius none`` the topological tip
enrichment (the tip cells' nodes) instead of the zone.

Condition numbers: the extreme eigenvalues of the symmetric scaled matrix (dense below
1500 unknowns, else SLEPc: Krylov-Schur, shift-and-invert at 0 with an LU for the least
in modulus).

Part ``accuracy``: the contact pressure's relative L2 error of paper case 2 (sticking,
P2 on quadrilaterals and triangles, n = 10, 20, 40) and case 3 (the annulus, alpha = 0,
P2 on curved Q2 cells, 4 x 16, 8 x 32, 16 x 64) with the default treatment (ghost
penalty 0.01), none (no ghost penalty, the dofs of empty support dropped), aggregation
(0.25, 0.15) on top of the ghost penalty, aggregation alone, and the Barbosa-Hughes scale
of the cut (``stabilization_length="cut"``, and ``"patch"``) with the ghost penalty
(``--accuracy-columns``: some of these only).

Part ``crack``: the Williams crack on Q2 quadrilaterals (geometric tip enrichment,
r_e = 0.3), n = 32, 64, 128, without and with ``aggregation=0.25`` (the default tip
basis: ``"shifted"`` without aggregation, ``"plain"`` with it): the energy error,
its rate and the condition number of the matrix the solver factors (tip-transformed;
``bench/crack_convergence.py``'s estimate, n <= 64).

Part ``tip_dofs``: the Williams crack (r_e = 0.3) on ``--elements`` and ``--sizes``
with nodal and gathered branch dofs (``tip_dofs``, :mod:`xfem_contact.fem.tip_dofs`),
for each of ``--treatments`` without a ghost penalty (``none``, ``aggregation 0.25``):
energy errors and rates. ``--tip-dofs gathered`` gathers the cracks' branch dofs in the
``crack_conditioning`` part (written to ``..._gathered``).

Run: ``python bench/aggregation.py [--parts conditioning crack_conditioning accuracy
crack tip_dofs] [--circles 30] [--sizes 8 16 32] [--treatments none "aggregation 0.25"]
[--tip-basis plain] [--tip-radius none] [--dense-below 0] [--accuracy-columns LABEL ...]
[--name NAME]``; writes
``bench/results/aggregation.{json,md}`` (conditioning; ``NAME.{json,md}`` with
``--name``),
``bench/results/aggregation_crack_conditioning.{json,md}``,
``bench/results/aggregation_accuracy.md`` (``NAME.md`` with ``--name``),
``bench/results/aggregation_crack.md`` and
``bench/results/aggregation_tip_dofs.md`` (``NAME.md`` with ``--name``).
"""

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")  # before numpy: one BLAS thread
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import xfem_contact  # noqa: E402, F401  (before dolfinx)

# isort: split
import argparse
import itertools
import json
import math
import pathlib
import time

import dolfinx.mesh
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc
from slepc4py import SLEPc

from xfem_contact.cases.cracks import williams_case, williams_energy_error
from xfem_contact.cases.paper import (
    annulus_pressure_error,
    annulus_problem,
    inclusion_errors,
    inclusion_problem,
)
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.forms import form
from xfem_contact.io.progress import note
from xfem_contact.mechanics.laws import Bonded
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem
from xfem_contact.solvers.assembly import ReducedMatrix
from xfem_contact.solvers.block_scaling import scaled, tip_transform
from xfem_contact.solvers.scaling import saddle_point_scaling

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
ELEMENTS = [("triangle", 1), ("triangle", 2), ("quadrilateral", 1), ("quadrilateral", 2)]
#: label: (ghost penalty, aggregation threshold)
TREATMENTS = {
    "none": (0.0, None),
    "aggregation 0.25": (0.0, 0.25),
    "ghost penalty 0.01": (0.01, None),
    "ghost penalty 0.01 + aggregation 0.15": (0.01, 0.15),
}
#: The treatment whose median C defines the outliers (else the first one run)
REFERENCE = "aggregation 0.25"
#: A sample is an outlier above this multiple of the aggregated samples' median C
OUTLIER = 10.0


def circles(count: int, n: int, rng) -> list[tuple[float, float, float]]:
    """Random circles inside the unit square; two in three pass within ``eps h`` of a
    node (inside, then outside), ``eps`` log-uniform in 1e-10 .. 1e-2."""
    out = []
    for k in range(count):
        cx, cy = rng.uniform(0.35, 0.65, 2)
        r = rng.uniform(0.12, 0.3)
        if k % 3:
            angle = rng.uniform(0.0, 2.0 * math.pi)
            point = np.array([cx + r * math.cos(angle), cy + r * math.sin(angle)])
            node = np.round(point * n) / n
            eps = 10.0 ** rng.uniform(-10.0, -2.0)
            r = math.hypot(*(node - (cx, cy))) + (1.0 if k % 3 == 1 else -1.0) * eps / n
        out.append((float(cx), float(cy), float(r)))
    return out


def circle(centre, radius):
    """The signed distance to a circle, as a level set."""
    return lambda x: np.hypot(x[0] - centre[0], x[1] - centre[1]) - radius


def bonded_circle(mesh, centre, radius, degree, ghost_penalty, aggregation) -> Problem:
    """The bonded circle of the module docstring (move it with ``update_interface``:
    the forms are compiled once)."""
    cut = CutMesh(mesh, circle(centre, radius), degree=2)
    problem = Problem(
        cut,
        degree,
        Material(100e6, 0.3),
        Bonded(),
        ghost_penalty=ghost_penalty,
        aggregation=aggregation,
    )
    problem.loads.add_point_displacement([0.5, 0.0], 0.0, 0)
    problem.loads.add_point_displacement([0.5, 1.0], 0.0, 0)
    problem.loads.add_point_displacement([0.0, 0.5], 0.0, 1)
    return problem


def cracks(count: int, n: int, rng) -> list[tuple[float, float, float]]:
    """Random straight cracks ``(tip x, tip y, angle)`` of the unit square, from the tip
    back to the boundary; two in three pass within ``eps h`` of a mesh node behind the
    tip (on either side), ``eps`` log-uniform in 1e-10 .. 1e-2."""
    out = []
    for k in range(count):
        tip = rng.uniform(0.3, 0.7, 2)
        angle = rng.uniform(0.0, 2.0 * math.pi)
        if k % 3:
            d = np.array([math.cos(angle), math.sin(angle)])
            normal = np.array([-d[1], d[0]])
            behind = tip - rng.uniform(0.1, 0.25) * d
            node = np.round(behind * n) / n
            eps = 10.0 ** rng.uniform(-10.0, -2.0)
            offset = (node - tip) @ normal - (1.0 if k % 3 == 1 else -1.0) * eps / n
            tip = tip + offset * normal  # the crack's line now passes eps h off the node
        out.append((float(tip[0]), float(tip[1]), float(angle)))
    return out


def crack_levelsets(tip, angle):
    """``(phi, psi)``: signed distances to the crack's line and along it from the tip."""
    d = (math.cos(angle), math.sin(angle))
    phi = lambda x: -(x[0] - tip[0]) * d[1] + (x[1] - tip[1]) * d[0]  # noqa: E731
    psi = lambda x: (x[0] - tip[0]) * d[0] + (x[1] - tip[1]) * d[1]  # noqa: E731
    return phi, psi


def free_crack(
    mesh,
    tip,
    angle,
    degree,
    ghost_penalty,
    aggregation,
    tip_basis="auto",
    tip_radius="auto",
    tip_dofs="nodal",
) -> Problem:
    """A crack with free lips in the unit square, its boundary clamped, geometric tip
    enrichment of the default radius (of this crack; kept by ``update_interface``) or
    ``tip_radius`` (None: topological), the tip basis ``tip_basis``, the branch dofs
    ``tip_dofs``."""
    phi, psi = crack_levelsets(tip, angle)
    cut = CutMesh(mesh, phi, degree=degree, tangent=psi)
    problem = Problem(
        cut,
        degree,
        Material(100e6, 0.3),
        "free",
        ghost_penalty=ghost_penalty,
        aggregation=aggregation,
        tip_basis=tip_basis,
        tip_radius=tip_radius,
        tip_dofs=tip_dofs,
    )
    zero = lambda x: np.zeros((2, x.shape[1]))  # noqa: E731
    on_boundary = lambda x: (  # noqa: E731
        np.isclose(x[0], 0.0)
        | np.isclose(x[0], 1.0)
        | np.isclose(x[1], 0.0)
        | np.isclose(x[1], 1.0)
    )
    problem.loads.add_displacement(on_boundary, {-1: zero, 1: zero})
    return problem


def scaled_condition(problem: Problem, dense_below: int = 1500) -> float:
    """2-norm condition number of the scaled reduced matrix the solver factors (serial):
    ``D R^T A R D`` (Jacobi), with a crack's tip enrichment ``Z^T R^T A R Z``
    (:mod:`xfem_contact.solvers.block_scaling`); all eigenvalues of the dense matrix
    below ``dense_below`` unknowns, else the extreme ones (SLEPc)."""
    R = problem.prolongation()
    matrix = ReducedMatrix(form(problem.bilinear_form()), problem.loads.bcs, R)
    matrix.assemble()
    A = matrix.release()
    transform = tip_transform(problem.space)
    if transform is None:
        D = saddle_point_scaling(A)
        A.diagonalScale(D, D)
    else:
        D = transform(R, A)
        unscaled, A = A, scaled(A, D)
        unscaled.destroy()
    try:
        if A.getSize()[0] < dense_below:
            dense = A.convert("dense").getDenseArray()
            s = np.abs(np.linalg.eigvalsh(0.5 * (dense + dense.T)))
            return float(s.max() / s.min())
        return _extreme(A, largest=True) / _extreme(A, largest=False)
    finally:
        for obj in (R, A, D):
            obj.destroy()


def _extreme(A: PETSc.Mat, largest: bool) -> float:
    """The largest or least modulus of an eigenvalue of the symmetric ``A`` (SLEPc)."""
    eps = SLEPc.EPS().create(A.getComm())
    eps.setOperators(A)
    eps.setProblemType(SLEPc.EPS.ProblemType.HEP)
    eps.setDimensions(1)
    eps.setTolerances(1e-8, 2000)
    if largest:
        eps.setWhichEigenpairs(SLEPc.EPS.Which.LARGEST_MAGNITUDE)
    else:
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTarget(0.0)
        st = eps.getST()
        st.setType(SLEPc.ST.Type.SINVERT)
        ksp = st.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
    eps.solve()
    if eps.getConverged() < 1:
        raise RuntimeError("the eigenvalue solver did not converge")
    value = abs(eps.getEigenvalue(0))
    eps.destroy()
    return float(value)


#: label: problem options of the accuracy part
ACCURACY_TREATMENTS = {
    "ghost penalty 0.01 (default)": {},
    "none (ghost penalty 0)": {"ghost_penalty": 0.0},
    "ghost penalty 0.01 + aggregation 0.25": {"aggregation": 0.25},
    "ghost penalty 0.01 + aggregation 0.15": {"aggregation": 0.15},
    "aggregation 0.25 alone": {"aggregation": 0.25, "ghost_penalty": 0.0},
    "ghost penalty 0.01, stabilization length 'cut'": {"stabilization_length": "cut"},
    "ghost penalty 0.01, stabilization length 'patch'": {"stabilization_length": "patch"},
    "ghost penalty 0.01 (higher derivatives 0.01), stabilization length 'patch'": {
        "stabilization_length": "patch",
        "ghost_penalty_higher": 0.01,
    },
}


def accuracy(columns: list[str] | None = None, name: str = "aggregation_accuracy") -> None:
    """The accuracy part (module docstring): prints and writes a Markdown table of the
    ``columns`` (labels of :data:`ACCURACY_TREATMENTS`; None: all) to ``name``."""
    treatments = {c: ACCURACY_TREATMENTS[c] for c in (columns or ACCURACY_TREATMENTS)}
    cases = [
        (f"case 2, {cell}, n = {n}", lambda o, n=n, c=cell: _case2(n, c, o))
        for cell in ("quadrilateral", "triangle")
        for n in (10, 20, 40)
    ]
    cases += [
        (f"case 3, {nr} x {na}", lambda o, nr=nr, na=na: _case3(nr, na, o))
        for nr, na in ((4, 16), (8, 32), (16, 64))
    ]
    lines = [
        "| case | " + " | ".join(treatments) + " |",
        "|---|" + "---|" * len(treatments),
    ]
    for case, run in cases:
        errors = []
        for options in treatments.values():
            try:
                errors.append(f"{run(options):.3e}")
            except Exception as error:  # reported, not hidden
                errors.append(f"failed: {type(error).__name__}")
        lines.append(f"| {case} | " + " | ".join(errors) + " |")
        note(lines[-1])
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def _case2(n, cell, options) -> float:
    problem = inclusion_problem(n, 2, "sticking", cell, **options)
    problem.solve()
    return inclusion_errors(problem, problem.w).pressure


def _case3(n_radial, n_angular, options) -> float:
    problem = annulus_problem(n_radial, n_angular, 2, **options)
    problem.solve()
    return annulus_pressure_error(problem)


def crack() -> None:
    """The crack part (module docstring): prints and writes a Markdown table."""
    import crack_convergence  # the bench next to this one

    lines = [
        "| aggregation | n | energy error | rate | condition number |",
        "|---|---|---|---|---|",
    ]
    for threshold in (None, 0.25):
        errors = []
        for n in (32, 64, 128):
            case = williams_case(n, 2, tip_radius=0.3, cell="quadrilateral", aggregation=threshold)
            case.problem.solve()
            errors.append(williams_energy_error(case))
            rate = "" if len(errors) < 2 else f"{math.log2(errors[-2] / errors[-1]):.2f}"
            kappa = crack_convergence.condition_number(case.problem) if n <= 64 else math.nan
            lines.append(f"| {threshold} | {n} | {errors[-1]:.3e} | {rate} | {kappa:.2e} |")
            note(lines[-1])
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "aggregation_crack.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def tip_dofs(args) -> None:
    """The tip_dofs part (module docstring): prints and writes a Markdown table."""
    elements = [(e.split(":")[0], int(e.split(":")[1])) for e in args.elements]
    # the Williams case has no ghost penalty: the treatments without one
    thresholds = {t: TREATMENTS[t][1] for t in args.treatments if TREATMENTS[t][0] == 0.0}
    lines = [
        "| element | tip dofs | treatment | "
        + " | ".join(f"n = {n}" for n in args.sizes)
        + " | rates |",
        "|---|---|---|" + "---|" * len(args.sizes) + "---|",
    ]
    for (cell, degree), dofs, (label, threshold) in itertools.product(
        elements, ("nodal", "gathered"), thresholds.items()
    ):
        errors = []
        for n in args.sizes:
            case = williams_case(
                n, degree, tip_radius=0.3, cell=cell, tip_dofs=dofs, aggregation=threshold
            )
            case.problem.solve()
            errors.append(williams_energy_error(case))
            note(f"{cell} P{degree} {dofs} {label} n = {n}: energy error {errors[-1]:.3e}")
        rates = [
            math.log(e0 / e1) / math.log(n1 / n0)
            for e0, e1, n0, n1 in zip(errors, errors[1:], args.sizes, args.sizes[1:], strict=False)
        ]
        lines.append(
            f"| {cell} P{degree} | {dofs} | {label} | "
            + " | ".join(f"{e:.3e}" for e in errors)
            + " | "
            + ", ".join(f"{r:.2f}" for r in rates)
            + " |"
        )
        note(lines[-1])
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.name or 'aggregation_tip_dofs'}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--parts", nargs="+", default=["conditioning", "accuracy", "crack"], help="parts"
    )
    parser.add_argument("--circles", type=int, default=30, help="circles per mesh")
    parser.add_argument("--sizes", type=int, nargs="+", default=[8, 16, 32], help="n")
    parser.add_argument("--elements", nargs="+", default=[f"{c}:{d}" for c, d in ELEMENTS])
    parser.add_argument(
        "--treatments", nargs="+", default=list(TREATMENTS), choices=list(TREATMENTS)
    )
    parser.add_argument(
        "--tip-basis",
        default="auto",
        choices=["auto", "plain", "shifted"],
        help="the cracks' tip basis (crack_conditioning; 'shifted' refuses aggregation)",
    )
    parser.add_argument(
        "--tip-radius",
        default="auto",
        choices=["auto", "none"],
        help="the cracks' tip enrichment: the default zone, or the tip cells' nodes (none)",
    )
    parser.add_argument(
        "--tip-dofs",
        default="nodal",
        choices=["nodal", "gathered"],
        help="the cracks' branch unknowns: each vertex's, or one per tip and function",
    )
    parser.add_argument(
        "--dense-below",
        type=int,
        default=1500,
        help="all eigenvalues of a dense matrix below this many unknowns, else the extreme "
        "ones (SLEPc; 0: always, about 5 times faster at n = 8)",
    )
    parser.add_argument(
        "--accuracy-columns",
        nargs="+",
        default=None,
        choices=list(ACCURACY_TREATMENTS),
        help="the accuracy part's treatments (default: all)",
    )
    parser.add_argument("--name", default=None, help="results name (default: the part's)")
    args = parser.parse_args()
    if "accuracy" in args.parts:
        accuracy(args.accuracy_columns, args.name or "aggregation_accuracy")
    if "conditioning" in args.parts:
        conditioning(args)
    if "crack_conditioning" in args.parts:
        conditioning(args, "crack")
    if "crack" in args.parts:
        crack()
    if "tip_dofs" in args.parts:
        tip_dofs(args)


def conditioning(args, kind: str = "interface") -> None:
    """The conditioning part (module docstring): prints and writes a Markdown table,
    for bonded circles (``kind = "interface"``) or free cracks (``"crack"``)."""
    elements = [(e.split(":")[0], int(e.split(":")[1])) for e in args.elements]
    treatments = {label: TREATMENTS[label] for label in args.treatments}
    rows = []
    for cell, degree in elements:
        for n in args.sizes:
            mesh = dolfinx.mesh.create_unit_square(
                MPI.COMM_WORLD, n, n, dolfinx.mesh.CellType[cell]
            )
            make = circles if kind == "interface" else cracks
            samples = make(args.circles, n, np.random.default_rng(1000 + n))
            C = {label: [] for label in treatments}
            start = time.perf_counter()
            for label, (ghost_penalty, aggregation) in treatments.items():
                if kind == "interface":
                    problem = bonded_circle(
                        mesh, (0.5, 0.5), 0.2, degree, ghost_penalty, aggregation
                    )
                else:
                    problem = free_crack(
                        mesh,
                        (0.5, 0.5),
                        0.3,
                        degree,
                        ghost_penalty,
                        aggregation,
                        args.tip_basis,
                        None if args.tip_radius == "none" else "auto",
                        args.tip_dofs,
                    )
                for a, b, c in samples:
                    if kind == "interface":
                        problem.update_interface(circle((a, b), c))
                    else:
                        problem.update_interface(*crack_levelsets((a, b), c))
                    C[label].append(scaled_condition(problem, args.dense_below) / n**2)
            reference = float(np.median(C.get(REFERENCE, next(iter(C.values())))))
            for label, values in C.items():
                v = np.array(values)
                rows.append(
                    {
                        "cell": cell,
                        "degree": degree,
                        "n": n,
                        "treatment": label,
                        "C_max": float(v.max()),
                        "C_median": float(np.median(v)),
                        "outliers": int((v > OUTLIER * reference).sum()),
                        "C": values,
                    }
                )
                note(
                    f"{cell:13s} P{degree} n={n:3d} {label:19s}: C = cond h^2 max {v.max():.3e} "
                    f"median {np.median(v):.3e}, outliers {rows[-1]['outliers']}/{v.size} "
                    f"({time.perf_counter() - start:.1f} s)"
                )
    lines = [
        "| cell | P | treatment | "
        + " | ".join(f"n={n}: max / median C" for n in args.sizes)
        + " | outliers |",
        "|---|---|---|" + "---|" * len(args.sizes) + "---|",
    ]
    for cell, degree in elements:
        for label in treatments:
            key = (cell, degree, label)
            sel = [r for r in rows if (r["cell"], r["degree"], r["treatment"]) == key]
            cells = " | ".join(f"{r['C_max']:.2e} / {r['C_median']:.2e}" for r in sel)
            outliers = sum(r["outliers"] for r in sel)
            total = args.circles * len(sel)
            lines.append(f"| {cell} | {degree} | {label} | {cells} | {outliers}/{total} |")
    RESULTS.mkdir(exist_ok=True)
    name = "aggregation" if kind == "interface" else "aggregation_crack_conditioning"
    if kind == "crack" and args.tip_basis != "auto":
        name += f"_{args.tip_basis}"
    if kind == "crack" and args.tip_radius != "auto":
        name += "_topological"
    if kind == "crack" and args.tip_dofs != "nodal":
        name += f"_{args.tip_dofs}"
    name = args.name or name
    (RESULTS / f"{name}.md").write_text("\n".join(lines) + "\n")
    (RESULTS / f"{name}.json").write_text(json.dumps({"rows": rows, "args": vars(args)}))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
