"""Independent exact references for 3D cut rules: convex polytopes clipped by planes
(vertices enumerated, faces triangulated by angle, cones from the centroid), and closed-form
monomial integrals over simplices (expansion in barycentric coordinates). Shares no code with
the cutters it checks."""

import functools
import itertools
import math

import numpy as np


def exponents(max_degree: int) -> list[tuple[int, int, int]]:
    """``(a, b, c)`` with ``a + b + c <= max_degree``."""
    return [
        (a, b, c)
        for a in range(max_degree + 1)
        for b in range(max_degree + 1 - a)
        for c in range(max_degree + 1 - a - b)
    ]


def simplex_moments(simplices: np.ndarray, exps) -> np.ndarray:
    """``sum over simplices of int x^a y^b z^c``: tetrahedra ``(m, 4, 3)`` (volume) or
    triangles ``(m, 3, 3)`` (area), by int lambda^k = |S| k! d! / (|k| + d)!."""
    simplices = np.asarray(simplices, dtype=np.float64).reshape(-1, *np.shape(simplices)[-2:])
    nv = simplices.shape[1]
    dim = nv - 1
    if dim == 3:
        size = np.abs(np.linalg.det(simplices[:, 1:] - simplices[:, :1])) / 6.0
    else:
        size = (
            np.linalg.norm(
                np.cross(simplices[:, 1] - simplices[:, 0], simplices[:, 2] - simplices[:, 0]),
                axis=1,
            )
            / 2.0
        )
    out = []
    for a, b, c in exps:
        dirs = [0] * a + [1] * b + [2] * c
        n = len(dirs)
        choice, factor = _expansion(nv, n)
        term = np.broadcast_to(factor, (simplices.shape[0], factor.size)).copy()
        for f, d in enumerate(dirs):
            term *= simplices[:, choice[:, f], d]
        total = term.sum(axis=1)
        out.append((size * total * math.factorial(dim) / math.factorial(n + dim)).sum())
    return np.array(out)


@functools.cache
def _expansion(nv: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Every choice of a vertex per linear factor, ``(nv^n, n)``, and prod(counts!)."""
    choice = np.array(list(itertools.product(range(nv), repeat=n)), dtype=int)
    choice = choice.reshape(nv**n, n)
    factor = np.array(
        [math.prod(math.factorial(int(k)) for k in np.bincount(c, minlength=nv)) for c in choice],
        dtype=float,
    )
    return choice, factor


def _polygon(points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Triangles ``(k, 3, 3)`` fanning a convex polygon given by unordered ``points``."""
    centre = points.mean(axis=0)
    u = points[0] - centre
    if np.linalg.norm(u) == 0:
        u = points[1] - centre
    u = u / np.linalg.norm(u)
    v = np.cross(normal / np.linalg.norm(normal), u)
    angle = np.arctan2((points - centre) @ v, (points - centre) @ u)
    ring = points[np.argsort(angle)]
    return np.array([[ring[0], ring[i], ring[i + 1]] for i in range(1, len(ring) - 1)])


def _unique(points: np.ndarray, tol: float) -> np.ndarray:
    kept = []
    for p in points:
        if all(np.linalg.norm(p - q) > tol for q in kept):
            kept.append(p)
    return np.array(kept)


def clip(
    planes: list[tuple[np.ndarray, float]],
    vertices: np.ndarray,
    edges,
    cut: tuple,
    side: int,
    tol: float = 1e-12,
):
    """A convex polytope ``{x : g.x + c0 <= 0 for (g, c0) in planes}`` with ``vertices``
    and ``edges`` (vertex pairs), intersected with side ``side`` of ``cut = (n, c)``,
    ``side * (n.x + c) >= 0``.

    Returns:
        ``(tets, cut_face)``: tetrahedra ``(m, 4, 3)`` filling it (empty if it has no
        volume) and the triangles ``(k, 3, 3)`` of its face on the cut plane (empty if none).
    """
    n, c = cut
    value = -side * (vertices @ n + c)
    pts = list(vertices[value <= 0])
    for i, j in edges:
        if value[i] * value[j] < 0:
            t = value[i] / (value[i] - value[j])
            pts.append(vertices[i] + t * (vertices[j] - vertices[i]))
    scale = max(1.0, np.abs(vertices).max())
    if len(pts) < 4:
        return np.zeros((0, 4, 3)), np.zeros((0, 3, 3))
    pts = _unique(np.array(pts), tol * scale)
    centre = pts.mean(axis=0)
    tets, face, seen = [], np.zeros((0, 3, 3)), set()
    for k, (g, c0) in enumerate(planes + [(-side * n, -side * c)]):
        on = np.abs(pts @ g + c0) <= tol * scale * max(1.0, np.linalg.norm(g))
        key = tuple(np.flatnonzero(on))
        if on.sum() < 3:
            continue
        if key in seen:  # the cut plane on a facet: a face, not a second cone
            face = _polygon(pts[on], g)
            continue
        seen.add(key)
        tri = _polygon(pts[on], g)
        area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        tri = tri[area > tol]
        if tri.size == 0:
            continue
        tets.append(np.concatenate([np.broadcast_to(centre, (len(tri), 1, 3)), tri], axis=1))
        if k == len(planes):
            face = tri
    if not tets:
        return np.zeros((0, 4, 3)), np.zeros((0, 3, 3))
    tets = np.concatenate(tets)
    vol = np.abs(np.linalg.det(tets[:, 1:] - tets[:, :1]))
    if vol.sum() <= tol:
        return np.zeros((0, 4, 3)), np.zeros((0, 3, 3))
    return tets[vol > 0], face


def tet_planes(vertices: np.ndarray) -> list[tuple[np.ndarray, float]]:
    """Facets ``g.x + c0 <= 0`` of a tetrahedron ``(4, 3)``."""
    planes = []
    for i in range(4):
        face = np.delete(vertices, i, axis=0)
        g = np.cross(face[1] - face[0], face[2] - face[0])
        c0 = -g @ face[0]
        if g @ vertices[i] + c0 > 0:
            g, c0 = -g, -c0
        planes.append((g, c0))
    return planes


def box_planes(lo, hi) -> list[tuple[np.ndarray, float]]:
    """Facets of the box ``[lo, hi]`` (3 coordinates each)."""
    planes = []
    for d in range(3):
        e = np.eye(3)[d]
        planes += [(-e, lo[d]), (e, -hi[d])]
    return planes


TET_EDGES = list(itertools.combinations(range(4), 2))


def box_edges() -> list[tuple[int, int]]:
    """Edges of :func:`box_vertices`: pairs differing in one coordinate."""
    bits = list(itertools.product((0, 1), repeat=3))
    return [
        (i, j)
        for i, j in itertools.combinations(range(8), 2)
        if sum(a != b for a, b in zip(bits[i], bits[j], strict=True)) == 1
    ]


def box_vertices(lo, hi) -> np.ndarray:
    return np.array(
        [
            [(lo, hi)[b][d] for d, b in enumerate(bits)]
            for bits in itertools.product((0, 1), repeat=3)
        ],
        dtype=float,
    )


def sphere_area_in_polytope(
    centre: np.ndarray, radius: float, planes: list[tuple[np.ndarray, float]]
) -> float:
    """Area of the sphere inside the convex polytope ``g.x + c0 <= 0`` (``planes``), by
    Gauss-Bonnet on the unit sphere, for pieces that are disks bounded by arcs of the
    circles where the planes meet the sphere: ``R^2 (2 pi L + sum_i t_i dpsi_i - sum_v
    theta_v)``, where ``L`` is the number of boundary loops (pieces), a boundary arc on
    the circle ``n_i.u = t_i`` turns by ``dpsi_i`` about ``n_i`` (its geodesic curvature
    integrates to ``-t_i dpsi_i``) and ``theta_v`` are the exterior angles at the
    corners."""
    normals, levels = [], []
    for g, c0 in planes:  # n.u <= t for unit vectors u = (x - centre) / R
        norm = np.linalg.norm(g)
        normals.append(g / norm)
        levels.append(-(c0 + g @ centre) / (norm * radius))
    normals, levels = np.array(normals), np.array(levels)
    if (levels <= -1.0).any():
        return 0.0
    if (levels >= 1.0).all():
        return 4.0 * math.pi * radius**2

    def inside(u, skip=()):
        keep = [i for i in range(len(levels)) if i not in skip]
        return bool((normals[keep] @ u <= levels[keep] + 1e-12).all())

    corners = []  # (u, i, j): on circles i and j
    for i, j in itertools.combinations(range(len(levels)), 2):
        line = np.cross(normals[i], normals[j])
        if line @ line < 1e-24:  # parallel planes
            continue
        A = np.array([normals[i], normals[j], line])
        p = np.linalg.solve(A, [levels[i], levels[j], 0.0])
        s2 = (1.0 - p @ p) / (line @ line)
        if s2 <= 0:
            continue
        for s in (math.sqrt(s2), -math.sqrt(s2)):
            u = p + s * line
            if inside(u, (i, j)):
                corners.append((u, i, j))
    parent = list(range(len(corners)))  # corners joined by arcs: one set per loop

    def root(k):
        while parent[k] != k:
            k = parent[k]
        return k

    area, loops = 0.0, 0
    for i, (n, t) in enumerate(zip(normals, levels, strict=True)):
        if abs(t) >= 1.0:
            continue
        e1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        on = sorted(
            (math.atan2(u @ e2, u @ e1), k) for k, (u, a, b) in enumerate(corners) if i in (a, b)
        )
        if not on:
            on = [(0.0, None)]
        ends = [*on, (on[0][0] + 2.0 * math.pi, on[0][1])]
        for (a, ka), (b, kb) in itertools.pairwise(ends):
            mid = 0.5 * (a + b)
            u = t * n + math.sqrt(1.0 - t * t) * (math.cos(mid) * e1 + math.sin(mid) * e2)
            if inside(u, (i,)) and b > a:
                area += t * (b - a)
                if ka is None:  # a whole circle: a loop of its own
                    loops += 1
                else:
                    parent[root(ka)] = root(kb)
    loops += len({root(k) for k in range(len(corners))})
    area += 2.0 * math.pi * loops
    for u, i, j in corners:  # exterior angle: between the inward normals in the tangent plane
        m = [-(normals[k] - (normals[k] @ u) * u) for k in (i, j)]
        m = [v / np.linalg.norm(v) for v in m]
        area -= math.acos(float(np.clip(m[0] @ m[1], -1.0, 1.0)))
    return radius**2 * area


def torus_area_in_polytope(
    centre: np.ndarray,
    radii: tuple[float, float],
    planes: list[tuple[np.ndarray, float]],
    count: int = 200000,
) -> float:
    """Area of the torus about the z axis through ``centre`` (``radii = (R, r)``) inside the
    convex polytope ``g.x + c0 <= 0`` (``planes``). In the parametrisation ``x = centre +
    ((R + r cos u) cos v, (R + r cos u) sin v, r sin u)``, ``dA = r (R + r cos u) du dv`` does
    not depend on ``v`` and each facet keeps an arc of ``v`` in closed form
    (``A cos v + B sin v + C <= 0``), so the inner integral is exact; the outer one is the
    midpoint rule on ``count`` intervals of the ``u`` where the arcs are not empty (found
    on ``count`` intervals of the circle)."""
    step = 2 * np.pi / count
    u = (np.arange(count) + 0.5) * step
    held = np.flatnonzero(_torus_arcs(centre, radii, planes, u) > 0)
    if held.size == 0:
        return 0.0
    if held[0] == 0 or held[-1] == count - 1:
        raise ValueError("the polytope's piece of the torus wraps around u = 0")
    lo, hi = u[held[0]] - step, u[held[-1]] + step
    step = (hi - lo) / count
    u = lo + (np.arange(count) + 0.5) * step
    return float(_torus_arcs(centre, radii, planes, u).sum() * step)


def _torus_arcs(centre, radii, planes, u: np.ndarray) -> np.ndarray:
    """``r (R + r cos u)`` times the length of the arc of ``v`` inside the polytope, at each
    ``u``."""
    big, small = radii
    rho = big + small * np.cos(u)
    ends, conditions = [np.zeros_like(u), np.full_like(u, 2 * np.pi)], []
    for g, c0 in planes:
        A, B = g[0] * rho, g[1] * rho
        C = g[2] * small * np.sin(u) + g @ centre + c0
        M, alpha = np.hypot(A, B), np.arctan2(B, A)
        with np.errstate(divide="ignore", invalid="ignore"):
            beta = np.arccos(np.clip(-C / M, -1.0, 1.0))  # cos(v - alpha) <= -C / M
        ends += [np.mod(alpha + beta, 2 * np.pi), np.mod(alpha - beta, 2 * np.pi)]
        conditions.append((A, B, C))
    ends = np.sort(np.stack(ends, axis=1), axis=1)
    middle = 0.5 * (ends[:, 1:] + ends[:, :-1])
    inside = np.ones(middle.shape, dtype=bool)
    for A, B, C in conditions:
        inside &= A[:, None] * np.cos(middle) + B[:, None] * np.sin(middle) + C[:, None] <= 0
    return small * rho * (np.diff(ends, axis=1) * inside).sum(axis=1)
