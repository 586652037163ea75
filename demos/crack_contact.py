"""An inclined crack in a plate: open under tension, then closed under compression with
Coulomb friction on its lips.

A centre crack of half length a = 0.1 m, inclined at beta = 45 degrees to the load, in a
square plate of half width 4a (E = 210 GPa, nu = 0.3, plane strain), P2 X-FEM with the
Heaviside and branch-function enrichment (tip radius 0.3a). Two loadings of the same
problem:

1. a remote tension sigma = 10 MPa (tractions on top and bottom): the crack opens;
   K_I and K_II at both tips against Griffith's infinite-plate values
   ``sigma sin^2(beta) sqrt(pi a)`` and ``sigma sin(beta) cos(beta) sqrt(pi a)``: the
   plate's free edges raise them, by 8 % and 6 % here (with Westergaard's exact
   displacement on the same plate's edges this mesh gives K within 3e-5 of them);
2. the same stress as compression, Coulomb friction 0.3 on the lips: the lips stay
   closed and slide; K_I vanishes (the lip term of the interaction integral carries the
   contact tractions; what is left, 3 % of |K| at most, is the discretisation's) and
   ``K_II = -(|tau| - mu |sigma_n|) sqrt(pi a)`` for the infinite plate.

Each case prints a table: K_I, K_II (MPa m^1/2), J and G (J/m^2) per tip and ring, the
reference and the difference from it, the law of the lips and the loads.

Writes (in --out): the lips' opening, slip and multipliers (PNG), each side's
displacement with the branch functions (VTX, and ``result_CASE.vtu`` for ParaView: the
lips grid, ``.pvtu`` of the pieces under MPI) and a JSON summary.

Run: ``python demos/crack_contact.py [--n 48] [--out results/crack_contact]`` (also
under ``mpiexec -n 2``).
"""

# %% [markdown]
# ## Imports
# `xfem_contact` first (the PyPI wheel's MPI library), then DOLFINx.

# %%
import argparse
import math
import pathlib
import time

# isort: split
import dolfinx.fem
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.crack_data import EnrichedDisplacements, lip_samples
from xfem_contact.io.crack_report import Reference, crack_table, load_words, tip_records
from xfem_contact.io.meshes import ghosted_partitioner
from xfem_contact.io.output import write_fields, write_json, write_lips
from xfem_contact.io.plots import plot_lips
from xfem_contact.io.progress import printer
from xfem_contact.mechanics.fracture import GrowthPath, TipIntegrals, effective_modulus
from xfem_contact.mechanics.laws import make_law
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

# %% [markdown]
# ## The crack and the problem
# The crack is a `GrowthPath` (a segment here): its level sets `phi` (signed distance)
# and `psi` (distance ahead of the nearer tip) cut the mesh; the law of its lips is a
# Coulomb law with multipliers (LBB-stable P2-P1 pair), which also holds the open
# crack: with tension the lips separate and carry nothing.


# %%
def build(n: int, a: float, beta: float, friction: float, comm) -> tuple:
    half = 4 * a
    d = np.array([math.cos(math.pi / 2 - beta), math.sin(math.pi / 2 - beta)])
    centre = np.array([0.0123, 0.0271]) * a  # off the mesh lines
    path = GrowthPath([centre - a * d, centre + a * d])
    mesh = dolfinx.mesh.create_rectangle(
        comm, [[-half, -half], [half, half]], [n, n], partitioner=ghosted_partitioner()
    )
    cut = CutMesh(mesh, path.phi, degree=2, tangent=path.psi)
    law = make_law("coulomb", friction=friction, lbb="none")
    material = Material(210e9, 0.3, "strain")
    problem = Problem(cut, 2, material, law, tip_radius=0.3 * a)
    top = problem.loads.add_traction(lambda x: np.isclose(x[1], half), (0.0, 1.0))
    bottom = problem.loads.add_traction(lambda x: np.isclose(x[1], -half), (0.0, -1.0))
    for component in (0, 1):
        problem.loads.add_point_displacement((-half, -half), 0.0, component)
    problem.loads.add_point_displacement((half, -half), 0.0, 1)
    return problem, (top, bottom), d


# %% [markdown]
# ## The run
# Tension, then compression: the traction handles' values change, nothing is
# compiled again. After each solve, K at both tips on two rings and the lips.


# %%
def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--n", type=int, default=48, help="cells per side of the plate (default %(default)s)"
    )
    parser.add_argument(
        "--out",
        default="results/crack_contact",
        help="folder of the results: PNG, VTX, summary.json (default %(default)s)",
    )
    parser.add_argument("--no-progress", action="store_true", help="print no progress lines")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = printer(not args.no_progress, comm)
    out = pathlib.Path(args.out)
    a, beta, sigma, friction = 0.1, math.pi / 4, 10e6, 0.3
    start = time.perf_counter()
    problem, (top, bottom), _ = build(args.n, a, beta, friction, comm)
    name = problem.cut.interface_names[0]
    s, c = math.sin(beta), math.cos(beta)
    root = math.sqrt(math.pi * a)
    finite = (
        "the plate is finite (a square of side 8a = 0.8 m): its free edges raise K over the "
        "infinite plate's"
    )
    griffith = {
        "tension": Reference(
            sigma * s * s * root,
            sigma * s * c * root,
            "Griffith, infinite plate: sigma sin^2(beta) sqrt(pi a), sigma sin(beta) "
            f"cos(beta) sqrt(pi a); {finite}",
        ),
        "compression": Reference(
            0.0,
            -(sigma * s * c - friction * sigma * s * s) * root,
            "closed crack in an infinite plate, Coulomb friction mu on its lips: 0, "
            f"-(|tau| - mu |sigma_n|) sqrt(pi a); {finite}",
        ),
    }
    rings = [(0.3 * a, 0.7 * a), (0.4 * a, 0.9 * a)]
    modulus = effective_modulus(210e9, 0.3, "strain")
    summary = {"n": args.n, "dofs": problem.space.dof_counts().total, "cases": {}}
    V = dolfinx.fem.functionspace(problem.mesh, ("Lagrange", 2, (2,)))
    sides = [dolfinx.fem.Function(V, name=f"u_{label}") for label in ("minus", "plus")]
    outputs = EnrichedDisplacements(problem, sides)
    for case, sign in (("tension", 1.0), ("compression", -1.0)):
        top.value, bottom.value = (0.0, sign * sigma), (0.0, -sign * sigma)
        problem.w.x.array[:] = 0.0
        problem.w_old.x.array[:] = 0.0
        report = problem.solve()
        crack = problem.cut.crack
        results = TipIntegrals(problem, rings).evaluate()
        tips = tip_records(crack.tips, crack.directions, results)
        reference = griffith[case]
        loads = f"{case}, {load_words(problem.loads)} (top and bottom edges)"
        law = problem.laws[name].describe()
        for line in crack_table("centre crack", tips, law, loads, reference, modulus):
            say(line)
        lips = lip_samples(problem, name)
        centre = np.mean(problem.cut.crack.tips, axis=0)
        d = problem.cut.crack.directions[-1]
        lips["s"] = ((np.c_[lips["x"], lips["y"]] - centre) @ d).tolist()
        if comm.rank == 0:
            plot_lips(lips, out / f"lips_{case}.png", "s along the crack (m)", f"Lips, {case}")
        for target, source in zip(sides, (0, 1), strict=True):
            target.x.array[:] = problem.space.field(problem.w, source).x.array
        outputs.update()
        write_fields(out, f"displacement_{case}", sides)
        write_lips(out / f"result_{case}.vtu", problem.cut, *sides)
        summary["cases"][case] = {
            "newton": report.iterations,
            "law": law,
            "tips": tips,
            "reference": {"K_I": reference.K_I, "K_II": reference.K_II},
            "max_opening": float(np.max(lips["opening"])),
            "max_slip": float(np.max(np.abs(lips["slip"]))),
        }
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        write_json(out / "summary.json", summary)
    say(f"{summary['dofs']} dofs, {summary['time']:.1f} s; results in {out}")


if __name__ == "__main__":
    main()
