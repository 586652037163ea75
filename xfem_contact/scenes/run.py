"""Build and run a :class:`~xfem_contact.scenes.scene.Scene`, creating only the effects it names."""

from __future__ import annotations

import pathlib
import time
from collections.abc import Callable
from typing import NamedTuple

import dolfinx.io
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from xfem_contact.fem import forms
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.io.gmsh import GmshMesh, facets, read_gmsh
from xfem_contact.io.meshes import annulus
from xfem_contact.io.output import write_json
from xfem_contact.mechanics.laws import ContactLaw, make_law
from xfem_contact.mechanics.loading import load_steps
from xfem_contact.mechanics.plain import PlainElasticityProblem
from xfem_contact.mechanics.problem import Problem
from xfem_contact.scenes.expressions import compile_expression
from xfem_contact.scenes.scene import InterfaceSpec, Scene
from xfem_contact.solvers.newton import NewtonFailure


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


def _part(scene: Scene, name: str, meshed: MeshedDomain) -> Callable | np.ndarray:
    """A boundary part: a locator of ``x`` for built-in and expression parts, local
    facet indices for the named physical groups of a gmsh file."""
    if name in scene.parts:
        f = compile_expression(scene.parts[name], f"parts.{name}.where")
        return lambda x: np.broadcast_to(np.asarray(f(x), dtype=bool), x[0].shape).copy()
    if meshed.gmsh is not None and name in meshed.gmsh.parts:
        return facets(meshed.gmsh, name)
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


class MeshedDomain(NamedTuple):
    """The mesh of a scene and, for a gmsh file, what was read with it (named parts)."""

    mesh: dolfinx.mesh.Mesh
    gmsh: GmshMesh | None = None


def create_mesh(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD) -> MeshedDomain:
    """The mesh a scene names: rectangle, annulus (curved cells) or a gmsh file. Collective."""
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
    return {spec.name: levelset(spec) for spec in scene.interfaces}


def build(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD):
    """Create the mesh and the problem of a scene (collective). Returns (problem, effects)."""
    meshed = create_mesh(scene, comm)
    mesh = meshed.mesh
    material = next(iter(scene.materials.values()))
    if not scene.interfaces:
        problem = PlainElasticityProblem(mesh, scene.degree, material)
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
        cut = CutMesh(
            mesh,
            interface_levelsets(scene),
            degree=scene.levelset_degree,
            quadrature_degree=scene.quadrature_degree,
        )
        laws = {
            spec.name: make_law(
                spec.law, friction=spec.friction, augmentation=spec.augmentation, lbb=spec.lbb
            )
            for spec in scene.interfaces
        }
        materials = {
            -1: {spec.name: scene.materials[spec.inside] for spec in scene.interfaces},
            1: scene.materials[scene.interfaces[0].outside],  # shared (see the schema)
        }
        problem = Problem(cut, scene.degree, materials, laws)
        gdim = mesh.geometry.dim
        effects = {
            "interface": scene.interfaces[0].law if len(laws) == 1 else None,
            "interfaces": [s.name for s in scene.interfaces],
            "laws": {name: law.describe() for name, law in laws.items()},
            "cut": True,
            "enrichment": True,
            "multipliers": sum(c for _, c, _ in problem.space.multiplier_fields),
            "tangential_multiplier": any(
                isinstance(law, ContactLaw) and law.multiplier_components(gdim) > 1
                for law in laws.values()
            ),
            "solver": "KSP (one linear solve per load step)"
            if problem.linear
            else "SNES (generalized Newton)",
            "pairing": False,
        }
    for load in scene.loads:
        _apply(problem, scene, load, meshed)
    return problem, effects


def _apply(problem, scene: Scene, load, meshed: MeshedDomain) -> None:
    side = {} if isinstance(problem, PlainElasticityProblem) else {"side": load.side}
    if load.type == "point_displacement":
        problem.add_point_displacement(load.point, float(load.value), int(load.component))
        return
    where = _part(scene, load.part, meshed) if load.part else None
    if load.type == "displacement":
        problem.add_displacement(where, _value(load.value, False), load.component)
    elif load.type == "pressure":
        problem.add_pressure(where, _value(load.value, False), **side)
    elif load.type == "traction":
        problem.add_traction(where, _value(load.value, True), **side)
    elif load.type == "body_force":
        problem.add_body_force(_value(load.value, True), **side)
    else:  # the scene schema admits no other type
        raise AssertionError(f"unhandled load type {load.type!r}")


class Result:
    """The output fields of a problem as collapsed Functions, refreshed after each solve.

    Plain problems have one field ``u``; cut problems ``u_minus``, ``u_plus`` and,
    with an interface law that needs one, ``multiplier`` (``multiplier_NAME`` per
    interface when several have one).
    """

    def __init__(self, problem):
        self.problem = problem
        if isinstance(problem, PlainElasticityProblem):
            self.names = ["u"]
            self.fields = [dolfinx.fem.Function(problem.V, name="u")]
            self._maps = [None]
        else:
            W = problem.space.W
            fields = problem.space.multiplier_fields
            self.names = ["u_minus", "u_plus"]
            self.names += [
                "multiplier" if len(fields) == 1 else f"multiplier_{name}" for _, _, name in fields
            ]
            self.fields, self._maps = [], []
            for i, name in enumerate(self.names):
                V, dofs = W.sub(i).collapse()
                self.fields.append(dolfinx.fem.Function(V, name=name))
                self._maps.append(np.asarray(dofs))

    def update(self, solution: dolfinx.fem.Function) -> None:
        """Copy a solution (plain ``u`` or mixed ``w``) into the fields."""
        for f, dofs in zip(self.fields, self._maps, strict=True):
            f.x.array[:] = solution.x.array if dofs is None else solution.x.array[dofs]
            f.x.scatter_forward()


def solve_step(
    problem, petsc_options: dict | None = None, log: Callable[[str], None] | None = None
) -> tuple[dolfinx.fem.Function, int, dict]:
    """Solve a problem at its current load factor: (solution, iterations, status).

    Contact problems run Newton from the previous step (a ``log`` line per
    iterate) and accept the step; linear ones solve once. ``petsc_options``
    override the solver's defaults (cut problems). Raises
    :class:`~xfem_contact.solvers.newton.NewtonFailure` with the iteration
    history when Newton fails.
    """
    if isinstance(problem, PlainElasticityProblem):
        return problem.solve(petsc_options), 1, {}
    if not problem.linear:
        report = problem.solve(petsc_options=petsc_options, log=log)
        problem.accept_step()
        return problem.w, report.iterations, report.status[-1]
    return problem.solve(petsc_options=petsc_options).w, 1, {}


def run(
    scene: Scene,
    out: str | pathlib.Path | None = None,
    log: Callable[[str], None] | None = print,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> dict:
    """Build, solve and summarise a scene. Collective.

    The loads are applied in ``scene.load_steps`` equal steps (a line per step and
    per Newton iterate goes to ``log``; ``None`` for silence). With ``out``, the
    fields of every step go to VTX files (``displacement.bp``, ``multiplier.bp``,
    time = load factor), the final state to ``result.vtu``, last the summary to
    ``summary.json`` (atomic; a stale one is removed first: a failed run leaves none).

    Returns:
        The summary: effects built, fields, dof counts, iterations per step, the
        contact status, timings (s).
    """
    say = log if (log and comm.rank == 0) else (lambda *a: None)
    out = None if out is None else pathlib.Path(out)
    if out is not None and comm.rank == 0:  # a summary.json is a finished run's
        (out / "summary.json").unlink(missing_ok=True)
    compiled_before = len(forms._cache)
    start = time.perf_counter()
    problem, effects = build(scene, comm)
    build_time = time.perf_counter() - start
    say(f"scene {scene.name}: effects {effects}")
    result = Result(problem)
    series = _open_series(out, result) if (out is not None and scene.outputs["vtx"]) else []
    steps, iterations, residuals, status = load_steps(scene.load_steps), [], [], {}
    solve_start = time.perf_counter()
    try:
        for k, t in enumerate(steps, start=1):
            problem.load_factor.set(t)
            try:
                solution, its, status = solve_step(
                    problem, scene.petsc_options or None, say if log else None
                )
            except NewtonFailure as failure:
                raise NewtonFailure(
                    f"Scene {scene.name!r}, load step {k}/{len(steps)} (load factor {t:.4g}): "
                    f"Newton failed (SNES reason {failure.report.reason})",
                    failure.report,
                ) from None
            iterations.append(its)
            if not problem.linear:
                residuals.append(problem.last_report.residuals)
            result.update(solution)
            for writer in series:
                writer.write(float(t))
            say(
                f"load step {k}/{len(steps)} (factor {t:.4g}): {its} iteration(s)"
                + "".join(f", {key} {value}" for key, value in status.items())
            )
    finally:
        for writer in series:
            writer.close()
    solve_time = time.perf_counter() - solve_start
    summary = {
        "scene": scene.name,
        "effects": effects,
        "ranks": comm.size,
        "fields": result.names,
        "load_steps": len(steps),
        "iterations": int(sum(iterations)),
        "iterations_per_step": iterations,
    }
    if isinstance(problem, PlainElasticityProblem):
        summary["dofs"] = {"u": problem.V.dofmap.index_map.size_global * problem.V.dofmap.bs}
    else:
        dofs = problem.space.dof_counts()
        summary["dofs"] = dofs._asdict() | {"total": dofs.total}
    if not problem.linear:
        summary["contact_status"] = status
        summary["newton_residuals"] = residuals
    if not isinstance(problem, PlainElasticityProblem):
        samples = {name: problem.interface_samples(name) for name in problem.laws}
        summary["interfaces"] = {
            name: law.describe() | {"samples": samples[name]} for name, law in problem.laws.items()
        }
        if not problem.linear and len(samples) == 1:
            summary["interface_samples"] = next(iter(samples.values()))
    summary["forms_compiled"] = len(forms._cache) - compiled_before
    cut_timings = getattr(getattr(problem, "cut", None), "timings", {})
    timings = dict(cut_timings) | {
        "mesh_and_spaces": build_time - sum(cut_timings.values()),
        "solve": solve_time,
    }
    if out is not None:
        output_start = time.perf_counter()
        _write_grid(out, problem, result.fields)
        timings["output"] = time.perf_counter() - output_start
    summary["timings"] = timings | {"total": time.perf_counter() - start}
    if out is not None:
        comm.barrier()  # every rank's files are on disk before rank 0 renders them
    if out is not None and comm.rank == 0:
        write_json(out / "summary.json", summary)
        if scene.outputs["png"]:
            from xfem_contact.io.pictures import render_folder

            render_folder(out, log=say)
    say(
        f"done in {summary['timings']['total']:.2f} s: dofs {summary['dofs']}, "
        f"iterations {summary['iterations_per_step']}"
    )
    return summary


def _open_series(out: str | pathlib.Path, result: Result) -> list:
    """VTX writers of the displacement(s) and the multiplier (one time step per load step)."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    comm = result.fields[0].function_space.mesh.comm
    groups = [("displacement", result.fields[:2])]
    if len(result.fields) > 2:
        groups.append(("multiplier", result.fields[2:]))
    return [
        dolfinx.io.VTXWriter(comm, out / f"{name}.bp", fields, engine="BP4")
        for name, fields in groups
    ]


def _write_grid(out: pathlib.Path, problem, fields) -> None:
    """``result.vtu`` (per process): the lips of a cut scene, or the plain mesh; and
    for a cut scene ``subcells.vtu``/``interface.vtu`` (the cut geometry)."""
    from xfem_contact.io.output import write_cut_geometry, write_lips

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
        write_cut_geometry(out, problem.cut)
