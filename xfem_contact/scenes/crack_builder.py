"""Build the cracks of a scene: their level sets on the mesh, their cut, and the rings of K.

A ``segment``, ``polyline`` or ``arc`` is a :class:`~xfem_contact.geometry.crack_paths.
CrackPath`; each of its ends is a tip when it lies inside the body (and a point just
beyond it too), else the crack's mouth on an edge: the crack then runs on beyond that
end, out of the body (:meth:`~xfem_contact.geometry.crack_paths.CrackPath.levelsets`).
``phi``/``psi`` expressions are taken as given. Bad input is a
:class:`~xfem_contact.scenes.schema.SceneError` naming the crack's key.
"""

from __future__ import annotations

import math
import re

import dolfinx.geometry
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.fem.tip_scale import tip_lengths
from xfem_contact.geometry.crack_paths import CrackPath, arc, polyline
from xfem_contact.mechanics.composition import crack_law
from xfem_contact.mechanics.fracture import tip_cell_size
from xfem_contact.mechanics.laws import make_law
from xfem_contact.scenes.expressions import numpy_field
from xfem_contact.scenes.schema import CRACK_RINGS, CrackSpec, Scene, SceneError

#: A point this far beyond an end (a fraction of the mesh's diameter) must lie in the
#: body too for the end to be a tip
BEYOND = 1e-6


def crack_path(spec: CrackSpec) -> CrackPath | None:
    """The curve of a ``segment``, ``polyline`` or ``arc`` crack; None for expressions."""
    p = spec.params
    if spec.shape in ("segment", "polyline"):
        return polyline(p["points"])
    if spec.shape == "arc":
        return arc(p["centre"], float(p["radius"]), [math.radians(a) for a in p["angles_deg"]])
    return None


def _extent(mesh: dolfinx.mesh.Mesh) -> float:
    """The diagonal of the mesh's bounding box (m). Collective."""
    x = mesh.geometry.x[:, :2]
    local = np.r_[-x.min(axis=0), x.max(axis=0)] if x.size else np.full(4, -np.inf)
    bounds = np.empty(4)
    mesh.comm.Allreduce(local, bounds, op=MPI.MAX)  # -xmin, -ymin, xmax, ymax
    return float(np.linalg.norm(bounds[2:] + bounds[:2]))


def inside(mesh: dolfinx.mesh.Mesh, points: np.ndarray) -> np.ndarray:
    """Whether each point ``(k, 2)`` lies in a cell of the mesh (closures). Collective."""
    tree = dolfinx.geometry.bb_tree(mesh, mesh.topology.dim)
    x = np.c_[points, np.zeros(len(points))]
    candidates = dolfinx.geometry.compute_collisions_points(tree, x)
    cells = dolfinx.geometry.compute_colliding_cells(mesh, candidates, x)
    local = np.array([len(cells.links(i)) > 0 for i in range(len(points))], dtype=np.int32)
    found = np.empty_like(local)
    mesh.comm.Allreduce(local, found, op=MPI.MAX)
    return found.astype(bool)


def crack_levelsets(spec: CrackSpec, mesh: dolfinx.mesh.Mesh, where: str) -> tuple:
    """``(phi, psi)`` of a scene crack on ``mesh`` (callables of ``x``). Collective.

    Raises:
        SceneError: no end of a curve inside the body (naming the shape's key).
    """
    path = crack_path(spec)
    if path is None:
        return (
            numpy_field(spec.params["phi"], f"{where}.phi"),
            numpy_field(spec.params["psi"], f"{where}.psi"),
        )
    size = _extent(mesh)
    beyond = path.ends + BEYOND * size * path.tangents
    tips = inside(mesh, path.ends) & inside(mesh, beyond)
    if not tips.any():
        key = "points" if spec.shape != "arc" else "angles_deg"
        raise SceneError(
            f"{where}.{key}",
            "no end of the crack lies inside the body: a crack needs a tip in the mesh "
            "(an edge crack: one end inside, the other on or beyond the boundary)",
        )
    room = math.inf if spec.shape != "arc" else 0.99 * (2 * math.pi * path.radius - path.length)
    return path.levelsets([0.0 if tip else min(size, room) for tip in tips])


def crack_cut(scene: Scene, mesh: dolfinx.mesh.Mesh, interfaces: dict | None = None) -> tuple:
    """``(cut, laws, materials, options)`` of a scene's cracks (one body: the first
    crack's material, tip radius) and closed ``interfaces`` (their level sets by name,
    in the body's material outside) for :class:`~xfem_contact.mechanics.problem.Problem`.
    Collective."""
    phis, psis, laws = {}, {}, {}
    for k, spec in enumerate(scene.cracks):
        phis[spec.name], psis[spec.name] = crack_levelsets(spec, mesh, f"cracks[{k}]")
        laws[spec.name] = crack_law(
            spec.law, friction=spec.friction, augmentation=spec.augmentation, lbb=spec.lbb
        )
    body = scene.materials[scene.cracks[0].material]
    inside = {name: body for name in phis}
    for spec in scene.interfaces:  # psi None: a closed interface among the cracks
        phis[spec.name], psis[spec.name] = (interfaces or {})[spec.name], None
        options = {"friction": spec.friction, "augmentation": spec.augmentation}
        options["multiplier_degree"] = spec.multiplier_degree
        laws[spec.name] = make_law(spec.law, lbb=spec.lbb, **options)
        inside[spec.name] = scene.materials[spec.inside]
    several = len(phis) > 1
    try:
        cut = CutMesh(
            mesh,
            phis,
            degree=scene.levelset_degree,
            quadrature_degree=scene.quadrature_degree,
            tangent=psis if several else psis[scene.cracks[0].name],
        )
    except ValueError as error:
        message = re.sub(r"^(levelset|tangent)(\[[^]]*\])?: ", "", " ".join(str(error).split()))
        raise SceneError(crack_key(scene, str(error)), message) from None
    # no ghost penalty: its derivatives of the branch functions make the forms very costly
    tip_radius = scene.cracks[0].tip_radius
    options = {"tip_radius": "auto" if tip_radius is None else tip_radius, "ghost_penalty": 0.0}
    materials = body if not scene.interfaces else {-1: inside, 1: body}
    return cut, laws, materials, options


def crack_key(scene: Scene, message: str) -> str:
    """The key of the crack an error names (``cracks 'a' and 'b'``: the second's, or
    ``levelset['a']``, ``tangent['a']``), else ``cracks[0]`` (``cracks`` for several)."""
    names = [spec.name for spec in scene.cracks]
    if scene.interfaces:
        names += [spec.name for spec in scene.interfaces]
    named = re.findall(r"(?:cracks '[^']*' and |\[|crack )'([^']*)'", message)
    if named and named[0] in names:
        k = names.index(named[0])
        n = len(scene.cracks)
        return f"cracks[{k}]" if k < n else f"interfaces[{k - n}]"
    return "cracks[0]" if len(names) == 1 else "cracks"


def problem_error(error: ValueError) -> SceneError:
    """A ValueError of building a cracked problem as a SceneError naming the key:
    ``cracks[0].tip_radius`` for the enrichment radius, else ``cracks[0]``."""
    message = " ".join(str(error).split())
    key = "cracks[0].tip_radius" if message.startswith("tip_radius") else "cracks[0]"
    return SceneError(key, message)


def _boundary_distance(mesh: dolfinx.mesh.Mesh, point: np.ndarray) -> float:
    """The distance (m) from ``point`` (2,) to the mesh boundary (its facets' chords).
    Collective."""
    fdim = mesh.topology.dim - 1
    mesh.topology.create_connectivity(fdim, mesh.topology.dim)
    mesh.topology.create_connectivity(fdim, 0)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    local = math.inf
    if facets.size:
        vertices = mesh.topology.connectivity(fdim, 0).array.reshape(-1, 2)[facets]
        nodes = dolfinx.mesh.entities_to_geometry(mesh, 0, vertices.ravel())[:, 0]
        a, b = (mesh.geometry.x[nodes, :2].reshape(-1, 2, 2)[:, i] for i in (0, 1))
        t = np.clip(np.sum((point - a) * (b - a), axis=1) / np.sum((b - a) ** 2, axis=1), 0, 1)
        local = float(np.linalg.norm(a + t[:, None] * (b - a) - point, axis=1).min())
    return mesh.comm.allreduce(local, op=MPI.MIN)


def default_rings(problem) -> list[tuple[float, float]]:
    """The rings of K (m) for every tip: :data:`CRACK_RINGS` in units of the shortest
    tip's crack length (:func:`~xfem_contact.fem.tip_scale.tip_lengths`, not of the
    mesh), ``r_inf`` at least the largest tip cell size ``h``, ``r_sup`` kept within
    90 % of the distance from every tip to the boundary and to the other tips; a ring
    left narrower than ``h / 2`` is dropped. Collective.

    Raises:
        SceneError: a tip too close to the boundary or another tip for any ring.
    """
    mesh, tips = problem.mesh, problem.cut.crack.tips
    h = max(tip_cell_size(mesh, tip) for tip in tips)
    length = float(tip_lengths(problem.cut).min())
    room = min(_boundary_distance(mesh, np.asarray(tip)) for tip in tips)
    if len(tips) > 1:
        gaps = np.linalg.norm(tips[:, None] - tips[None], axis=2)
        room = min(room, float(gaps[~np.eye(len(tips), dtype=bool)].min()))
    if problem.cut.crack.union is not None:  # and to the other cracks
        room = min(room, problem.cut.crack.union.gap)
    rings = [(max(a * length, h), min(b * length, 0.9 * room)) for a, b in CRACK_RINGS]
    rings = [(r_inf, r_sup) for r_inf, r_sup in rings if r_sup - r_inf >= 0.5 * h]
    if not rings:
        raise SceneError(
            "cracks[0].rings",
            f"a tip lies {room:.4g} m from the boundary or another tip, too close for the "
            f"default rings from {CRACK_RINGS[0][0]:g} crack lengths ({length:.4g} m) or the "
            f"tip cells ({h:.4g} m): refine the mesh or give rings = [[r_inf, r_sup], ...] (m)",
        )
    return rings
