"""An inclined crack in a plate: open under tension, then closed under compression with
Coulomb friction on its lips.

A centre crack of half length a = 0.1 m, inclined at beta = 45 degrees to the load, in a
square plate of half width 4a (E = 210 GPa, nu = 0.3, plane strain), P2 X-FEM with the
Heaviside and branch-function enrichment (tip radius 0.3a). Two loadings of the same
problem:

1. a remote tension sigma = 10 MPa (tractions on top and bottom): the crack opens;
   K_I and K_II at both tips against Griffith's infinite-plate values
   ``sigma sin^2(beta) sqrt(pi a)`` and ``sigma sin(beta) cos(beta) sqrt(pi a)`` (the
   plate's finite width raises them by a few per cent);
2. the same stress as compression, Coulomb friction 0.3 on the lips: the lips stay
   closed and slide; K_I vanishes (the lip term of the interaction integral carries the
   contact tractions) and K_II = (|tau| - mu |sigma_n|) sqrt(pi a) for the infinite plate.

Writes (in --out): the lips' opening, slip and multipliers (PNG), each side's
displacement with the branch functions (VTX) and a JSON summary.

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
from xfem_contact.io.meshes import ghosted_partitioner
from xfem_contact.io.output import write_fields, write_json
from xfem_contact.io.plots import plot_lips
from xfem_contact.mechanics.fracture import CrackPath, TipIntegrals
from xfem_contact.mechanics.laws import make_law
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.problem import Problem

# %% [markdown]
# ## The crack and the problem
# The crack is a `CrackPath` (a segment here): its level sets `phi` (signed distance)
# and `psi` (distance ahead of the nearer tip) cut the mesh; the law of its lips is a
# Coulomb law with multipliers (LBB-stable P2-P1 pair), which also holds the open
# crack: with tension the lips separate and carry nothing.


# %%
def build(n: int, a: float, beta: float, friction: float, comm) -> tuple:
    half = 4 * a
    d = np.array([math.cos(math.pi / 2 - beta), math.sin(math.pi / 2 - beta)])
    centre = np.array([0.0123, 0.0271]) * a  # off the mesh lines
    path = CrackPath([centre - a * d, centre + a * d])
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
    say = print if comm.rank == 0 and not args.no_progress else (lambda *a: None)
    out = pathlib.Path(args.out)
    a, beta, sigma, friction = 0.1, math.pi / 4, 10e6, 0.3
    start = time.perf_counter()
    problem, (top, bottom), _ = build(args.n, a, beta, friction, comm)
    name = problem.cut.interface_names[0]
    s, c = math.sin(beta), math.cos(beta)
    root = math.sqrt(math.pi * a)
    griffith = {
        "tension": (sigma * s * s * root, sigma * s * c * root),
        "compression": (0.0, (sigma * s * c - friction * sigma * s * s) * root),
    }
    rings = [(0.3 * a, 0.7 * a), (0.4 * a, 0.9 * a)]
    summary = {"n": args.n, "dofs": problem.space.dof_counts().total, "cases": {}}
    V = dolfinx.fem.functionspace(problem.mesh, ("Lagrange", 2, (2,)))
    sides = [dolfinx.fem.Function(V, name=f"u_{label}") for label in ("minus", "plus")]
    outputs = EnrichedDisplacements(problem, sides)
    for case, sign in (("tension", 1.0), ("compression", -1.0)):
        top.value, bottom.value = (0.0, sign * sigma), (0.0, -sign * sigma)
        problem.w.x.array[:] = 0.0
        problem.w_old.x.array[:] = 0.0
        report = problem.solve()
        results = TipIntegrals(problem, rings).evaluate()
        K_I, K_II = griffith[case]
        tips = []
        for k, per_ring in enumerate(results):
            K = [(r.K_I, r.K_II) for r in per_ring]
            tips.append({"position": problem.cut.crack.tips[k].tolist(), "K": K})
            say(
                f"{case}, tip {k}: K_I {K[0][0] / 1e6:.4f}, K_II {abs(K[0][1]) / 1e6:.4f} "
                f"MPa m^1/2 (infinite plate {K_I / 1e6:.4f}, {abs(K_II) / 1e6:.4f}; second "
                f"ring {K[1][0] / 1e6:.4f}, {abs(K[1][1]) / 1e6:.4f})"
            )
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
        summary["cases"][case] = {
            "newton": report.iterations,
            "tips": tips,
            "infinite_plate": {"K_I": K_I, "K_II": K_II},
            "max_opening": float(np.max(lips["opening"])),
            "max_slip": float(np.max(np.abs(lips["slip"]))),
        }
    summary["time"] = time.perf_counter() - start
    if comm.rank == 0:
        write_json(out / "summary.json", summary)
    say(f"{summary['dofs']} dofs, {summary['time']:.1f} s; results in {out}")


if __name__ == "__main__":
    main()
