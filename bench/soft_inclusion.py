"""Where the multiplier of a soft inclusion errs, and through which side's traction.

Paper case 2 (16 x 16, Q2, sticking, hydrostatic pressure 1 Pa) with the inclusion
``--contrast`` times the matrix's modulus, for each Barbosa-Hughes length and ghost
penalty asked for. Prints the multiplier's Fourier misfit
(:func:`~xfem_contact.cases.paper.pressure_fourier_misfit`, the check of
``tests/stability/test_materials.py``) and its largest error against a reference (the
cut's lengths without the ghost penalty on a 48 x 48 mesh), both over the mean
``|lambda_n|``; at the worst point, the errors of each side's own normal traction
``n . sigma_s(u_s) n`` against the reference, the sides' trace lengths (the scale's own
ones; ``"patch"``: its credited ones) and the weight of the matrix (stiff) side in the
traction average. Serial.
Run: ``python bench/soft_inclusion.py [--contrast 1e-2] [--lengths cut patch cell]
[--ghost 0 0.01]``.
"""

import argparse

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import numpy as np

from xfem_contact.cases.paper import (
    INCLUSION_CENTRE,
    INCLUSION_E,
    inclusion_problem,
    pressure_fourier_misfit,
)
from xfem_contact.fem.evaluation import cell_dofs, lagrange_element, rule_cells
from xfem_contact.mechanics.materials import Material

SIDES = (-1, 1)


def solve(n, contrast, length, ghost):
    materials = {-1: Material(contrast * INCLUSION_E, 0.0), 1: Material(INCLUSION_E, 0.0)}
    problem = inclusion_problem(
        n,
        2,
        "sticking",
        loading="hydrostatic",
        materials=materials,
        stabilization_length=length,
        ghost_penalty=ghost,
    )
    problem.solve()
    return problem


def angles(x, y):
    return np.arctan2(np.asarray(y) - INCLUSION_CENTRE[1], np.asarray(x) - INCLUSION_CENTRE[0])


def side_tractions(problem):
    """Per side, ``n . sigma_s(u_s) n`` (Pa) at the interface rule points, with the
    points, their cells and the context."""
    ctx = next(iter(problem.contexts.values()))
    cells, X = rule_cells(ctx.cut, ctx.rules), ctx.rules.points
    J = ctx.cut.maps.jacobian(cells, X)[:, :2, :2]
    n = ctx.normal_at()
    out = {}
    for field, s in enumerate(SIDES):
        V = problem.w.function_space.sub(field)
        dphi = lagrange_element(V).tabulate(1, X)[1:, :, :, 0]  # (2, points, nodes)
        values = problem.w.x.array[cell_dofs(V, cells)]  # (points, nodes, 2)
        grad = np.einsum("dpi,pic->pcd", dphi, values) @ np.linalg.inv(J)
        strain = 0.5 * (grad + np.swapaxes(grad, 1, 2))
        material = ctx.materials[s].material
        stress = 2.0 * material.mu * strain + material.lmbda * np.einsum(
            "pii->p", strain
        )[:, None, None] * np.eye(2)
        out[s] = np.einsum("pi,pij,pj->p", n, stress, n)
    x = ctx.cut.maps.push_forward(cells, X)
    return out, x, cells, ctx


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=16, help="cells per side")
    parser.add_argument("--contrast", type=float, default=1e-2, help="inclusion / matrix E")
    parser.add_argument("--lengths", nargs="+", default=["cut", "patch", "cell"])
    parser.add_argument("--ghost", type=float, nargs="+", default=[0.0, 0.01])
    args = parser.parse_args()
    reference = solve(48, args.contrast, "cut", 0.0)
    samples = reference.interface_samples(reference.w)
    theta_ref = angles(samples["x"], samples["y"])
    order = np.argsort(theta_ref)
    theta_ref, lam_ref = theta_ref[order], np.array(samples["lambda_n"])[order]
    print(f"reference (48 x 48, cut, no ghost penalty): misfit "
          f"{pressure_fourier_misfit(reference):.4f}")
    for length in args.lengths:
        for ghost in args.ghost:
            problem = solve(args.n, args.contrast, length, ghost)
            traction, x, cells, ctx = side_tractions(problem)
            exact = np.interp(angles(x[:, 0], x[:, 1]), theta_ref, lam_ref, period=2 * np.pi)
            scale = np.abs(exact).mean()
            lam = ctx.multiplier_parts_at(ctx.values_at(problem.w, ctx.field))[0]
            error = (lam - exact) / scale
            k = int(np.argmax(np.abs(error)))
            V0 = ctx.cell_size.function_space
            lengths = ctx.trace_lengths(patch=length == "patch")
            l_soft, l_stiff = (lengths[s].x.array[V0.dofmap.list[cells[k], 0]] for s in SIDES)
            m = {s: ctx.materials[s].material for s in SIDES}
            c_soft = l_soft / (2.0 * m[-1].mu + m[-1].lmbda)
            c_stiff = l_stiff / (2.0 * m[1].mu + m[1].lmbda)
            if length == "cell":
                mu = [m[s].mu for s in SIDES]
                w_stiff = mu[0] / (mu[0] + mu[1])
            else:
                w_stiff = c_stiff / (c_soft + c_stiff)
            e_soft, e_stiff = ((traction[s][k] - exact[k]) / scale for s in SIDES)
            print(
                f"{length:5s} ghost {ghost:g}: misfit {pressure_fourier_misfit(problem):.4f}, "
                f"largest error {error[k]:+.4f} at ({x[k, 0]:.3f}, {x[k, 1]:.3f}): "
                f"inclusion's traction {e_soft:+.4f}, matrix's {e_stiff:+.3f}; trace lengths "
                f"{l_soft:.2e} (inclusion), {l_stiff:.2e} m; matrix weight {w_stiff:.4f} "
                f"(times its error {w_stiff * e_stiff:+.4f})",
                flush=True,
            )


if __name__ == "__main__":
    main()
