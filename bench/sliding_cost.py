"""The CPU cost of a large-sliding Newton iteration against a small-sliding one.

Paper case 3 at 1 rad in 4 load steps (P2, n x 4n cells,
:func:`~xfem_contact.cases.rotation.rotating_annulus_problem`, segment-to-segment
integration) and, in the same run on the same mesh, the small-sliding solve of case 3
(:func:`~xfem_contact.cases.paper.annulus_problem`, a second solve from zero, as
``bench/rotating_inclusion.py`` measures it). CPU time (``time.process_time``: less
sensitive to the other loads of a shared machine than wall time) per Newton
iteration, the first load step left out (it sets up and compiles), divided into the
hybrid elements' residual and Jacobian (:class:`~xfem_contact.mechanics.sliding.
coupling.SlidingCoupling`: breakpoints, pairing, element, blocks) and the rest (bulk
assembly, factorisation, solve). Also the CPU time of the whole large-sliding run
(set-up, 4 steps, pressure errors), and with ``--profile`` its top cProfile entries.

Run: ``python bench/sliding_cost.py [--meshes 20,40,80] [--profile]``.
"""

import argparse
import cProfile
import pstats
import time

import xfem_contact  # noqa: F401  (before dolfinx with the PyPI wheel)

# isort: split
from xfem_contact.cases.paper import annulus_problem
from xfem_contact.cases.rotation import pressure_errors, rotating_annulus_problem
from xfem_contact.mechanics.sliding.coupling import SlidingCoupling

_SPENT = {"residual": 0.0, "jacobian": 0.0}
_COUNTING = [False]


def _timed(name: str, key: str) -> None:
    method = getattr(SlidingCoupling, name)

    def timed(*args, **kwargs):
        start = time.process_time()
        try:
            return method(*args, **kwargs)
        finally:
            if _COUNTING[0]:
                _SPENT[key] += time.process_time() - start

    setattr(SlidingCoupling, name, timed)


_timed("add_residual", "residual")
_timed("add_jacobian", "jacobian")


def large(n: int) -> dict:
    """Case 3 turned by 1 rad in 4 steps: CPU s per iteration (total and parts)."""
    start = time.process_time()
    problem = rotating_annulus_problem(n, 2, 1.0)
    _SPENT.update(residual=0.0, jacobian=0.0)
    cpu, iterations = 0.0, 0
    for k in range(1, 5):
        problem.loads.set_time(k / 4)
        _COUNTING[0] = k > 1
        step = time.process_time()
        report = problem.solve()
        step = time.process_time() - step
        problem.accept_step()
        if k > 1:
            cpu, iterations = cpu + step, iterations + report.iterations
    _COUNTING[0] = False
    errors = pressure_errors(problem)
    row = {"n": n, "dofs": problem.space.dof_counts().total, "iterations": iterations}
    row["run_cpu_s"] = time.process_time() - start
    row["iteration_cpu_s"] = cpu / iterations
    row["coupling_residual_s"] = _SPENT["residual"] / iterations
    row["coupling_jacobian_s"] = _SPENT["jacobian"] / iterations
    row["error"], row["oscillation"] = errors["error"], errors["oscillation"]
    return row


def small(n: int) -> float:
    """CPU s per Newton iteration of small sliding (case 3, alpha 0) on the same mesh."""
    problem = annulus_problem(n, 4 * n, 2, 2)
    problem.solve()
    problem.w.x.array[:] = 0.0
    start = time.process_time()
    report = problem.solve()
    return (time.process_time() - start) / max(report.iterations, 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", default="20,40", help="n radial (n x 4n cells)")
    parser.add_argument("--profile", action="store_true", help="cProfile the first mesh's run")
    args = parser.parse_args()
    for i, n in enumerate(int(v) for v in args.meshes.split(",")):
        if args.profile and i == 0:
            profile = cProfile.Profile(time.process_time)
            row = profile.runcall(large, n)
            pstats.Stats(profile).sort_stats("tottime").print_stats(15)
        else:
            row = large(n)
        base = small(n)
        rest = row["iteration_cpu_s"] - row["coupling_residual_s"] - row["coupling_jacobian_s"]
        print(
            f"n = {n} ({row['dofs']} dofs), P2, 1 rad, 4 steps: large sliding "
            f"{row['iteration_cpu_s']:.3f} CPU s per iteration (coupling residual "
            f"{row['coupling_residual_s']:.3f}, coupling Jacobian "
            f"{row['coupling_jacobian_s']:.3f}, rest {rest:.3f}), small sliding "
            f"{base:.3f}: ratio {row['iteration_cpu_s'] / base:.2f}; whole large-sliding "
            f"run {row['run_cpu_s']:.1f} CPU s; error {row['error']:.2e}, oscillation "
            f"{row['oscillation']:.1e}",
            flush=True,
        )


if __name__ == "__main__":
    main()
