"""Paper case 1: straight interface, no contact (Heaviside-enriched elasticity).

A 3 m x 2 m plate (x in [-1.5, 1.5], y in [0, 2]) cut by the interface y = 1 (not
a mesh line), plane stress, E = 10 GPa, nu = 0.2. Bottom clamped; top u_x = 0,
u_y = -2.5e-6 x^2 + 1e-5 m; lateral pressure P = 0.1 - 0.05 y MPa on the upper
block only; the interface is free (an open gap). The upper block's exact field is
quadratic, so quadratic X-FEM reproduces it to round-off; the lower block does
not move and the gap stays >= 3.875e-6 m.

Writes (in --out): the interface displacement plot (u_y of both lips against x,
exact dashed: the paper's Fig. 4) as PNG, VTX fields, ``result.vtu`` (the lips),
``subcells.vtu``/``interface.vtu`` (the cut), and a JSON summary (``--json``,
default OUT/summary.json); ``xfem-contact show OUT`` renders the folder.

Run: ``python demos/straight_interface.py --degree 2 --cell quadrilateral``
(also under ``mpiexec -n 2``).
"""

# %% [markdown]
# ## Imports
# `xfem_contact` first (the PyPI wheel's MPI library), then DOLFINx and UFL.

# %%
import argparse
import pathlib
import time

import xfem_contact

# isort: split
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.cases.paper import straight_interface_exact, straight_interface_problem
from xfem_contact.fem.evaluation import evaluate_at_rules, interface_points
from xfem_contact.io.output import write_cut_geometry, write_fields, write_json, write_lips
from xfem_contact.io.plots import Series, line_plot
from xfem_contact.io.progress import add_output_arguments, printer

# %% [markdown]
# ## The run
# Paper case 1: the plate cut by the straight interface y = 1 (free), one linear
# solve, the interface displacement of both blocks against the exact quadratic field,
# the output files and the JSON summary.


# %%
def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--degree",
        type=int,
        default=2,
        choices=[1, 2],
        help="polynomial degree of the displacement (default %(default)s)",
    )
    parser.add_argument(
        "--cell",
        default="quadrilateral",
        choices=["quadrilateral", "triangle"],
        help="cell shape of the mesh (default %(default)s)",
    )
    parser.add_argument("--nx", type=int, default=20, help="cells along x (default %(default)s)")
    parser.add_argument(
        "--ny",
        type=int,
        default=29,
        help="cells along y, odd so that the interface stays inside a row of cells "
        "(default %(default)s)",
    )
    add_output_arguments(parser, "results/straight_interface", "VTX, .vtu, PNG, summary.json")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    say = printer(not args.quiet, comm)
    out = pathlib.Path(args.out)
    timings = {}

    t0 = time.perf_counter()
    problem = straight_interface_problem(args.nx, args.ny, args.degree, args.cell, comm)
    cut, mesh = problem.cut, problem.mesh
    timings["setup"] = time.perf_counter() - t0
    say(f"mesh {args.nx}x{args.ny} {args.cell}, {cut.num_cut_cells_global} cut cells")

    t0 = time.perf_counter()
    solution = problem.solve()
    timings["assemble_and_solve"] = time.perf_counter() - t0
    dofs = problem.space.dof_counts()
    say(f"degree {args.degree}: dofs {dofs.standard} standard + {dofs.enriched} enriched")

    xi = interface_points(cut)
    lower = evaluate_at_rules(solution.w.sub(0), cut, cut.interface_rules)
    upper = evaluate_at_rules(solution.w.sub(1), cut, cut.interface_rules)
    exact = np.array(straight_interface_exact(xi.T)).T
    umax = comm.allreduce(np.max(np.abs(exact), initial=0.0), op=MPI.MAX)
    err_upper = comm.allreduce(np.max(np.abs(upper - exact), initial=0.0), op=MPI.MAX) / umax
    err_lower = comm.allreduce(np.max(np.abs(lower), initial=0.0), op=MPI.MAX)
    gap = comm.allreduce(np.min(upper[:, 1] - lower[:, 1], initial=np.inf), op=MPI.MIN)
    x = ufl.SpatialCoordinate(mesh)
    u_ex = ufl.as_vector(straight_interface_exact(x))
    up = ufl.split(solution.w)[1]
    l2 = np.sqrt(
        comm.allreduce(
            dolfinx.fem.assemble_scalar(
                xfem_contact.form(ufl.inner(up - u_ex, up - u_ex) * cut.dx(1))
            ),
            op=MPI.SUM,
        )
        / comm.allreduce(
            dolfinx.fem.assemble_scalar(xfem_contact.form(ufl.inner(u_ex, u_ex) * cut.dx(1))),
            op=MPI.SUM,
        )
    )
    say(
        f"interface: max |u+ - exact| / max|u| = {err_upper:.3e}; max |u-| = {err_lower:.3e} m;"
        f" min gap = {gap:.4e} m (exact 3.875e-06); upper-block L2 error {l2:.3e}"
    )

    t0 = time.perf_counter()
    u_minus, u_plus = solution.displacement(-1), solution.displacement(+1)
    write_fields(out, "displacement", [u_minus, u_plus])
    write_lips(out / "result.vtu", cut, u_minus, u_plus)
    write_cut_geometry(out, cut)
    rows_upper = np.c_[xi, upper]
    rows_lower = np.c_[xi, lower]
    gathered = comm.gather((rows_upper, rows_lower), root=0)
    timings["output"] = time.perf_counter() - t0
    if comm.rank == 0:
        rows_upper = np.concatenate([g[0] for g in gathered])
        rows_lower = np.concatenate([g[1] for g in gathered])
        order = np.argsort(rows_upper[:, 0])
        plot(out / "interface_displacement.png", rows_upper[order], rows_lower[order], args)
        summary = {
            "case": "paper case 1: straight interface, no contact",
            "degree": args.degree,
            "cell": args.cell,
            "mesh": [args.nx, args.ny],
            "ranks": comm.size,
            "dofs": dofs._asdict() | {"total": dofs.total},
            "interface_rel_max_error": err_upper,
            "upper_block_rel_L2_error": l2,
            "lower_block_max_displacement": err_lower,
            "min_gap": gap,
            "timings": timings,
            "interface_samples": rows_upper[order],
            "lower_lip_samples": rows_lower[order],
        }
        path = write_json(args.json or out / "summary.json", summary)
        say(f"wrote {path}, {out / 'interface_displacement.png'}, VTX and .vtu files in {out}")


# %% [markdown]
# ## The interface displacement (the paper's Fig. 4)


# %%
def plot(path, upper, lower, args):
    x = np.linspace(-1.5, 1.5, 200)
    line_plot(
        path,
        [
            Series(upper[:, 0], upper[:, 3] * 1e6, "o", "upper lip (X-FEM)"),
            Series(lower[:, 0], lower[:, 3] * 1e6, "s", "lower lip (X-FEM)"),
            Series(x, (9.5e-6 - 2.5e-6 * x**2) * 1e6, "k--", "exact upper lip"),
        ],
        "x (m)",
        "u_y on the interface (µm)",
        f"Case 1, degree {args.degree}, {args.cell}",
    )


# %%
if __name__ == "__main__":
    main()
