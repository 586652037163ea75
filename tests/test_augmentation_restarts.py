"""The stagnation test of the Newton solver and the restarts of a stalled contact solve
with another augmentation (the slipping sweep of bench/robustness3d.py meets the inclusion
that needs it: ``--laws slipping``)."""

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import types

import numpy as np
import pytest

from xfem_contact.mechanics.augmentation_restarts import AugmentationWarning, solve_restarting
from xfem_contact.solvers.newton import STALL_WINDOW, STALLED, stalled
from xfem_contact.solvers.report import NewtonFailure, SolveReport

#: The residual norms of the bench's cycling ellipsoid (period 4 from iterate 5)
CYCLE = [1.385e-1, 3.547e-2, 1.977e-2, 3.477e-3, 9.456e-4, 9.586e-4, 3.402e-2, 4.516e-3]
CYCLE += [1.167e-3, 9.416e-4, 3.378e-2]
#: A slow solve that converges (the concentric spheres with lbb="none", P1, n = 4)
SLOW = [1.79e-1, 2.28e2, 1.86e-1, 4.22e-2, 7.08e-3, 1.79e-3, 9.58e-4, 1.61e-3, 5.26e-4]
SLOW += [3.10e-3, 2.72e-3, 1.31e-3, 3.12e-4, 1.50e-4, 7.45e-5, 3.36e-5, 5.07e-6, 3.61e-8]
#: The same spheres on the tetrahedron frame's rules: a jump of the active set at iterate
#: 10, then Newton descending again (each norm below the one before it)
JUMP = [1.787e-1, 1.046e2, 2.445e-1, 1.957e-2, 4.284e-3, 1.259e-3, 5.906e-4, 5.914e-4]
JUMP += [1.170e-4, 5.420e-5, 2.164e-1, 1.870e-1, 1.810e-2, 3.856e-3]


def test_a_cycle_stalls_at_its_second_turn_and_slow_convergence_does_not():
    first = next(k for k in range(len(CYCLE) + 1) if stalled(CYCLE[:k]))
    assert first - 1 == 8  # iterations: the cycle's iterates 5..8 never improve on 4
    linear = list(0.8 ** np.arange(40))  # linear convergence by 0.8 an iterate
    for slow in (linear, SLOW, JUMP):
        assert not any(stalled(slow[:k]) for k in range(len(slow) + 1))
    # the early iterates of a solve never stall (an active set settling)
    assert not stalled([1.0] * (2 * STALL_WINDOW))


def fake_law(augmentation: float | None) -> types.SimpleNamespace:
    """A law with an ``augmentation`` option (None: a law without one)."""
    if augmentation is None:
        return types.SimpleNamespace(options=lambda: {})
    law = types.SimpleNamespace(augmentation=augmentation)
    law.options = lambda: {"augmentation": law.augmentation}
    return law


class FakeNewton:
    """Stalls (or fails otherwise) unless the law's augmentation is ``good``."""

    def __init__(self, law, good, failure=STALLED):
        self.law, self.good, self.failure = law, good, failure
        self.w = types.SimpleNamespace(x=types.SimpleNamespace(array=np.zeros(3)))
        self.starts = []

    def solve(self):
        self.starts.append(self.w.x.array.copy())
        self.w.x.array[:] += 1.0  # the iterates move the state
        if self.law.augmentation != self.good:
            raise NewtonFailure("no", SolveReport([1.0] * 9, reason=self.failure))
        return SolveReport([1.0, 1e-12], reason=2)


def test_a_stalled_solve_restarts_from_its_start_with_the_next_augmentation():
    law = fake_law(3.0)
    newton = FakeNewton(law, good=1.5)
    with pytest.warns(AugmentationWarning, match="times 0.5"):
        report = solve_restarting(newton, {"interface": law, "bonded": fake_law(None)})
    assert law.augmentation == 1.5  # kept
    assert len(newton.starts) == 3 and all(np.all(s == 0.0) for s in newton.starts)
    assert len(report.earlier) == 2 and report.total_iterations == 8 + 8 + 1


@pytest.mark.parametrize("reason", [STALLED, -5])
def test_a_solve_that_fails_keeps_the_augmentation_it_started_with(reason):
    law = fake_law(1.0)
    newton = FakeNewton(law, good=None, failure=reason)
    with pytest.raises(NewtonFailure) as failure:
        solve_restarting(newton, {"interface": law})
    assert law.augmentation == 1.0
    assert len(newton.starts) == (3 if reason == STALLED else 1)
    assert len(failure.value.report.earlier) == (2 if reason == STALLED else 0)
