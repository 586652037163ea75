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
traction average; the root mean square over the points of each side's traction error;
and, on each side's ghost penalty facets, ``sum_F h^3 |[D^2 u]|^2`` over
``sum_F h |[D u]|^2`` (its second-derivative against its gradient jumps). Each
configuration also with the ghost penalty's factor of second-derivative jumps of
``--higher``. Serial.
Run: ``python bench/soft_inclusion.py [--contrast 1e-2] [--lengths cut patch cell]
[--ghost 0 0.01] [--higher 1 0.01 0]``.
"""

import argparse

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import dolfinx.fem
import numpy as np
import ufl

from xfem_contact.cases.paper import (
    INCLUSION_CENTRE,
    INCLUSION_E,
    inclusion_problem,
    pressure_fourier_misfit,
)
from xfem_contact.fem.evaluation import cell_dofs, lagrange_element, rule_cells
from xfem_contact.fem.forms import form
from xfem_contact.mechanics.bulk import ghost_penalty_facets
from xfem_contact.mechanics.materials import Material

SIDES = (-1, 1)


def solve(n, contrast, length, ghost, higher=1.0):
    materials = {-1: Material(contrast * INCLUSION_E, 0.0), 1: Material(INCLUSION_E, 0.0)}
    problem = inclusion_problem(
        n,
        2,
        "sticking",
        loading="hydrostatic",
        materials=materials,
        stabilization_length=length,
        ghost_penalty=ghost,
        ghost_penalty_higher=higher,
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
        trace = np.einsum("pii->p", strain)[:, None, None]
        stress = 2.0 * material.mu * strain + material.lmbda * trace * np.eye(2)
        out[s] = np.einsum("pi,pij,pj->p", n, stress, n)
    x = ctx.cut.maps.push_forward(cells, X)
    return out, x, cells, ctx


def jump_ratios(problem):
    """Per side, ``sum_F h^3 |[D^2 u]|^2 / sum_F h |[D u]|^2`` on its ghost penalty's
    facets (serial)."""
    dS = ufl.Measure("dS", domain=problem.mesh, subdomain_data=ghost_penalty_facets(problem.cut))
    h = ufl.avg(problem.cell_size)
    fields = ufl.split(problem.w)
    out = {}
    for i, s in enumerate(SIDES):
        grad = ufl.grad(fields[i])
        first = h * ufl.inner(ufl.jump(grad), ufl.jump(grad)) * dS(i + 1)
        second = h**3 * ufl.inner(ufl.jump(ufl.grad(grad)), ufl.jump(ufl.grad(grad))) * dS(i + 1)
        out[s] = dolfinx.fem.assemble_scalar(form(second)) / dolfinx.fem.assemble_scalar(
            form(first)
        )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=16, help="cells per side")
    parser.add_argument("--contrast", type=float, default=1e-2, help="inclusion / matrix E")
    parser.add_argument("--lengths", nargs="+", default=["cut", "patch", "cell"])
    parser.add_argument("--ghost", type=float, nargs="+", default=[0.0, 0.01])
    parser.add_argument("--higher", type=float, nargs="+", default=[1.0])
    args = parser.parse_args()
    reference = solve(48, args.contrast, "cut", 0.0)
    samples = reference.interface_samples(reference.w)
    theta_ref = angles(samples["x"], samples["y"])
    order = np.argsort(theta_ref)
    theta_ref, lam_ref = theta_ref[order], np.array(samples["lambda_n"])[order]
    print(
        f"reference (48 x 48, cut, no ghost penalty): misfit "
        f"{pressure_fourier_misfit(reference):.4f}"
    )
    configurations = [
        (length, ghost, higher)
        for length in args.lengths
        for ghost in args.ghost
        for higher in (args.higher if ghost > 0 else [1.0])
    ]
    for length, ghost, higher in configurations:
        problem = solve(args.n, args.contrast, length, ghost, higher)
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
        rms = [np.sqrt(np.mean((traction[s] - exact) ** 2)) / scale for s in SIDES]
        ratios = jump_ratios(problem)
        print(
            f"{length:5s} ghost {ghost:g} (higher {higher:g}): misfit "
            f"{pressure_fourier_misfit(problem):.4f}, "
            f"largest error {error[k]:+.4f} at ({x[k, 0]:.3f}, {x[k, 1]:.3f}): "
            f"inclusion's traction {e_soft:+.4f}, matrix's {e_stiff:+.3f}; trace lengths "
            f"{l_soft:.2e} (inclusion), {l_stiff:.2e} m; matrix weight {w_stiff:.4f} "
            f"(times its error {w_stiff * e_stiff:+.4f}); traction errors rms "
            f"{rms[0]:.3f} (inclusion), {rms[1]:.2f} (matrix); second / first jumps "
            f"{ratios[-1]:.3g} (inclusion), {ratios[1]:.3g} (matrix)",
            flush=True,
        )


if __name__ == "__main__":
    main()
