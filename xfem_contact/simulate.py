"""Build and run a :class:`~xfem_contact.scene.Scene`, creating only the effects it names."""

from __future__ import annotations

import pathlib
import time
from collections.abc import Callable

import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact import forms
from xfem_contact.contact import ContactProblem
from xfem_contact.cutmesh import CutMesh
from xfem_contact.elasticity import ElasticityProblem
from xfem_contact.expressions import compile_expression
from xfem_contact.meshes import annulus
from xfem_contact.plain import PlainElasticityProblem
from xfem_contact.scene import InterfaceSpec, Scene


def levelset(spec: InterfaceSpec) -> Callable[[np.ndarray], np.ndarray]:
    """The level set of an interface, negative on its side -1 (``inside``)."""
    p = spec.params
    if spec.shape == "circle":
        (cx, cy), r = p["centre"], float(p["radius"])
        return lambda x: np.hypot(x[0] - cx, x[1] - cy) - r
    if spec.shape == "ellipse":
        (cx, cy), (a, b), t = p["centre"], p["axes"], float(p.get("angle", 0.0))

        def phi(x):
            dx, dy = x[0] - cx, x[1] - cy
            u, v = np.cos(t) * dx + np.sin(t) * dy, -np.sin(t) * dx + np.cos(t) * dy
            return min(a, b) * (np.hypot(u / a, v / b) - 1.0)

        return phi
    if spec.shape in ("line", "half-plane"):
        (px, py), (nx, ny) = p["point"], p["normal"]
        norm = np.hypot(nx, ny)
        return lambda x: ((x[0] - px) * nx + (x[1] - py) * ny) / norm
    f = compile_expression(p["expression"], "interface expression")
    return lambda x: np.broadcast_to(np.asarray(f(x), dtype=float), x[0].shape).copy()


def _locator(scene: Scene, name: str) -> Callable:
    (x0, y0), (x1, y1) = scene.corners
    r0, r1 = scene.radii
    tol = 1e-6 * r1
    builtin = {
        "inner": lambda x: np.abs(np.hypot(x[0], x[1]) - r0) < tol,
        "outer": lambda x: np.abs(np.hypot(x[0], x[1]) - r1) < tol,
        "left": lambda x: np.isclose(x[0], x0),
        "right": lambda x: np.isclose(x[0], x1),
        "bottom": lambda x: np.isclose(x[1], y0),
        "top": lambda x: np.isclose(x[1], y1),
        "boundary": lambda x: np.ones(x.shape[1], dtype=bool),
    }
    if name in scene.parts:
        f = compile_expression(scene.parts[name], f"parts.{name}.where")
        return lambda x: np.broadcast_to(np.asarray(f(x), dtype=bool), x[0].shape).copy()
    return builtin[name]


def _value(value, vector: bool):
    """A load value: number, [a, b], or expression string(s) -> number/callable."""
    if isinstance(value, list | tuple):
        comps = [_value(v, False) for v in value]

        def vector_value(x):
            if isinstance(x, ufl.core.expr.Expr):
                return ufl.as_vector([c(x) if callable(c) else c for c in comps])
            return np.stack(
                [np.broadcast_to(c(x) if callable(c) else c, x[0].shape) for c in comps]
            )

        if vector and not any(callable(c) for c in comps):
            return ufl.as_vector(comps)
        return vector_value
    if isinstance(value, str):
        f = compile_expression(value, "load value")
        return lambda x: (
            f(x)
            if isinstance(x, ufl.core.expr.Expr)
            else np.broadcast_to(np.asarray(f(x), dtype=float), x[0].shape).copy()
        )
    return float(value)


def build(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD):
    """Create the mesh and the problem of a scene (collective). Returns (problem, effects)."""
    if scene.kind == "annulus":
        mesh = annulus(comm, *scene.radii, *scene.cells, scene.geometry_degree)
    else:
        mesh = dolfinx.mesh.create_rectangle(
            comm,
            [list(scene.corners[0]), list(scene.corners[1])],
            list(scene.cells),
            dolfinx.mesh.CellType[scene.cell],
        )
    material = next(iter(scene.materials.values()))
    if not scene.interfaces:
        problem = PlainElasticityProblem(mesh, scene.degree, material)
        effects = {
            "interface": None,
            "cut": False,
            "enrichment": False,
            "multipliers": 0,
            "tangential_multiplier": False,
            "solver": "KSP (one linear solve)",
            "pairing": False,
        }
    else:
        spec = scene.interfaces[0]
        cut = CutMesh(
            mesh,
            levelset(spec),
            degree=scene.levelset_degree,
            quadrature_degree=scene.quadrature_degree,
        )
        materials = {-1: scene.materials[spec.inside], 1: scene.materials[spec.outside]}
        if spec.law in ContactProblem.LAWS:
            problem = ContactProblem(
                cut,
                scene.degree,
                materials,
                spec.law,
                friction=spec.friction,
                augmentation=spec.augmentation,
                lbb=spec.lbb,
            )
            solver = "SNES (generalized Newton)"
        else:
            problem = ElasticityProblem(cut, scene.degree, materials, spec.law)
            solver = "KSP (one linear solve)"
        comps = problem.space.multiplier_components
        effects = {
            "interface": spec.law,
            "cut": True,
            "enrichment": True,
            "multipliers": comps,
            "tangential_multiplier": comps > 1 and spec.law != "bonded",
            "solver": solver,
            "pairing": False,
        }
    for load in scene.loads:
        _apply(problem, scene, load)
    return problem, effects


def _apply(problem, scene: Scene, load) -> None:
    side = {} if isinstance(problem, PlainElasticityProblem) else {"side": load.side}
    if load.type == "point_displacement":
        problem.add_point_displacement(load.point, float(load.value), int(load.component))
        return
    where = _locator(scene, load.part) if load.part else None
    if load.type == "displacement":
        problem.add_displacement(where, _value(load.value, False), load.component)
    elif load.type == "pressure":
        problem.add_pressure(where, _value(load.value, False), **side)
    elif load.type == "traction":
        problem.add_traction(where, _value(load.value, True), **side)
    elif load.type == "body_force":
        problem.add_body_force(_value(load.value, True), **side)


def run(
    scene: Scene,
    out: str | pathlib.Path | None = None,
    log: Callable[[str], None] | None = print,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> dict:
    """Build, solve and summarise a scene; writes VTX and ``summary.json`` into ``out``."""
    say = log if (log and comm.rank == 0) else (lambda *a: None)
    compiled_before = len(forms._cache)
    start = time.perf_counter()
    problem, effects = build(scene, comm)
    say(f"scene {scene.name}: effects {effects}")
    summary = {"scene": scene.name, "effects": effects, "ranks": comm.size}
    if isinstance(problem, PlainElasticityProblem):
        u = problem.solve()
        summary |= {
            "fields": ["u"],
            "dofs": {"u": problem.V.dofmap.index_map.size_global * 2},
            "iterations": 1,
        }
        fields = [u]
    else:
        if isinstance(problem, ContactProblem):
            report = problem.solve(log=say)
            w, iterations = problem.w, report.iterations
            summary["contact_status"] = report.status[-1]
        else:
            w, iterations = problem.solve().w, 1
        dofs = problem.space.dof_counts()
        names = ["u_minus", "u_plus"] + (["multiplier"] if problem.space.has_multiplier else [])
        summary |= {
            "fields": names,
            "dofs": dofs._asdict() | {"total": dofs.total},
            "iterations": iterations,
        }
        fields = [w.sub(i).collapse() for i in range(len(names))]
        for f, name in zip(fields, names, strict=True):
            f.name = name
    summary["forms_compiled"] = len(forms._cache) - compiled_before
    summary["timings"] = {"total": time.perf_counter() - start}
    if out is not None:
        from xfem_contact.output import write_fields, write_json

        out = pathlib.Path(out)
        if scene.outputs.get("vtx", True):
            write_fields(out, "displacement", fields[:2])
            if len(fields) > 2:
                write_fields(out, "multiplier", fields[2:])
        _write_grid(out, problem, fields)
        if comm.rank == 0:
            write_json(out / "summary.json", summary)
    say(
        f"done in {summary['timings']['total']:.2f} s: dofs {summary['dofs']}, "
        f"iterations {summary['iterations']}"
    )
    return summary


def _write_grid(out: pathlib.Path, problem, fields) -> None:
    """``result.vtu`` (per process): the lips of a cut scene, or the plain mesh."""
    from xfem_contact.output import write_lips

    if isinstance(problem, PlainElasticityProblem):
        import dolfinx.plot
        import pyvista

        u = fields[0]
        topology, cell_types, x = dolfinx.plot.vtk_mesh(u.function_space)
        grid = pyvista.UnstructuredGrid(topology, cell_types, x)
        values = u.x.array.reshape(-1, 2)
        grid.point_data["u"] = np.c_[values, np.zeros(values.shape[0])]
        comm = problem.mesh.comm
        name = "result.vtu" if comm.size == 1 else f"result_r{comm.rank}.vtu"
        grid.save(out / name)
    else:
        write_lips(out / "result.vtu", problem.cut, fields[0], fields[1])
