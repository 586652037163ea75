"""Where the sticking sphere's memory goes: resident memory by phase, one process.

Solves :func:`xfem_contact.cases.solid.sphere_problem` (sticking, quadric level set, P2
tetrahedra, ``--n`` cells per edge) with a solver preset (``--solver``, default
``iterative``) and samples the process's resident memory (``/proc/self/status``: VmRSS
every 10 ms) while labelling the time by phase: the package's named phases (the
timers of :mod:`xfem_contact._timers`), the band multigrid's block extraction and its
sub-solvers' set-up, the Krylov solve, and the steps of the case itself (mesh, cut,
problem). Prints per phase the resident memory at its start and end and the largest
sampled in it (MB); PETSc allocations are counted (tracemalloc would not see them).
With ``--save FILE`` the solution's dof array is written (``numpy.save``), to compare
two versions of the code on the same case; with ``--name NAME`` the table is written to
``bench/results/NAME.{md,json}``.

Run: ``python bench/memory3d.py --n 24 [--solver iterative] [--save u.npy] [--name
memory3d_24]``.
"""

import argparse
import json
import pathlib
import threading
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
import dolfinx.common
import dolfinx.mesh
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from xfem_contact import _timers
from xfem_contact.cases import solid
from xfem_contact.mechanics import problem as problem_module
from xfem_contact.mechanics import solving
from xfem_contact.solvers import band_multigrid, newton
from xfem_contact.solvers.options import preset


def rss_mb() -> float:
    """This process's resident memory (MB)."""
    with open("/proc/self/status") as status:
        for text in status:
            if text.startswith("VmRSS:"):
                return int(text.split()[1]) / 1024.0
    return float("nan")


class Sampler:
    """Resident memory sampled on a thread, the samples charged to the current label."""

    def __init__(self, period: float = 0.01):
        self.label, self.rows, self.period = "start", {}, period
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _charge(self, label: str, value: float) -> None:
        row = self.rows.setdefault(label, {"start": value, "end": value, "peak": value})
        row["end"], row["peak"] = value, max(row["peak"], value)

    def _run(self):
        while not self._stop.wait(self.period):
            with self._lock:
                self._charge(self.label, rss_mb())

    def enter(self, label: str) -> str:
        """Charge from now on to ``label``; the previous label."""
        if TRIM:
            TRIM(0)
        with self._lock:
            previous, value = self.label, rss_mb()
            self._charge(previous, value)
            self.label = label
            self._charge(label, value)
        return previous

    def stop(self):
        self._stop.set()
        self._thread.join()
        self.enter("end")


SAMPLER: Sampler | None = None
#: glibc's ``malloc_trim`` when ``--trim`` is given
TRIM = None


class LabelledTimer(dolfinx.common.Timer):
    """DOLFINx's timer that also labels the memory samples by the phase's name."""

    def __init__(self, name: str):
        super().__init__(name)
        self._previous = SAMPLER.enter(name.removeprefix("xfem_contact: "))

    def stop(self):
        SAMPLER.enter(self._previous)
        return super().stop()


def labelled(name: str, function):
    """``function`` with its calls charged to ``name``."""

    def call(*args, **kwargs):
        previous = SAMPLER.enter(name)
        try:
            return function(*args, **kwargs)
        finally:
            SAMPLER.enter(previous)

    return call


def main():
    global SAMPLER, TRIM
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=12, help="cells per edge (even)")
    parser.add_argument("--solver", default="iterative", choices=["iterative", "direct"])
    parser.add_argument("--save", help="write the solution's dofs here (numpy .npy)")
    parser.add_argument("--trim", action="store_true", help="malloc_trim at each phase")
    parser.add_argument("--name", help="write bench/results/NAME.{md,json}")
    args = parser.parse_args()
    if args.trim:
        import ctypes

        TRIM = ctypes.CDLL("libc.so.6").malloc_trim
    SAMPLER = Sampler()
    _timers.Timer = LabelledTimer
    bmg = band_multigrid.BandMultigrid
    bmg._build = labelled("band multigrid: blocks", bmg._build)
    bmg.apply = labelled("band multigrid: apply", bmg.apply)
    bmg.setUp = labelled("band multigrid: set-up", bmg.setUp)
    ksp_setup = PETSc.KSP.setUp

    def ksp_set_up(ksp):
        return labelled(f"KSP set-up {ksp.getOptionsPrefix()}", ksp_setup)(ksp)

    PETSc.KSP.setUp = ksp_set_up

    solid.dolfinx.mesh.create_unit_cube = labelled("mesh", dolfinx.mesh.create_unit_cube)
    solid.CutMesh = labelled("cut mesh", solid.CutMesh)
    for module, name in (
        (problem_module, "EnrichedSpace"),
        (problem_module, "prolongation_matrix"),
        (solving, "rigid_modes"),
        (solving, "vertex_interpolation"),
        (solving, "fieldsplit_dofs"),
        (newton, "fieldsplit_sets"),
        (newton, "saddle_point_scaling"),
    ):
        setattr(module, name, labelled(name, getattr(module, name)))
    start = time.perf_counter()
    SAMPLER.enter("problem")
    problem = solid.sphere_problem(
        args.n, 2, "sticking", levelset="quadric", petsc_options=preset(args.solver)
    )
    SAMPLER.enter("solve")
    report = problem.solve()
    SAMPLER.enter("errors")
    pressure, _ = solid.sphere_errors(problem)
    wall = time.perf_counter() - start
    SAMPLER.stop()
    if args.save:
        np.save(args.save, problem.w.x.array[: problem.w.x.index_map.size_local * 1])
    if MPI.COMM_WORLD.rank == 0:
        print(f"{'phase':45s} {'start':>8s} {'end':>8s} {'peak':>8s}  (MB)")
        for label, row in SAMPLER.rows.items():
            print(f"{label:45s} {row['start']:8.0f} {row['end']:8.0f} {row['peak']:8.0f}")
        summary = {
            "n": args.n,
            "dofs": problem.space.dof_counts().total,
            "krylov": report.linear_iterations,
            "wall_s": wall,
            "peak_mb": max(r["peak"] for r in SAMPLER.rows.values()),
            "error": pressure,
        }
        print(json.dumps(summary))
        if args.name:
            write(args.name, summary, SAMPLER.rows)


def write(name: str, summary: dict, rows: dict) -> None:
    """``bench/results/NAME.{md,json}``: the phases' table and the summary."""
    results = pathlib.Path(__file__).resolve().parent / "results"
    results.mkdir(exist_ok=True)
    (results / f"{name}.json").write_text(json.dumps(summary | {"phases": rows}, indent=1))
    lines = [
        f"n = {summary['n']}, {summary['dofs']:,} dofs, Krylov {summary['krylov']}, "
        f"{summary['wall_s']:.1f} s, peak resident memory {summary['peak_mb']:.0f} MB "
        "(sampled every 10 ms), pressure error "
        f"{summary['error']:.3e}. Resident memory by phase (MB; a phase's samples "
        "are charged to the innermost phase running):",
        "",
        "| phase | start | end | peak |",
        "|---|---|---|---|",
    ]
    for label, row in rows.items():
        lines.append(f"| {label} | {row['start']:.0f} | {row['end']:.0f} | {row['peak']:.0f} |")
    (results / f"{name}.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
