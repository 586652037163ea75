"""Build a :class:`~xfem_contact.scenes.scene.Scene`: its mesh, level sets, laws and
problem, creating only the effects it names (see :func:`build`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import dolfinx.io
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.geometry.levelset import InterfaceError
from xfem_contact.io.gmsh import GmshMesh, facets, read_gmsh
from xfem_contact.io.meshes import annulus
from xfem_contact.mechanics.laws import make_law
from xfem_contact.mechanics.loads import annulus_parts, box_parts
from xfem_contact.mechanics.plain import PlainElasticityProblem
from xfem_contact.mechanics.problem import Problem
from xfem_contact.scenes.crack_builder import crack_cut, problem_error
from xfem_contact.scenes.expressions import compile_expression, numpy_field
from xfem_contact.scenes.load_kinds import LOAD_KINDS
from xfem_contact.scenes.scene import InterfaceSpec, Scene, SceneError


def levelset(spec: InterfaceSpec, gdim: int = 2) -> Callable[[np.ndarray], np.ndarray]:
    """The level set of an interface on a mesh of dimension ``gdim``, negative on its side
    -1 (``inside``). The curved 3D shapes are quadrics scaled to unit slope on the surface
    (a P2 level set holds them exactly): ``(|x - c|^2 - R^2) / (2 R)`` for a sphere."""
    p = spec.params
    if spec.shape == "sphere":
        c, R = np.asarray(p["centre"], dtype=float), float(p["radius"])
        return lambda x: (((x.T - c) ** 2).sum(axis=1) - R**2) / (2 * R)
    if spec.shape == "ellipsoid":
        c, axes = np.asarray(p["centre"], dtype=float), np.asarray(p["axes"], dtype=float)
        return lambda x: ((((x.T - c) / axes) ** 2).sum(axis=1) - 1.0) * axes.min() / 2
    if spec.shape == "cylinder":
        a, r = np.asarray(p["axis"], dtype=float), float(p["radius"])
        a, c = a / np.linalg.norm(a), np.asarray(p["point"], dtype=float)

        def phi(x):
            d = x.T - c
            return (np.sum(d * d, axis=1) - (d @ a) ** 2 - r * r) / (2.0 * r)

        return phi
    if spec.shape == "plane":
        n, c = np.asarray(p["normal"], dtype=float), np.asarray(p["point"], dtype=float)
        return lambda x: (x.T - c) @ (n / np.linalg.norm(n))
    if spec.shape == "circle":
        (cx, cy), r = p["centre"], float(p["radius"])
        return lambda x: np.hypot(x[0] - cx, x[1] - cy) - r
    if spec.shape == "ellipse":
        (cx, cy), (a, b) = p["centre"], p["axes"]
        t = math.radians(p["angle_deg"]) if "angle_deg" in p else float(p.get("angle", 0.0))

        def phi(x):
            dx, dy = x[0] - cx, x[1] - cy
            u, v = np.cos(t) * dx + np.sin(t) * dy, -np.sin(t) * dx + np.cos(t) * dy
            return min(a, b) * (np.hypot(u / a, v / b) - 1.0)

        return phi
    if spec.shape in ("line", "half-plane"):
        (px, py), (nx, ny) = p["point"], p["normal"]
        norm = np.hypot(nx, ny)
        return lambda x: ((x[0] - px) * nx + (x[1] - py) * ny) / norm
    return numpy_field(p["expression"], "interface expression", gdim)


def scene_parts(scene: Scene, meshed: MeshedDomain) -> dict:
    """The boundary parts a scene can name: the built-in ones of its mesh kind, the
    named physical groups of a gmsh file (local facet indices), the scene's own
    (locators of ``x``)."""
    if scene.kind in ("rectangle", "box"):
        parts = box_parts(scene.corners)
    elif scene.kind == "annulus":
        parts = annulus_parts(*scene.radii)
    else:
        parts = {"boundary": lambda x: np.ones(x.shape[1], dtype=bool)}
    if meshed.gmsh is not None:
        parts |= {name: facets(meshed.gmsh, name) for name in meshed.gmsh.parts}
    for name, where in scene.parts.items():
        f = compile_expression(where, f"parts.{name}.where", dim=scene.gdim)
        parts[name] = lambda x, f=f: np.broadcast_to(np.asarray(f(x), dtype=bool), x[0].shape)
    return parts


def _value(value, gdim: int = 2):
    """A load value: number, [a, b] ([a, b, c] in 3D), or expression string(s) -> number,
    tuple or callable (of the UFL ``x`` for loads on forms, of numpy points for
    displacements)."""
    if isinstance(value, list | tuple):
        comps = [_value(v, gdim) for v in value]

        def vector_value(x):
            if isinstance(x, ufl.core.expr.Expr):
                return ufl.as_vector([c(x) if callable(c) else c for c in comps])
            return np.stack(
                [np.broadcast_to(c(x) if callable(c) else c, x[0].shape) for c in comps]
            )

        return vector_value if any(callable(c) for c in comps) else tuple(comps)
    if isinstance(value, str):
        f = compile_expression(value, "load value", dim=gdim)
        return lambda x: (
            f(x)
            if isinstance(x, ufl.core.expr.Expr)
            else np.broadcast_to(np.asarray(f(x), dtype=float), x[0].shape).copy()
        )
    return float(value)


class MeshedDomain(NamedTuple):
    """The mesh of a scene and, for a gmsh file, what was read with it (named parts)."""

    mesh: dolfinx.mesh.Mesh
    gmsh: GmshMesh | None = None


def create_mesh(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD) -> MeshedDomain:
    """The mesh a scene names: rectangle, annulus (curved cells), box or a gmsh file.
    Collective."""
    if scene.kind == "box":
        cell = dolfinx.mesh.CellType[scene.cell]
        box = [list(scene.corners[0]), list(scene.corners[1])]
        return MeshedDomain(dolfinx.mesh.create_box(comm, box, list(scene.cells), cell))
    if scene.kind == "gmsh":
        meshed = read_gmsh(scene.file, comm, scene.geometry_degree, scene.cell, scene.size)
        return MeshedDomain(meshed.mesh, meshed)
    if scene.kind == "annulus":
        return MeshedDomain(annulus(comm, *scene.radii, *scene.cells, scene.geometry_degree))
    mesh = dolfinx.mesh.create_rectangle(
        comm,
        [list(scene.corners[0]), list(scene.corners[1])],
        list(scene.cells),
        dolfinx.mesh.CellType[scene.cell],
    )
    return MeshedDomain(mesh)


def interface_levelsets(scene: Scene) -> dict[str, Callable]:
    """The level sets of the scene's interfaces by name (a :class:`CutMesh` cuts
    several as one, checked apart: see :func:`xfem_contact.geometry.levelset.union`)."""
    return {spec.name: levelset(spec, scene.gdim) for spec in scene.interfaces}


def interface_error(scene: Scene, error: InterfaceError) -> SceneError:
    """A level set refused for an interface, as a SceneError naming its key
    (``interfaces[1]``)."""
    index = [spec.name for spec in scene.interfaces].index(error.name)
    return SceneError(f"interfaces[{index}]", error.message)


def build(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD, petsc_options_prefix: str | None = None):
    """Create the mesh and the problem of a scene (collective). Returns (problem, effects).

    The problem takes the scene's PETSc options (``[solver]``) and ``petsc_options_prefix``
    (``None``: a unique one, see :class:`~xfem_contact.mechanics.problem.Problem`)."""
    solver = {"petsc_options": scene.petsc_options, "petsc_options_prefix": petsc_options_prefix}
    meshed = create_mesh(scene, comm)
    mesh = meshed.mesh
    material = next(iter(scene.materials.values()))
    if not (scene.interfaces or scene.cracks):
        problem = PlainElasticityProblem(mesh, scene.degree, material, **solver)
        effects = {
            "interface": None,
            "interfaces": [],
            "cut": False,
            "enrichment": False,
            "multipliers": 0,
            "tangential_multiplier": False,
            "solver": "KSP (one linear solve per load step)",
            "pairing": False,
        }
    else:
        if scene.cracks:
            cut, laws, materials, options = crack_cut(scene, mesh, interface_levelsets(scene))
        else:
            try:
                cut = CutMesh(
                    mesh,
                    interface_levelsets(scene),
                    degree=scene.levelset_degree,
                    quadrature_degree=scene.quadrature_degree,
                )
            except InterfaceError as error:
                raise interface_error(scene, error) from None
            laws = {
                spec.name: make_law(
                    spec.law,
                    friction=spec.friction,
                    augmentation=spec.augmentation,
                    lbb=spec.lbb,
                    multiplier_degree=spec.multiplier_degree,
                )
                for spec in scene.interfaces
            }
            materials = {
                -1: {spec.name: scene.materials[spec.inside] for spec in scene.interfaces},
                1: scene.materials[scene.interfaces[0].outside],  # shared (see the schema)
            }
            first = scene.interfaces[0]  # kinematics, slave side and pairing are shared
            options = {"kinematics": first.kinematics, "slave": first.slave}
            options["pairing"] = first.pairing
        try:
            problem = Problem(cut, scene.degree, materials, laws, **solver, **options)
        except ValueError as error:
            if not scene.cracks:
                raise
            raise problem_error(error) from None
        gdim = mesh.geometry.dim
        effects = {
            "interface": next(iter(laws.values())).name if len(laws) == 1 else None,
            "interfaces": list(laws),
            "laws": {name: law.describe() for name, law in problem.laws.items()},
            "kinematics": problem.kinematics,
            "cut": True,
            "enrichment": True,
            "multipliers": sum(c for _, c, _ in problem.space.multiplier_fields),
            "tangential_multiplier": any(
                law.tangential and law.multiplier_components(gdim) > 1 for law in laws.values()
            ),
            "solver": "KSP (one linear solve per load step)"
            if problem.linear
            else "SNES (generalized Newton)",
            "pairing": bool(problem.couplings),
        }
        if scene.cracks:
            effects["crack"] = {"tips": len(cut.crack.tips), "tip_radius": options["tip_radius"]}
    loads = problem.loads
    loads.parts = scene_parts(scene, meshed)
    for name, (start, end) in scene.stages.items():
        loads.add_stage(name, start, end)
    for k, load in enumerate(scene.loads):
        try:
            _apply(loads, load, scene.gdim)
        except ValueError as error:
            raise SceneError(f"loads[{k}]", str(error)) from None
    return problem, effects


def _apply(loads, load, gdim: int) -> None:
    """Add one scene load to a problem's :class:`~xfem_contact.mechanics.loads.Loads`
    (its type's row of :data:`~xfem_contact.scenes.load_kinds.LOAD_KINDS`)."""
    value = None if load.value is None else _value(load.value, gdim)
    LOAD_KINDS[load.type].add(loads, load, value, {"path": load.path})
