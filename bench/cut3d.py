"""Volumes and areas of a sphere, a torus and an ellipsoid by the 3D cut rules on
structured meshes of the unit cube, and a fuzz of random cuts of single cells.

Relative errors of the volume and area of three surfaces centred at ``(0.5, 0.5, 0.5)``,
whose level sets are interpolated per cell (P1 / P2 on tetrahedra, six per cube; Q1 / Q2
on hexahedra), with the rates of consecutive sizes, the number of cut cells and the CPU
time (``time.process_time``) of classification + cut + rules (not of the mesh and the
nodal values):

- sphere, ``R = 0.3``: the signed distance ``|x - c| - R``;
- torus about the z axis, ``R = 0.3``, ``r = 0.12``: the smooth quartic
  ``((rho - R)^2 + z^2 - r^2) ((rho + R)^2 + z^2 - r^2) / (4 R^2)`` (``rho`` the distance to
  the axis; the second factor is positive, so its zero set is the torus only);
- ellipsoid, semi-axes ``0.35, 0.25, 0.15``: ``|(x - c) / a| - 1`` (exact area by a
  spectrally converging double integral);
- quadric (on request): the sphere as ``|x - c|^2 - R^2``, interpolated exactly by P2 / Q2,
  so that only the rules err::

    python bench/cut3d.py --sizes 4 8 16 32

``--levelset function callable`` measures the degree-2 rows twice: with the level set's
nodal values only (what a P2/Q2 ``Function`` gives) and with the level set as a callable,
whose exact zero set Saye's rules then follow (roots on every line and the interface's
gradient from the callable; cells, boxes and axes from the interpolant), as
``CutMesh(..., exact_zero_set=True)`` does::

    python bench/cut3d.py --sizes 8 16 32 --kinds tet-P2 hex-Q2 --levelset function callable

``--lenses`` checks the Q2 hexahedra on the sphere's exact zero set cell by cell against
Gauss-Bonnet: whether a cell certified on one side by the interpolant holds a lens of the
sphere (which the rules would drop), and each cut cell's area::

    python bench/cut3d.py --sizes 8 16 32 --lenses --centres 8

``--order k`` sets the Gauss points per interval of Saye's rules (P2 tetrahedra and
hexahedra; default 4, as ``quadrature_degree = 6`` in ``CutMesh``). ``--min-depth 1``
splits every box of the P2 tetrahedra that the interface may cross before Saye's rules,
``--frame hexahedra`` runs them on the four hexahedra of each tetrahedron instead of on
truncated boxes of the tetrahedron itself
(:func:`~xfem_contact.quadrature.curved_tet_rules.p2_tet_cut_rules`), and
``--raise-tolerance T`` (``off``: none) sets the tetrahedron frame's raised orders (the
tolerance; on exact zero sets that of cells coarse against the surface, scaled by
``(2 h kappa)^3`` below ``h kappa = 1/2``,
:func:`~xfem_contact.quadrature.curved_tet_rules.raise_tolerances`). With
``--centres K`` each rate of the means gets a 95 % bootstrap interval over the centres.

The fuzz (``--fuzz N``) cuts ``N`` reference cells per kind by random spheres, ellipsoids,
tori and planes (a third of them moved to pass exactly through a node) and counts the
failures: a non-positive weight, side volumes missing the cell volume by more than 1e-12,
an interface area off the exact one (known for planes, clipped exactly, and for spheres on
their exact zero sets, by Gauss-Bonnet: ``checked``) by more than its tolerance
(:func:`area_tolerance`; ``worst``: the largest error over it), or an exception other than
the documented refusal of a singular zero set (counted apart); with ``--levelset
callable`` also those of the P2 / Q2 rules on the exact zero sets::

    python bench/cut3d.py --fuzz 10000 --sizes
"""

from __future__ import annotations

import argparse
import functools
import importlib.util
import itertools
import pathlib
import resource
import time

import basix
import numpy as np

from xfem_contact.geometry.cut_tets import classify_tets, cut_tets
from xfem_contact.quadrature import curved_tet_rules
from xfem_contact.quadrature.curved_tet_rules import classify_p2_tets, p2_tet_cut_rules
from xfem_contact.quadrature.cut_tet_rules import tet_interface_rule, tet_side_rules
from xfem_contact.quadrature.saye import classify_hexes, hex_cut_rules

R, CENTRE = 0.3, np.array([0.5, 0.5, 0.5])
TORUS = (0.3, 0.12)
AXES = np.array([0.35, 0.25, 0.15])


def _ellipsoid_area(a: float, b: float, c: float, m: int = 200) -> float:
    """Area of the ellipsoid with semi-axes ``a, b, c``: Gauss-Legendre in ``cos theta``
    (``m`` points) times the trapezoidal rule in ``phi`` (``2 m``), both spectrally
    convergent for this analytic, periodic integrand."""
    t, wt = np.polynomial.legendre.leggauss(m)
    phi = np.arange(2 * m) * np.pi / m
    T, P = np.meshgrid(t, phi, indexing="ij")
    s2 = 1.0 - T**2
    f = np.sqrt(
        (b * c) ** 2 * s2 * np.cos(P) ** 2 + (a * c) ** 2 * s2 * np.sin(P) ** 2 + (a * b * T) ** 2
    )
    return float(wt @ f.sum(axis=1) * np.pi / m)


def _sphere(x: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """The sphere's signed distance."""
    return np.linalg.norm(x - centre, axis=-1) - R


def _torus(x: np.ndarray, centre: np.ndarray) -> np.ndarray:
    big, small = TORUS
    y = x - centre
    rho2, z2 = y[..., 0] ** 2 + y[..., 1] ** 2, y[..., 2] ** 2
    return ((rho2 + z2 + big**2 - small**2) ** 2 - 4 * big**2 * rho2) / (4 * big**2)


def _ellipsoid(x: np.ndarray, centre: np.ndarray) -> np.ndarray:
    return np.linalg.norm((x - centre) / AXES, axis=-1) - 1.0


#: name -> (level set on points (..., 3) about a centre (3,), exact volume, exact area)
SHAPES = {
    "sphere": (_sphere, 4.0 / 3.0 * np.pi * R**3, 4.0 * np.pi * R**2),
    "torus": (_torus, 2 * np.pi**2 * TORUS[0] * TORUS[1] ** 2, 4 * np.pi**2 * TORUS[0] * TORUS[1]),
    "ellipsoid": (_ellipsoid, 4.0 / 3.0 * np.pi * AXES.prod(), _ellipsoid_area(*AXES)),
    # the sphere as |x - c|^2 - R^2: P2 and Q2 interpolate it exactly, so only the rules err
    "quadric": (
        lambda x, centre: ((x - centre) ** 2).sum(axis=-1) - R**2,
        4.0 / 3.0 * np.pi * R**3,
        4.0 * np.pi * R**2,
    ),
}


#: The six tetrahedra of the cube [0, 1]^3 around its diagonal (0, 0, 0) - (1, 1, 1).
KUHN = [
    [(0, 0, 0), (1, 0, 0), (1, 1, 0), (1, 1, 1)],
    [(0, 0, 0), (1, 0, 0), (1, 0, 1), (1, 1, 1)],
    [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 1, 1)],
    [(0, 0, 0), (0, 1, 0), (0, 1, 1), (1, 1, 1)],
    [(0, 0, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1)],
    [(0, 0, 0), (0, 0, 1), (0, 1, 1), (1, 1, 1)],
]


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


MIN_DEPTH = 0
"""Forced box splits of the P2 tetrahedra's rules (``--min-depth``)."""


ORDER = 4
"""Gauss points per interval of Saye's rules (``--order``)."""


FRAME = "tetrahedron"
"""Where the P2 tetrahedra's rules run Saye's algorithm (``--frame``)."""


RAISE_TOLERANCE = curved_tet_rules.RAISE_TOLERANCE
"""Rule-change tolerance of the P2 tetrahedra's boxes above which their order is doubled
(``--raise-tolerance``; ``None``: off)."""


CHUNK = 4096
"""Cut P2 tetrahedra per call of the rules: their volumes and areas are summed, so that
only one chunk's rules are held at a time."""


@functools.lru_cache(maxsize=1)
def tet_geometry(
    n: int, perturb: float, degree: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Vertices ``(6 n^3, 4, 3)``, Jacobians ``(6 n^3, 3, 3)``, ``|det J|`` and the nodes
    ``(6 n^3, 4 | 10, 3)`` of the P``degree`` level set of :func:`kuhn_mesh` (the last
    mesh is kept: several centres on one mesh build it once)."""
    vertices = kuhn_mesh(n, perturb)
    J = np.transpose(vertices[:, 1:] - vertices[:, :1], (0, 2, 1))
    detJ = np.abs(np.linalg.det(J))
    nodes = vertices
    if degree == 2:
        element = basix.create_element(
            basix.ElementFamily.P, basix.CellType.tetrahedron, 2, basix.LagrangeVariant.gll_warped
        )
        nodes = vertices[:, :1] + np.einsum("qk,ndk->nqd", element.points, J)
    for array in (vertices, J, detJ, nodes):
        array.flags.writeable = False
    return vertices, J, detJ, nodes


def sphere_tets(
    n: int, degree: int = 4, shape: str = "sphere", centre: np.ndarray = CENTRE
) -> tuple[float, float, int, float, int]:
    """Volume, area, cut-cell count, CPU seconds on ``6 n^3`` tetrahedra (P1 level set
    of ``shape`` about ``centre``) and the points of the cut cells' rules (both sides and
    the interface)."""
    _, J, detJ, nodes = tet_geometry(n, PERTURB, 1)
    phi = SHAPES[shape][0](nodes, centre)
    start = time.process_time()
    side = classify_tets(phi)
    cut = np.flatnonzero(side == 0)
    geometry = cut_tets(phi[cut])
    minus = tet_side_rules(geometry, -1, degree)
    gamma = tet_interface_rule(geometry, degree, lambda rows, X: J[cut[rows]])
    elapsed = time.process_time() - start
    volume = detJ[side == -1].sum() / 6.0 + (minus.weights * detJ[cut[minus.point_rows]]).sum()
    area = (gamma.weights * detJ[cut[gamma.point_rows]]).sum()
    plus = tet_side_rules(geometry, 1, degree)
    points = minus.weights.size + plus.weights.size + gamma.weights.size
    return volume, area, cut.size, elapsed, points


def sphere_p2_tets(
    n: int,
    order: int | None = None,
    shape: str = "sphere",
    callable_: bool = False,
    centre: np.ndarray = CENTRE,
) -> tuple[float, float, int, float, int]:
    """Volume, area, cut-cell count, CPU seconds on ``6 n^3`` tetrahedra (P2 level set
    of ``shape`` about ``centre``; with ``callable_`` following the level set's exact zero
    set, as ``CutMesh(..., exact_zero_set=True)`` does) and the points of the cut cells'
    rules."""
    vertices, J, detJ, nodes = tet_geometry(n, PERTURB, 2)
    phi = SHAPES[shape][0](nodes, centre)

    def on_cells(cells):
        """The level set at reference points of ``cells``, as ``(rows, X) -> (m,)``."""

        def exact(rows, X):
            x = vertices[cells[rows], 0] + np.einsum("mij,mj->mi", J[cells[rows]], X)
            return SHAPES[shape][0](x, centre)

        return exact

    start = time.process_time()
    side = classify_p2_tets(phi, on_cells(np.arange(phi.shape[0])) if callable_ else None)
    cut = np.flatnonzero(side == 0)
    volume = detJ[side == -1].sum() / 6.0
    area, points = 0.0, 0
    for first in range(0, cut.size, CHUNK):
        cells = cut[first : first + CHUNK]
        rules = p2_tet_cut_rules(
            phi[cells],
            order or ORDER,
            min_depth=MIN_DEPTH,
            frame=FRAME,
            raise_tolerance=RAISE_TOLERANCE,
            jacobian=lambda rows, X, cells=cells: J[cells[rows]],
            exact=on_cells(cells) if callable_ else None,
        )
        volume += (rules.minus.weights * detJ[cells[rules.minus.point_rows]]).sum()
        area += (rules.interface.weights * detJ[cells[rules.interface.point_rows]]).sum()
        points += sum(r.weights.size for r in (rules.minus, rules.plus, rules.interface))
    elapsed = time.process_time() - start
    return volume, area, cut.size, elapsed, points


def sphere_hexes(
    n: int,
    degree: int,
    order: int | None = None,
    shape: str = "sphere",
    callable_: bool = False,
    centre: np.ndarray = CENTRE,
) -> tuple[float, float, int, float, int]:
    """Volume, area, cut-cell count, CPU seconds on ``n^3`` hexahedra (Q``degree`` level
    set of ``shape`` about ``centre``; with ``callable_`` and degree 2, following the level
    set's exact zero set) and the points of the cut cells' rules."""
    h = 1.0 / n
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, degree, basix.LagrangeVariant.gll_warped
    )
    phi = SHAPES[shape][0](origins(n)[:, None] + h * element.points[None], centre)
    start = time.process_time()
    side = classify_hexes(phi, degree)
    cut = np.flatnonzero(side == 0)
    J = np.broadcast_to(h * np.eye(3), (cut.size, 3, 3))
    corners = origins(n)[cut]

    def exact(rows, X):
        return SHAPES[shape][0](corners[rows] + h * X, centre)

    rules = hex_cut_rules(
        phi[cut],
        degree,
        order or ORDER,
        jacobian=lambda rows, X: J[rows],
        exact=exact if callable_ and degree == 2 else None,
    )
    elapsed = time.process_time() - start
    volume = ((side == -1).sum() + rules.minus.weights.sum()) * h**3
    area = rules.interface.weights.sum() * h**3
    points = sum(r.weights.size for r in (rules.minus, rules.plus, rules.interface))
    return volume, area, cut.size, elapsed, points


def hex_lenses(n: int, centre: np.ndarray, order: int) -> tuple[int, float, float, float]:
    """The exact zero set of the sphere about ``centre`` on ``n^3`` Q2 hexahedra, cell by
    cell against Gauss-Bonnet: the cells certified on one side by the interpolant's
    Bernstein coefficients where the sphere has area (a lens that the rules never see),
    the share of the sphere's area in them, and over the cut cells the summed relative
    error and the largest error of a cell over its exact area."""
    h = 1.0 / n
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.hexahedron, 2, basix.LagrangeVariant.gll_warped
    )
    corners = origins(n)
    phi = _sphere(corners[:, None] + h * element.points[None], centre)
    side = classify_hexes(phi, 2)
    near = np.linalg.norm(corners + h / 2 - centre, axis=1) - R
    near = np.flatnonzero(np.abs(near) <= h * np.sqrt(3.0) / 2)  # the cells the sphere meets
    exact = np.zeros(corners.shape[0])
    exact[near] = [
        reference.sphere_area_in_polytope(centre, R, reference.box_planes(x, x + h))
        for x in corners[near]
    ]
    lens = np.flatnonzero((side != 0) & (exact > 0))
    cut = np.flatnonzero(side == 0)
    rules = hex_cut_rules(
        phi[cut], 2, order, exact=lambda rows, X: _sphere(corners[cut[rows]] + h * X, centre)
    )
    area = np.bincount(rules.interface.point_rows, rules.interface.weights, minlength=cut.size)
    error = area * h**2 - exact[cut]
    total = SHAPES["sphere"][2]
    worst = np.max(np.abs(error)[exact[cut] > 0] / exact[cut][exact[cut] > 0])
    return lens.size, exact[lens].sum() / total, error.sum() / total, worst


def random_level_set(rng: np.random.Generator):
    """A random sphere, ellipsoid, torus or plane around the reference cells: a callable
    on points ``(..., 3)`` and, for a sphere or a plane, ``(shape, centre, radius |
    normal)`` (the surface's area in a cell is then exact; else ``None``). Each level set
    is the signed distance (planes, spheres, tori) or a multiple of it near the surface
    (ellipsoids), so that ``f - s = 0`` is the sphere of radius ``R + s`` or the plane
    moved by ``s`` along its normal."""
    centre = rng.uniform(-0.5, 1.5, size=3)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shape = rng.choice(["sphere", "ellipsoid", "torus", "plane"])
    if shape == "plane":
        normal = Q[0]
        return (lambda x: (x - centre) @ normal), ("plane", centre, normal)
    if shape == "sphere":
        radius = rng.uniform(0.05, 1.5)
        surface = ("sphere", centre, radius)
        return (lambda x: np.linalg.norm(x - centre, axis=-1) - radius), surface
    if shape == "ellipsoid":
        axes = rng.uniform(0.1, 1.2, size=3)
        return (lambda x: np.linalg.norm(((x - centre) @ Q) / axes, axis=-1) - 1.0), None
    big, small = rng.uniform(0.3, 1.0), rng.uniform(0.05, 0.3)

    def torus(x):
        y = (x - centre) @ Q
        return np.hypot(np.hypot(y[..., 0], y[..., 1]) - big, y[..., 2]) - small

    return torus, None


_REFERENCE = importlib.util.spec_from_file_location(
    "cut3d_reference", pathlib.Path(__file__).resolve().parents[1] / "tests" / "cut3d_reference.py"
)
reference = importlib.util.module_from_spec(_REFERENCE)
_REFERENCE.loader.exec_module(reference)
"""The exact references of the tests (polytopes clipped by planes, Gauss-Bonnet)."""

REFERENCE_CELLS = {
    "tetrahedron": np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    "hexahedron": reference.box_vertices([0.0] * 3, [1.0] * 3),
}


def exact_area(cell: str, surface, shift: float, exact_zero_set: bool) -> float:
    """Area of the zero set of ``f - shift`` in the reference ``cell`` for ``surface =
    (shape, centre, radius | normal)`` of :func:`random_level_set`: for a plane (which
    every interpolant represents exactly), and for a sphere when the rules follow the exact
    zero set; else NaN (``None``; a sphere's interpolant, whose error in a cell that the
    sphere grazes is of the cell's size at any ``h``; a sphere moved through a node, where
    Gauss-Bonnet's corners meet)."""
    if surface is None or (surface[0] == "sphere" and (shift != 0 or not exact_zero_set)):
        return np.nan
    shape, centre, size = surface
    vertices = REFERENCE_CELLS[cell]
    if cell == "tetrahedron":
        planes, edges = reference.tet_planes(vertices), reference.TET_EDGES
    else:
        planes, edges = reference.box_planes([0.0] * 3, [1.0] * 3), reference.box_edges()
    if shape == "sphere":
        return reference.sphere_area_in_polytope(centre, size, planes)
    _, face = reference.clip(planes, vertices, edges, (size, -(centre @ size) - shift), 1)
    cross = np.cross(face[:, 1] - face[:, 0], face[:, 2] - face[:, 0])
    return float(np.linalg.norm(cross, axis=1).sum() / 2)


AREA_FLOOR = 1e-10
"""Area tolerance of the fuzz for planes (every rule is exact for them; reference units)."""


def area_tolerance(cell: str, surface) -> float:
    """Tolerance of a cell's interface area against :func:`exact_area`: ``AREA_FLOOR``
    for a plane, ``AREA_FLOOR + h^2 theta^3`` for a sphere (on its exact zero set), with
    ``theta = h / R`` (the cell's diameter ``h`` against the radius): the error of the
    cell's share of a surface whose relative error falls as ``h^3``, as the raised orders
    allow (``curved_tet_rules.RAISE_POWER``)."""
    if surface is None or surface[0] == "plane":
        return AREA_FLOOR
    h = np.sqrt(2.0) if cell == "tetrahedron" else np.sqrt(3.0)
    return AREA_FLOOR + h**2 * (h / surface[2]) ** curved_tet_rules.RAISE_POWER


def fuzz_cells(kind: str, count: int, seed: int = 0, callable_: bool = False) -> dict[str, float]:
    """Failures of the rules of ``count`` random cuts of one reference cell of ``kind``:
    ``{"cases", "cut", "weights", "volume", "area", "checked", "errors", "refused",
    "reduced", "worst"}`` (``area``: interface areas off the exact one by more than
    :func:`area_tolerance`, of the ``checked`` cases whose area is known,
    :func:`exact_area`; ``worst``: the largest error over its tolerance; ``unreferenced``:
    spheres whose Gauss-Bonnet area fell outside 0 .. the cell's boundary area, not
    checked); with
    ``callable_`` (P2 tetrahedra, Q2 hexahedra), of the rules on the exact zero sets."""
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
    functions, surfaces = zip(*(random_level_set(rng) for _ in range(count)), strict=True)
    phi = np.array([f(element.points) for f in functions])
    through = rng.random(count) < 1 / 3
    node = rng.integers(0, element.points.shape[0], size=count)
    shift = np.where(through, phi[np.arange(count), node], 0.0)
    phi[through] -= shift[through, None]  # zero at a node, exactly
    phi[through, node[through]] = 0.0
    exact_zero_set = callable_ and kind in ("tet-P2", "hex-Q2")
    exact_areas = np.array(
        [exact_area(cell[0], s, d, exact_zero_set) for s, d in zip(surfaces, shift, strict=True)]
    )
    tolerances = np.array([area_tolerance(cell[0], s) for s in surfaces])
    # a piece of a sphere in a convex cell is part of the boundary of a convex subset of
    # the cell, so its area is at most the cell's boundary area: beyond it (or below 0),
    # Gauss-Bonnet's pieces were not disks, and the case is not checked
    boundary = 1.5 + np.sqrt(3.0) / 2.0 if cell[0] == "tetrahedron" else 6.0
    unreferenced = (exact_areas < 0) | (exact_areas > boundary)
    exact_areas[unreferenced] = np.nan

    def exact_of(cells: np.ndarray):
        """The exact level sets of ``cells`` as a function of ``(rows, X)``."""

        def exact(rows, X):
            values = np.empty(rows.size)
            for row in np.unique(rows):
                at = rows == row
                values[at] = functions[cells[row]](X[at]) - shift[cells[row]]
            return values

        return exact if callable_ and kind in ("tet-P2", "hex-Q2") else None

    volume = 1.0 / 6.0 if cell[0] == "tetrahedron" else 1.0
    names = ("cases", "cut", "weights", "volume", "area", "checked", "errors", "refused", "reduced")
    counts = dict.fromkeys(names, 0)
    counts["cases"], counts["worst"] = count, 0.0
    counts["unreferenced"] = int(unreferenced.sum())
    batch = 500
    for start in range(0, count, batch):
        rows = np.arange(start, min(start + batch, count))
        try:
            areas = (exact_areas[rows], tolerances[rows])
            _check_batch(kind, phi[rows], volume, counts, areas, exact_of(rows))
        except Exception:  # noqa: BLE001 - find the failing cells one by one
            for row in rows:
                one = rows[row - start : row - start + 1]
                try:
                    areas = (exact_areas[one], tolerances[one])
                    _check_batch(kind, phi[one], volume, counts, areas, exact_of(one))
                except ValueError as error:
                    counts["refused" if "singular point" in str(error) else "errors"] += 1
                except Exception:  # noqa: BLE001 - a fuzz counts every failure
                    counts["errors"] += 1
    return counts


def _check_batch(
    kind: str,
    phi: np.ndarray,
    volume: float,
    counts: dict[str, float],
    areas: tuple[np.ndarray, np.ndarray],
    exact=None,
) -> None:
    """Rules of cells ``phi`` (following ``exact`` if given); adds their failures to
    ``counts`` (raises before adding); ``areas``: the exact interface area of each cell
    (NaN: unknown, not checked) and its tolerance."""
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
        if kind == "tet-P2":
            found = p2_tet_cut_rules(phi, exact=exact)
        else:
            found = hex_cut_rules(phi, int(kind[-1]), exact=exact)
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
    interface = np.bincount(rules[2].point_rows, rules[2].weights, minlength=n)
    expected, tolerance = areas
    checked = ~np.isnan(expected)
    counts["checked"] += int(checked.sum())
    counts["area"] += int((np.abs(interface - expected)[checked] > tolerance[checked]).sum())
    ratio = np.abs(interface - expected)[checked] / tolerance[checked]
    counts["worst"] = max(counts["worst"], float(ratio.max(initial=0.0)))


def shifted_centres(n: int, count: int, seed: int = 0) -> np.ndarray:
    """Centres ``(max(count, 1), 3)`` of the surfaces on a mesh of size ``h = 1 / n``: the
    cube's centre if ``count == 0``, else the cube's centre shifted by ``h u`` with
    ``count`` vectors ``u`` uniform in ``[0, 1)^3`` (seeded, the same ``u`` for every
    ``n``)."""
    if count == 0:
        return CENTRE[None]
    u = np.random.default_rng(seed).uniform(0.0, 1.0, size=(count, 3))
    return CENTRE + u / n


def _previous(sizes: list[int], n: int) -> int | None:
    at = sizes.index(n)
    return sizes[at - 1] if at else None


def _print_errors(shape: str, n: int, rows: list, previous: dict | None) -> dict:
    """Print the row of size ``n`` from the ``(volume, area, cut cells, cpu s, points)`` of
    each centre: the relative errors (their mean and largest magnitude over several centres)
    and the rates of the means against ``previous``; returns this row's errors."""
    _, exact_volume, exact_area = SHAPES[shape]
    volume, area, ncut, elapsed, points = (np.array(c) for c in zip(*rows, strict=True))
    row = {
        "n": n,
        "volume": (volume - exact_volume) / exact_volume,
        "area": (area - exact_area) / exact_area,
    }
    several = volume.size > 1
    if previous is None:
        header = f"{'n':>5} {'cut cells':>10}"
        for name in ("volume", "area"):
            header += f" {name + (' mean' if several else ' err'):>11}"
            header += f" {'max':>9} {'rate':>5}" if several else f" {'rate':>5}"
        print(header + f" {'cpu s':>7} {'points':>9}")
    line = f"{n:5d} {int(ncut.mean()):10d}"
    for name in ("volume", "area"):
        mean = np.abs(row[name]).mean()
        rate = ""
        if previous is not None:
            before = np.abs(previous[name]).mean()
            rate = f"{np.log(before / mean) / np.log(n / previous['n']):5.2f}"
        line += f" {mean:11.3e}"
        line += f" {np.abs(row[name]).max():9.2e} {rate:>5}" if several else f" {rate:>5}"
    print(line + f" {elapsed.mean():7.2f} {int(points.mean()):9d}", flush=True)
    return row


def _print_signed(errors: dict[int, dict]) -> None:
    """Print the signed relative errors of each size, one column per centre."""
    print("signed relative errors, one per centre:")
    for name in ("volume", "area"):
        for n, row in errors.items():
            print(f"{n:5d} {name:>6} " + " ".join(f"{e:+9.2e}" for e in row[name]))


BOOTSTRAP = 10000
"""Resamples of the centres for the rates' confidence intervals."""


def _print_rate_intervals(errors: dict[int, dict]) -> None:
    """Print, for each pair of consecutive sizes, the rate of the mean ``|relative error|``
    with a 95 % bootstrap interval: the centres (the same ``u`` at every size) resampled
    with replacement :data:`BOOTSTRAP` times, seeded."""
    sizes = list(errors)
    count = np.asarray(errors[sizes[0]]["volume"]).size
    if count < 2 or len(sizes) < 2:
        return
    draw = np.random.default_rng(1).integers(0, count, size=(BOOTSTRAP, count))
    print(f"rates of the means, 95 % bootstrap interval over the {count} centres:")
    for before, n in itertools.pairwise(sizes):
        line = f"{before:5d} -> {n:<5d}"
        for name in ("volume", "area"):
            a, b = np.abs(errors[before][name]), np.abs(errors[n][name])
            rate = np.log(a.mean() / b.mean()) / np.log(n / before)
            resampled = np.log(a[draw].mean(axis=1) / b[draw].mean(axis=1)) / np.log(n / before)
            low, high = np.percentile(resampled, [2.5, 97.5])
            line += f" {name} {rate:5.2f} [{low:5.2f}, {high:5.2f}]"
        print(line)


def _print_fitted_rates(errors: dict[int, dict]) -> None:
    """Print the least-squares slopes of ``log`` (mean relative error) against ``log n``
    over all sizes (three or more)."""
    if len(errors) < 3:
        return
    sizes = np.array(list(errors))
    line = f"least-squares rate over n = {', '.join(map(str, sizes))}:"
    for name in ("volume", "area"):
        means = [np.abs(row[name]).mean() for row in errors.values()]
        line += f" {name} {-np.polyfit(np.log(sizes), np.log(means), 1)[0]:.2f}"
    print(line)


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
    parser.add_argument(
        "--shapes",
        nargs="+",
        default=["sphere", "torus", "ellipsoid"],
        choices=list(SHAPES),
        help="surfaces to measure",
    )
    parser.add_argument(
        "--min-depth",
        type=int,
        default=0,
        help="forced box splits of the P2 tetrahedra's rules (p2_tet_cut_rules min_depth)",
    )
    parser.add_argument(
        "--levelset",
        nargs="+",
        default=["function"],
        choices=["function", "callable"],
        help="the degree-2 level set as its interpolant's nodal values (a P2/Q2 Function) "
        "and/or as a callable (rules on its exact zero set); degree 1 cuts the interpolant",
    )
    parser.add_argument(
        "--order",
        type=int,
        default=4,
        help="Gauss points per interval of Saye's rules (P2 tetrahedra, hexahedra)",
    )
    parser.add_argument(
        "--frame",
        default="tetrahedron",
        choices=["tetrahedron", "hexahedra"],
        help="P2 tetrahedra: Saye's rules on truncated boxes of the tetrahedron or on its "
        "four hexahedra (p2_tet_cut_rules frame)",
    )
    parser.add_argument(
        "--centres",
        type=int,
        default=0,
        metavar="K",
        help="average the errors over K centres shifted by up to h per coordinate "
        "(seeded; 0: the cube's centre only)",
    )
    parser.add_argument(
        "--raise-tolerance",
        type=lambda text: None if text == "off" else float(text),
        default=curved_tet_rules.RAISE_TOLERANCE,
        metavar="T",
        help="P2 tetrahedra (tetrahedron frame): boxes whose rules move by more than T "
        "(on exact zero sets: times (2 h kappa)^3 where h kappa < 1/2) between order - 1 and "
        "order get 2 order "
        "points ('off': never; p2_tet_cut_rules "
        f"raise_tolerance, default {curved_tet_rules.RAISE_TOLERANCE:g})",
    )
    parser.add_argument(
        "--lenses",
        action="store_true",
        help="Q2 hexahedra, exact zero set of the sphere: per size and centre, the cells "
        "certified by the interpolant where the sphere has area, and the cut cells' areas "
        "against Gauss-Bonnet (instead of the volume and area rows)",
    )
    args = parser.parse_args()
    if args.centres < 0:
        parser.error(f"--centres must be >= 0, got {args.centres}")
    global PERTURB, MIN_DEPTH, ORDER, FRAME, RAISE_TOLERANCE
    PERTURB, MIN_DEPTH, ORDER, FRAME = args.perturb, args.min_depth, args.order, args.frame
    RAISE_TOLERANCE = args.raise_tolerance
    for kind, levelset in itertools.product(args.kinds if args.fuzz else [], args.levelset):
        if levelset == "callable" and kind in ("tet-P1", "hex-Q1"):
            continue
        start = time.perf_counter()
        counts = fuzz_cells(kind, args.fuzz, callable_=levelset == "callable")
        failures = counts["weights"] + counts["volume"] + counts["area"] + counts["errors"]
        label = f" ({levelset})" if kind in ("tet-P2", "hex-Q2") else ""
        print(
            f"fuzz {kind}{label}: {counts} -> {failures} failure(s) "
            f"({time.perf_counter() - start:.1f} s)"
        )
    runs = {
        "tet-P1": lambda n, shape, c, centre: sphere_tets(n, shape=shape, centre=centre),
        "tet-P2": lambda n, shape, c, centre: sphere_p2_tets(
            n, shape=shape, callable_=c, centre=centre
        ),
        "hex-Q1": lambda n, shape, c, centre: sphere_hexes(n, 1, shape=shape, centre=centre),
        "hex-Q2": lambda n, shape, c, centre: sphere_hexes(
            n, 2, shape=shape, callable_=c, centre=centre
        ),
    }
    if args.lenses:
        print("\nhex-Q2: sphere (callable), cell by cell against Gauss-Bonnet")
        print(f"{'n':>5} {'centre':>6} {'lenses':>6} {'lens area':>9} {'sum err':>9} {'worst':>8}")
        for n in args.sizes:
            for k, centre in enumerate(shifted_centres(n, args.centres)):
                lenses, share, total, worst = hex_lenses(n, centre, args.order)
                print(f"{n:5d} {k:6d} {lenses:6d} {share:9.2e} {total:+9.2e} {worst:8.2e}")
        args.sizes = []
    cases = itertools.product(args.shapes, args.kinds if args.sizes else [], args.levelset)
    for shape, kind, levelset in cases:
        if levelset == "callable" and kind in ("tet-P1", "hex-Q1"):
            continue  # degree 1: the interpolant's cut either way
        label = f" ({levelset})" if kind in ("tet-P2", "hex-Q2") else ""
        if args.centres:
            label += f", {args.centres} centres"
        print(f"\n{kind}: {shape}{label}")
        errors = {}
        for n in args.sizes:
            rows = [
                runs[kind](n, shape, levelset == "callable", centre)
                for centre in shifted_centres(n, args.centres)
            ]
            errors[n] = _print_errors(shape, n, rows, errors.get(_previous(args.sizes, n)))
        if args.centres:
            _print_signed(errors)
            _print_rate_intervals(errors)
            _print_fitted_rates(errors)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"\npeak memory {peak:.0f} MB")


if __name__ == "__main__":
    main()
