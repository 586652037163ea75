"""Run a :class:`~xfem_contact.scenes.scene.Scene` built by
:mod:`~xfem_contact.scenes.builder`: load steps, solves, outputs and the summary."""

from __future__ import annotations

import logging
import pathlib

import dolfinx.io
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from xfem_contact._timers import phase, seconds
from xfem_contact._version import versions
from xfem_contact.fem import forms
from xfem_contact.io.crack_data import EnrichedDisplacements
from xfem_contact.io.interface_data import sample_status
from xfem_contact.io.output import write_json
from xfem_contact.io.progress import progress
from xfem_contact.mechanics.loads import load_steps
from xfem_contact.mechanics.reactions import balance
from xfem_contact.mechanics.stress import StressFields
from xfem_contact.scenes.builder import (  # noqa: F401  (re-exported)
    MeshedDomain,
    build,
    create_mesh,
    interface_levelsets,
    levelset,
)
from xfem_contact.scenes.crack_outputs import CrackOutputs
from xfem_contact.scenes.scene import Scene
from xfem_contact.solvers.report import NewtonFailure, SolveError

logger = logging.getLogger(__name__)


class Result:
    """The output fields of a problem as collapsed Functions, refreshed after each solve.

    Plain problems have one field ``u``; cut problems ``u_minus``, ``u_plus`` and,
    with an interface law that needs one, ``multiplier`` (``multiplier_NAME`` per
    interface when several have one); with a crack also ``branch``, and each side's
    displacement includes the branch functions
    (:class:`~xfem_contact.io.crack_data.EnrichedDisplacements`). ``stress`` holds the
    Cauchy and von Mises stresses of each displacement field
    (:class:`~xfem_contact.mechanics.stress.StressFields`).
    """

    def __init__(self, problem):
        self.problem = problem
        space = problem.space
        self.names = space.field_names()
        self.fields, self._maps = [], []
        for i, name in enumerate(self.names):
            V, dofs = space.field_space(i)
            self.fields.append(dolfinx.fem.Function(V, name=name))
            self._maps.append(dofs)
        crack = getattr(problem.cut, "crack", None) is not None
        self._enriched = EnrichedDisplacements(problem, self.fields) if crack else None
        self.stress = _stress_fields(problem, self.fields)

    def update(self, solution: dolfinx.fem.Function) -> None:
        """Copy a solution (plain ``u`` or mixed ``w``) into the fields; their stresses."""
        for f, dofs in zip(self.fields, self._maps, strict=True):
            f.x.array[:] = solution.x.array[dofs]
            f.x.scatter_forward()
        if self._enriched is not None:
            self._enriched.update()
        self.stress.update()


def _stress_fields(problem, fields: list) -> StressFields:
    """The stresses of the displacement fields, with each side's material law."""
    materials = problem.bulk.materials
    sides = [
        (label, materials[side], fields[i])
        for i, (label, side) in enumerate(problem.space.displacement_sides())
    ]
    return StressFields(sides, problem.kinematics)


def solve_step(problem) -> tuple[dolfinx.fem.Function, int, dict]:
    """Solve a problem at its current time and accept the step: (solution, iterations,
    status).

    Contact problems run Newton from the previous step (a log record per
    iterate); linear ones solve once, with the problem's options. Raises
    :class:`~xfem_contact.solvers.newton.NewtonFailure` with the iteration
    history when Newton fails.
    """
    report = problem.solve()
    problem.accept_step()
    return problem.w, report.iterations or 1, report.status[-1] if report.status else {}


def run(
    scene: Scene,
    out: str | pathlib.Path | None = None,
    comm: MPI.Comm = MPI.COMM_WORLD,
    progress_bar: bool = True,
) -> dict:
    """Build, solve and summarise a scene. Collective.

    The pseudo-time runs to ``scene.end_time`` (default: the loads' last time, at
    least 1) in ``scene.load_steps`` equal steps, each load following its path (an INFO
    record per step on this module's logger on rank 0, per Newton iterate on the
    solver's: shown where a handler is installed, see
    :func:`~xfem_contact.solvers.log_lines.lines_to`), with a progress bar over
    the steps when there are several and ``progress_bar`` is true
    (:func:`xfem_contact.io.progress.progress`). With ``out``, the
    fields of every step go to VTX files (``displacement.bp``, ``multiplier.bp``,
    time = pseudo-time), each step's grids to ``result.pvd`` (the lips, or the plain
    mesh, with the displacement and stresses) and, for a cut scene, ``interface.pvd``
    (the interface with the laws' state), series ParaView opens
    (:class:`StepGrids`, ``.pvtu`` pieces in parallel), the final state to
    ``result.vtu``, last the summary to ``summary.json`` (atomic; a stale one is removed
    first: a failed run leaves none).

    Returns:
        The summary: effects built, fields, dof counts, iterations per step, the
        contact status, timings (s); ``steps``, a record per load step (``step``,
        ``time``, ``iterations``, ``status`` (the solver's), ``forces``: the reactions,
        loads and balance (N/m) of :func:`~xfem_contact.mechanics.reactions.balance`,
        ``interfaces``: the rule points open, sticking and sliding per interface
        (:func:`status_counts`), and with cracks ``cracks``: K_I, K_II, J, G per tip and
        ring of each crack); with a crack
        its lips and K at the last step (``cracks``, see
        :class:`~xfem_contact.scenes.crack_outputs.CrackOutputs`).
    """
    say = logger.info if comm.rank == 0 else (lambda *a: None)
    out = None if out is None else pathlib.Path(out)
    if out is not None and comm.rank == 0:  # a summary.json is a finished run's
        (out / "summary.json").unlink(missing_ok=True)
    compiled_before = forms.compiled_forms()
    total, timer = phase("scene run"), phase("scene build")
    problem, effects = build(scene, comm)
    build_time = seconds(timer)
    say(f"scene {scene.name}: effects {effects}")
    cracks = CrackOutputs(problem, scene) if scene.cracks else None
    result = Result(problem)
    series = _open_series(out, result) if (out is not None and scene.outputs["vtx"]) else []
    grids = None if out is None else StepGrids(out, problem, result)
    end_time = scene.end_time or problem.loads.end_time
    steps, iterations, residuals, status = load_steps(scene.load_steps, end_time), [], [], {}
    pairing, records, tips = [], [], None
    forces_time = output_time = 0.0
    solving = phase("scene load steps")
    try:
        bar = progress(steps, f"{scene.name}: load steps", progress_bar and len(steps) > 1, comm)
        for k, t in enumerate(bar, start=1):
            problem.loads.set_time(t)
            try:
                solution, its, status = solve_step(problem)
            except SolveError as failure:
                newton = isinstance(failure, NewtonFailure)
                solver = "Newton failed (SNES" if newton else "the linear solve failed (KSP"
                raise type(failure)(
                    f"Scene {scene.name!r}, load step {k}/{len(steps)} (time {t:.4g}): "
                    f"{solver} reason {failure.report.reason})",
                    failure.report,
                ) from None
            iterations.append(its)
            if not problem.linear:
                residuals.append(problem.last_report.residuals)
            if problem.couplings:
                unpaired = problem.unpaired_points()  # collective
                pairing.append(
                    {
                        name: counts | {"unpaired_points": unpaired[name].tolist()}
                        for name, counts in problem.pairing_counts().items()
                    }
                )
                status = status | {
                    f"{key} {name}": value
                    for name, counts in pairing[-1].items()
                    for key, value in counts.items()
                    if key not in ("unpaired", "unpaired_points")  # status has the count
                }
            result.update(solution)
            record = {"step": k, "time": float(t), "iterations": its, "status": status}
            timer = phase("scene forces")  # reactions, interface resultants (N/m)
            record["forces"] = balance(problem, problem.w)
            forces_time += seconds(timer)
            if problem.laws:
                record["interfaces"] = status_counts(problem)
            if cracks is not None:
                tips = cracks.tips()
                record["cracks"] = cracks.per_crack(tips)
            records.append(record)
            timer = phase("scene output")
            for writer in series:
                writer.write(float(t))
            if grids is not None:
                grids.write(float(t))
            output_time += seconds(timer)
            say(
                f"load step {k}/{len(steps)} (time {t:.4g}): {its} iteration(s)"
                + "".join(f", {key} {value}" for key, value in status.items())
            )
    finally:
        for writer in series:
            writer.close()
    solve_time = seconds(solving) - forces_time - output_time
    summary = {
        "scene": scene.name,
        "effects": effects,
        "ranks": comm.size,
        "versions": versions(),
        "fields": result.names,
        "load_steps": len(steps),
        "iterations": int(sum(iterations)),
        "iterations_per_step": iterations,
    }
    dofs = problem.space.dof_counts()
    summary["dofs"] = dofs._asdict() | {"total": dofs.total}
    if not problem.linear:
        summary["contact_status"] = status
        summary["newton_residuals"] = residuals
    if pairing:
        summary["pairing"] = pairing
    if problem.laws:
        samples = {name: problem.interface_samples(problem.w, name) for name in problem.laws}
        for name, sampled in samples.items():  # 0 open, 1 stick, 2 slip
            sampled["status"] = sample_status(problem, name)
        summary["interfaces"] = {
            name: law.describe() | {"samples": samples[name]} for name, law in problem.laws.items()
        }
        if not problem.linear and len(samples) == 1:
            summary["interface_samples"] = next(iter(samples.values()))
    if cracks is not None:
        summary["cracks"] = cracks.summary(tips)
        for line in cracks.lines(summary["cracks"]):
            say(line)
    summary["steps"] = records
    summary["forces"] = records[-1]["forces"]  # the last step's
    reactions = ", ".join(f"{k} {v}" for k, v in summary["forces"]["reactions"].items())
    say(
        f"reactions (N/m): {reactions or 'none'}; balance (relative) "
        f"{summary['forces']['balance_relative']:.1e}"
    )
    summary["forms_compiled"] = forms.compiled_forms() - compiled_before
    cut_timings = {} if problem.cut is None else problem.cut.timings
    timings = dict(cut_timings) | {
        "mesh_and_spaces": build_time - sum(cut_timings.values()),
        "solve": solve_time,
        "forces": forces_time,
    }
    if out is not None:
        timer = phase("scene output")
        grids.write_last()
        timings["output"] = output_time + seconds(timer)
    summary["timings"] = timings | {"total": seconds(total)}
    if out is not None:
        comm.barrier()  # every rank's files are on disk before rank 0 renders them
    if out is not None and comm.rank == 0:
        write_json(out / "summary.json", summary)
        if scene.outputs["png"]:
            from xfem_contact.io.pictures import render_folder

            render_folder(out)
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
    multipliers = [f for f in result.fields[2:] if f.name.startswith("multiplier")]
    if multipliers:
        groups.append(("multiplier", multipliers))
    groups.append(("stress", result.stress.stress + result.stress.von_mises))
    return [
        dolfinx.io.VTXWriter(comm, out / f"{name}.bp", fields, engine="BP4")
        for name, fields in groups
    ]


def status_counts(problem) -> dict[str, dict[str, int]]:
    """Per interface (and crack) the number of its rule points open, sticking and
    sliding (:func:`~xfem_contact.io.interface_data.sample_status`, all processes).
    Collective."""
    counts = {}
    for name in problem.laws:
        codes = np.bincount(sample_status(problem, name), minlength=3)
        counts[name] = dict(zip(("open", "stick", "slip"), codes.tolist(), strict=True))
    return counts


class StepGrids:
    """The grids of every load step: ``result.pvd`` (the lips of a cut scene, or the
    plain mesh, with the displacement and the stresses) and, for a cut scene,
    ``interface.pvd`` (the interface pieces with the laws' state at their nodes), then
    the last step's as ``result.vtu`` and ``interface.vtu`` with ``subcells.vtu`` (the
    cut geometry) for ``xfem-contact show``. Collective."""

    def __init__(self, out: pathlib.Path, problem, result: Result):
        from xfem_contact.io.output import VTU_COMPRESSION
        from xfem_contact.io.series import StepSeries

        self.out, self.problem, self.result = out, problem, result
        comm = problem.mesh.comm
        self.series = {"result": StepSeries(out, "result", comm, VTU_COMPRESSION)}
        if problem.cut is not None:
            self.series["interface"] = StepSeries(out, "interface", comm, VTU_COMPRESSION)
        self.last = {}

    def arrays(self) -> dict:
        """The grids of the current state (name to :class:`~xfem_contact.io.vtu.GridArrays`)."""
        from xfem_contact.io.interface_data import interface_point_data
        from xfem_contact.io.output import interface_grid_arrays, lips_grid_arrays
        from xfem_contact.io.vtu import plain_arrays

        problem, fields, stress = self.problem, self.result.fields, self.result.stress
        if problem.cut is None:  # a plain problem
            named = {"stress": stress.stress[0], "von_mises": stress.von_mises[0]}
            return {"result": plain_arrays(fields[0], named)}
        named = {
            "stress": dict(zip((-1, 1), stress.stress, strict=True)),
            "von_mises": dict(zip((-1, 1), stress.von_mises, strict=True)),
        }
        return {
            "result": lips_grid_arrays(problem.cut, fields[0], fields[1], named),
            "interface": interface_grid_arrays(
                problem.cut, interface_point_data(problem), fields[0]
            ),
        }

    def write(self, t: float) -> None:
        """Add the current state as the step at pseudo-time ``t`` to each series."""
        self.last = self.arrays()
        for name, arrays in self.last.items():
            self.series[name].write(t, arrays)

    def write_last(self) -> None:
        """``result.vtu``, ``interface.vtu`` of the last step written, ``subcells.vtu``."""
        from xfem_contact.io.output import VTU_COMPRESSION, subcell_grid_arrays
        from xfem_contact.io.series import write_grid

        comm = self.problem.mesh.comm
        grids = dict(self.last)
        if self.problem.cut is not None:
            grids["subcells"] = subcell_grid_arrays(self.problem.cut)
        for name, arrays in grids.items():
            write_grid(self.out / f"{name}.vtu", arrays, comm, VTU_COMPRESSION)
