"""Sphere volume and area by the 3D cut rules on structured meshes of the unit cube, and a
fuzz of random cuts of single cells.

Relative errors of the volume and area of the sphere of radius ``R = 0.3`` centred at
``(0.5, 0.5, 0.5)``, whose level set is the signed distance interpolated per cell (P1 / P2
on tetrahedra, six per cube; Q1 / Q2 on hexahedra), with the rates of consecutive sizes,
the number of cut cells and the time of cut + rules::

    python bench/cut3d.py --sizes 4 8 16 32

The fuzz (``--fuzz N``) cuts ``N`` reference cells per kind by random spheres, ellipsoids,
tori and planes (a third of them moved to pass exactly through a node) and counts the
failures: a non-positive weight, side volumes missing the cell volume by more than 1e-12,
or an exception other than the documented refusal of a singular zero set (counted apart)::

    python bench/cut3d.py --fuzz 10000 --sizes
"""

from __future__ import annotations

import argparse
import itertools
import time

import basix
import numpy as np

from xfem_contact.geometry.cut_tets import classify_tets, cut_tets
from xfem_contact.quadrature.curved_tet_rules import classify_p2_tets, p2_tet_cut_rules
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


def kuhn_mesh(n: int, perturb: float = 0.0) -> np.ndarray:
    """Vertices ``(6 n^3, 4, 3)`` of the Kuhn tetrahedra of ``n^3`` cubes; with ``perturb``
    every mesh vertex moves by a random vector of at most ``perturb h`` per coordinate
    (seeded; an unstructured-like mesh)."""
    index = (
        np.array(list(itertools.product(range(n), repeat=3)))[:, None, None]
        + np.array(KUHN, dtype=int)[None]
    ).reshape(-1, 3)
    move = np.random.default_rng(0).uniform(-perturb, perturb, size=(n + 1, n + 1, n + 1, 3))
    vertices = ((index + move[index[:, 0], index[:, 1], index[:, 2]]) / n).reshape(-1, 4, 3)
    grid = index.reshape(-1, 4, 3).astype(float)
    before = np.linalg.det(grid[:, 1:] - grid[:, :1])
    after = np.linalg.det(vertices[:, 1:] - vertices[:, :1])
    if (before * after <= 0).any():
        raise ValueError(f"perturb = {perturb} inverts tetrahedra; use a smaller value")
    return vertices


PERTURB = 0.0
"""Vertex perturbation of the tetrahedral meshes (``--perturb``)."""


def sphere_tets(n: int, degree: int = 4) -> tuple[float, float, int]:
    """Volume, area and cut-cell count on ``6 n^3`` tetrahedra (P1 level set)."""
    vertices = kuhn_mesh(n, PERTURB)
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


def sphere_p2_tets(n: int, order: int = 4) -> tuple[float, float, int]:
    """Volume, area and cut-cell count on ``6 n^3`` tetrahedra (P2 level set, Saye's
    rules on its four hexahedra)."""
    vertices = kuhn_mesh(n, PERTURB)
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))
    detJ = np.abs(np.linalg.det(J))
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
    )
    x = vertices[:, :1] + np.einsum("qk,ndk->nqd", element.points, J)
    phi = level_set(x)
    side = classify_p2_tets(phi)
    cut = np.flatnonzero(side == 0)
    rules = p2_tet_cut_rules(phi[cut], order, jacobian=lambda rows, X: J[cut[rows]])
    volume = detJ[side == -1].sum() / 6.0
    volume += (rules.minus.weights * detJ[cut[rules.minus.point_rows]]).sum()
    area = (rules.interface.weights * detJ[cut[rules.interface.point_rows]]).sum()
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


def random_level_set(rng: np.random.Generator):
    """A random sphere, ellipsoid, torus or plane around the reference cells, as a callable
    on points ``(..., 3)``."""
    centre = rng.uniform(-0.5, 1.5, size=3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shape = rng.choice(["sphere", "ellipsoid", "torus", "plane"])
    if shape == "plane":
        normal = Q[0]
        return lambda x: (x - centre) @ normal
    if shape == "sphere":
        radius = rng.uniform(0.05, 1.5)
        return lambda x: np.linalg.norm(x - centre, axis=-1) - radius
    if shape == "ellipsoid":
        axes = rng.uniform(0.1, 1.2, size=3)
        return lambda x: np.linalg.norm(((x - centre) @ Q) / axes, axis=-1) - 1.0
    big, small = rng.uniform(0.3, 1.0), rng.uniform(0.05, 0.3)

    def torus(x):
        y = (x - centre) @ Q
        return np.hypot(np.hypot(y[..., 0], y[..., 1]) - big, y[..., 2]) - small

    return torus


def fuzz_cells(kind: str, count: int, seed: int = 0) -> dict[str, int]:
    """Failures of the rules of ``count`` random cuts of one reference cell of ``kind``:
    ``{"cases", "cut", "weights", "volume", "errors", "refused", "reduced"}``."""
    rng = np.random.default_rng(seed)
    cell = {
        "tet-P1": ("tetrahedron", 1),
        "tet-P2": ("tetrahedron", 2),
        "hex-Q1": ("hexahedron", 1),
        "hex-Q2": ("hexahedron", 2),
    }[kind]
    element = basix.create_element(
        basix.ElementFamily.P,
        getattr(basix.CellType, cell[0]),
        cell[1],
        basix.LagrangeVariant.gll_warped,
    )
    phi = np.array([random_level_set(rng)(element.points) for _ in range(count)])
    through = rng.random(count) < 1 / 3
    node = rng.integers(0, element.points.shape[0], size=count)
    phi[through] -= phi[through, node[through], None]  # zero at a node, exactly
    phi[through, node[through]] = 0.0
    volume = 1.0 / 6.0 if cell[0] == "tetrahedron" else 1.0
    counts = dict.fromkeys(("cases", "cut", "weights", "volume", "errors", "refused", "reduced"), 0)
    counts["cases"] = count
    batch = 500
    for start in range(0, count, batch):
        rows = np.arange(start, min(start + batch, count))
        try:
            _check_batch(kind, phi[rows], volume, counts)
        except Exception:  # noqa: BLE001 - find the failing cells one by one
            for row in rows:
                try:
                    _check_batch(kind, phi[row : row + 1], volume, counts)
                except ValueError as error:
                    counts["refused" if "singular point" in str(error) else "errors"] += 1
                except Exception:  # noqa: BLE001 - a fuzz counts every failure
                    counts["errors"] += 1
    return counts


def _check_batch(kind: str, phi: np.ndarray, volume: float, counts: dict[str, int]) -> None:
    """Rules of cells ``phi``; adds their failures to ``counts`` (raises before adding)."""
    n = phi.shape[0]
    if kind == "tet-P1":
        geometry = cut_tets(phi)
        rules = [
            tet_side_rules(geometry, -1, 2),
            tet_side_rules(geometry, 1, 2),
            tet_interface_rule(geometry, 2),
        ]
        reduced = 0
    else:
        found = p2_tet_cut_rules(phi) if kind == "tet-P2" else hex_cut_rules(phi, int(kind[-1]))
        rules = [found.minus, found.plus, found.interface]
        reduced = found.reduced.size
    minus, plus = (np.bincount(r.point_rows, r.weights, minlength=n) for r in rules[:2])
    bad = np.zeros(n, dtype=bool)
    for r in rules:
        bad[r.point_rows[r.weights <= 0]] = True
    counts["cut"] += int(((minus > 0) & (plus > 0)).sum())
    counts["reduced"] += int(reduced)
    counts["weights"] += int(bad.sum())
    counts["volume"] += int((np.abs(minus + plus - volume) > 1e-12).sum())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--sizes", type=int, nargs="*", default=[4, 8, 16, 32], help="cells per side (h = 1/n)"
    )
    parser.add_argument(
        "--kinds",
        nargs="+",
        default=["tet-P1", "tet-P2", "hex-Q1", "hex-Q2"],
        choices=["tet-P1", "tet-P2", "hex-Q1", "hex-Q2"],
        help="cell kind and degree",
    )
    parser.add_argument(
        "--fuzz",
        type=int,
        default=0,
        metavar="N",
        help="random cuts of one cell per kind (0: none)",
    )
    parser.add_argument(
        "--perturb",
        type=float,
        default=0.0,
        help="random vertex moves of the tetrahedral meshes, in units of h",
    )
    args = parser.parse_args()
    global PERTURB
    PERTURB = args.perturb
    for kind in args.kinds if args.fuzz else []:
        start = time.perf_counter()
        counts = fuzz_cells(kind, args.fuzz)
        failures = counts["weights"] + counts["volume"] + counts["errors"]
        print(
            f"fuzz {kind}: {counts} -> {failures} failure(s) ({time.perf_counter() - start:.1f} s)"
        )
    runs = {
        "tet-P1": sphere_tets,
        "tet-P2": sphere_p2_tets,
        "hex-Q1": lambda n: sphere_hexes(n, 1),
        "hex-Q2": lambda n: sphere_hexes(n, 2),
    }
    for kind in args.kinds if args.sizes else []:
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
