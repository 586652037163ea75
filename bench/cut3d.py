"""Sphere volume and area by the 3D cut rules on structured meshes of the unit cube.

Relative errors of the volume and area of the sphere of radius ``R = 0.3`` centred at
``(0.5, 0.5, 0.5)``, whose level set is the signed distance interpolated per cell (P1 on
tetrahedra, six per cube; Q1 / Q2 on hexahedra), with the rates of consecutive sizes,
the number of cut cells and the time of cut + rules::

    python bench/cut3d.py --sizes 4 8 16 32
"""

from __future__ import annotations

import argparse
import itertools
import time

import basix
import numpy as np

from xfem_contact.geometry.cut_tets import classify_tets, cut_tets
from xfem_contact.quadrature.cut_tet_rules import tet_interface_rule, tet_side_rules
from xfem_contact.quadrature.saye import classify_hexes, hex_cut_rules

R, CENTRE = 0.3, np.array([0.5, 0.5, 0.5])
VOLUME, AREA = 4.0 / 3.0 * np.pi * R**3, 4.0 * np.pi * R**2

#: The six tetrahedra of the cube [0, 1]^3 around its diagonal (0, 0, 0) - (1, 1, 1).
KUHN = [
    [(0, 0, 0), (1, 0, 0), (1, 1, 0), (1, 1, 1)],
    [(0, 0, 0), (1, 0, 0), (1, 0, 1), (1, 1, 1)],
    [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 1, 1)],
    [(0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1)],
    [(0, 0, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1)],
    [(0, 0, 0), (0, 0, 1), (0, 1, 1), (1, 1, 1)],
]


def level_set(x: np.ndarray) -> np.ndarray:
    return np.linalg.norm(x - CENTRE, axis=-1) - R


def origins(n: int) -> np.ndarray:
    return np.array(list(itertools.product(range(n), repeat=3)), dtype=float) / n


def sphere_tets(n: int, degree: int = 4) -> tuple[float, float, int]:
    """Volume, area and cut-cell count on ``6 n^3`` tetrahedra (P1 level set)."""
    h = 1.0 / n
    vertices = (origins(n)[:, None, None] + h * np.array(KUHN, dtype=float)[None]).reshape(-1, 4, 3)
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))
    detJ = np.abs(np.linalg.det(J))
    phi = level_set(vertices)
    side = classify_tets(phi)
    cut = np.flatnonzero(side == 0)
    geometry = cut_tets(phi[cut])
    minus = tet_side_rules(geometry, -1, degree)
    gamma = tet_interface_rule(geometry, degree, lambda rows, X: J[cut[rows]])
    volume = detJ[side == -1].sum() / 6.0 + (minus.weights * detJ[cut[minus.point_rows]]).sum()
    area = (gamma.weights * detJ[cut[gamma.point_rows]]).sum()
    return volume, area, cut.size


def sphere_hexes(n: int, degree: int, order: int = 4) -> tuple[float, float, int]:
    """Volume, area and cut-cell count on ``n^3`` hexahedra (Q``degree`` level set)."""
    h = 1.0 / n
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, degree, basix.LagrangeVariant.gll_warped
    )
    phi = level_set(origins(n)[:, None] + h * element.points[None])
    side = classify_hexes(phi, degree)
    cut = np.flatnonzero(side == 0)
    J = np.broadcast_to(h * np.eye(3), (cut.size, 3, 3))
    rules = hex_cut_rules(phi[cut], degree, order, jacobian=lambda rows, X: J[rows])
    volume = ((side == -1).sum() + rules.minus.weights.sum()) * h**3
    area = rules.interface.weights.sum() * h**3
    return volume, area, cut.size


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=[4, 8, 16, 32], help="cells per side (h = 1/n)"
    )
    parser.add_argument(
        "--kinds",
        nargs="+",
        default=["tet-P1", "hex-Q1", "hex-Q2"],
        choices=["tet-P1", "hex-Q1", "hex-Q2"],
        help="cell kind and degree",
    )
    args = parser.parse_args()
    runs = {
        "tet-P1": sphere_tets,
        "hex-Q1": lambda n: sphere_hexes(n, 1),
        "hex-Q2": lambda n: sphere_hexes(n, 2),
    }
    for kind in args.kinds:
        print(f"\n{kind}: sphere R = {R}")
        print(
            f"{'n':>5} {'cut cells':>10} {'volume err':>11} {'rate':>5} {'area err':>11} "
            f"{'rate':>5} {'time s':>7}"
        )
        previous = None
        for n in args.sizes:
            start = time.perf_counter()
            volume, area, ncut = runs[kind](n)
            elapsed = time.perf_counter() - start
            ev, ea = abs(volume - VOLUME) / VOLUME, abs(area - AREA) / AREA
            rates = ["", ""]
            if previous is not None:
                ratio = n / previous[0]
                rates = [
                    f"{np.log(previous[1] / ev) / np.log(ratio):5.2f}",
                    f"{np.log(previous[2] / ea) / np.log(ratio):5.2f}",
                ]
            print(
                f"{n:5d} {ncut:10d} {ev:11.3e} {rates[0]:>5} {ea:11.3e} {rates[1]:>5} "
                f"{elapsed:7.2f}"
            )
            previous = (n, ev, ea)


if __name__ == "__main__":
    main()
