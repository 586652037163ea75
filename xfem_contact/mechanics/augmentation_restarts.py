"""Restarts of a stalled contact solve with another augmentation.

The contact laws' augmented-Lagrangian residual
(:mod:`~xfem_contact.mechanics.laws.contact`) is semismooth and generalized Newton
converges only locally. On a few cuts it cycles among a few contact and friction states,
or stalls where the residual has no root nearby. Line searches on the residual norm
stall there too. The discrete problem depends on the augmentation ``r``: the contact
state is taken at the rule points, where the multiplier and the jump, of different
degrees, meet only weakly. So a solve that stalls at one ``r`` is restarted from the
state before it with the augmentation of every contact law scaled by the next factor of
:data:`AUGMENTATION_FACTORS` (relative to the augmentation the solve started with), until
one converges. The laws keep the augmentation that converged (later solves and the
reported state use it), and an :class:`AugmentationWarning` names it.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping

from xfem_contact.mechanics.laws import InterfaceLaw
from xfem_contact.solvers.newton import STALLED, NewtonFailure, ReducedNewton
from xfem_contact.solvers.report import SolveReport

#: The factors of the augmentation tried in turn after a stalled Newton solve
AUGMENTATION_FACTORS = (2.0, 0.5)


class AugmentationWarning(UserWarning):
    """A contact solve stalled and converged with another augmentation."""


def solve_restarting(newton: ReducedNewton, laws: Mapping[str, InterfaceLaw]) -> SolveReport:
    """Solve with ``newton``; while it stalls (reason
    :data:`~xfem_contact.solvers.newton.STALLED`), put the state it started from back
    into its ``w`` and solve again with the augmentation of the laws that have one scaled
    by the next of :data:`AUGMENTATION_FACTORS`. Collective.

    Args:
        newton: The problem's Newton solver.
        laws: The problem's interface laws by interface name.

    Returns:
        The converged solve's report; its ``earlier`` holds the stalled ones.

    Raises:
        NewtonFailure: A failure other than a stall, or the last stall; the laws then keep
            the augmentation they started with (as they do when any other exception, an
            interrupt too, ends a solve).
    """
    adaptable = {name: law for name, law in laws.items() if "augmentation" in law.options()}
    given = {name: law.augmentation for name, law in adaptable.items()}
    earlier: list[SolveReport] = []
    start = newton.w.x.array.copy()
    for factor in (1.0, *AUGMENTATION_FACTORS):
        for name, law in adaptable.items():
            law.augmentation = factor * given[name]
        try:
            report = newton.solve()
        except NewtonFailure as failure:
            last = factor == AUGMENTATION_FACTORS[-1]
            if failure.report.reason != STALLED or not adaptable or last:
                _set_augmentation(adaptable, given)
                failure.report.earlier = earlier
                raise
            earlier.append(failure.report)
            newton.w.x.array[:] = start
            continue
        except BaseException:  # e.g. an interrupt: the laws keep the augmentation given
            _set_augmentation(adaptable, given)
            raise
        report.earlier = earlier
        if earlier:
            values = ", ".join(f"{name!r} {law.augmentation:g}" for name, law in adaptable.items())
            stalls = ", ".join(str(r.iterations) for r in earlier)
            warnings.warn(
                f"Newton stalled ({stalls} iterations) and converged with the augmentation "
                f"times {factor:g}: {values} ({report.total_iterations} iterations in all); "
                "the laws keep it",
                AugmentationWarning,
                stacklevel=3,
            )
        return report
    raise AssertionError("unreachable: the last factor returns or raises")


def _set_augmentation(laws: Mapping[str, InterfaceLaw], values: Mapping[str, float]) -> None:
    for name, law in laws.items():
        law.augmentation = values[name]
