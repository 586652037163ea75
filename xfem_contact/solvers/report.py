"""What a solve reports: the solution, the history of its iterates (one for a linear
solve), and the failures that carry it.

Every solve of the package fails the same way: it raises a :class:`SolveError`
(:class:`NewtonFailure` for a Newton solve, :class:`LinearSolveFailure` for a linear
one) holding the :class:`SolveReport` of the failed solve, after the problem's state
was put back to the one before the solve and every PETSc object of the solve freed."""

from __future__ import annotations

import dataclasses
import typing


@dataclasses.dataclass
class SolveReport:
    """One solve: the solution, residual norms and per-iterate status lines.

    Attributes:
        residuals: Norm of the scaled reduced residual ``D R^T F`` at each iterate,
            the initial one first (``iterations + 1`` entries; a linear solve has
            two: before and after).
        status: The status callback's dict at each iterate (same length).
        reason: SNES converged reason (> 0 converged, < 0 diverged).
        final_residual: The residual norm evaluated after the solve (checked
            against the tolerances; NaN before).
    """

    residuals: list[float] = dataclasses.field(default_factory=list)
    status: list[dict] = dataclasses.field(default_factory=list)
    #: Krylov iterations of the linear solve of each Newton step (1 per step for LU)
    linear_iterations: list[int] = dataclasses.field(default_factory=list)
    reason: int = 0
    final_residual: float = float("nan")
    #: Wall time (s) of residual/Jacobian assembly, of the status callback and of
    #: the whole solve
    assembly_time: float = 0.0
    status_time: float = 0.0
    total_time: float = 0.0
    #: The solution on the problem's mixed space (set by ``Problem.solve``)
    w: typing.Any = None
    #: The problem's enriched space (for :meth:`field`)
    space: typing.Any = dataclasses.field(default=None, repr=False)
    #: The reports of the stalled solves this one restarted from
    #: (:mod:`xfem_contact.mechanics.augmentation_restarts`), first first
    earlier: list = dataclasses.field(default_factory=list, repr=False)

    @property
    def converged(self) -> bool:
        """Whether the solve converged (``reason > 0``)."""
        return self.reason > 0

    def field(self, i: int):
        """Collapsed copy of field ``i`` of :attr:`w`: 0 side -1, 1 side +1, 2..
        multipliers (:meth:`displacement` takes the side itself)."""
        return self.space.field(self.w, i)

    def displacement(self, side: int):
        """Collapsed copy of the displacement field of ``side`` (-1 or +1) of :attr:`w`
        (its standard part; m)."""
        sides = {s: (i, label) for i, (label, s) in enumerate(self.space.displacement_sides())}
        if side not in sides:
            raise ValueError(f"side must be one of {sorted(sides)}, got {side!r}")
        field, label = sides[side]
        return self.space.field(self.w, field, name=f"u_{label}" if label else "u")

    @property
    def linear_solve_time(self) -> float:
        """Wall time (s) of the rest: the factorisations and triangular solves."""
        return self.total_time - self.assembly_time - self.status_time

    @property
    def iterations(self) -> int:
        """Number of Newton steps taken."""
        return max(len(self.residuals) - 1, 0)

    @property
    def total_iterations(self) -> int:
        """Newton steps taken, those of the :attr:`earlier` solves included."""
        return self.iterations + sum(r.iterations for r in self.earlier)

    def table(self) -> str:
        """The history, one line per iterate. Not collective."""
        lines = []
        for k, r in enumerate(self.residuals):
            extra = self.status[k] if k < len(self.status) else {}
            lines.append(
                f"  iterate {k:2d}  |F| = {r:.3e}  "
                + "  ".join(f"{key} {value}" for key, value in extra.items())
            )
        return "\n".join(lines)


#: The report of a Newton solve (the same type)
NewtonReport = SolveReport


class SolveError(RuntimeError):
    """A solve did not converge; ``report`` holds its history (reason < 0)."""

    def __init__(self, message: str, report: SolveReport):
        super().__init__(f"{message}\n{report.table()}")
        self.report = report


class NewtonFailure(SolveError):
    """Newton (SNES) did not converge; ``report`` holds the iteration history."""


class LinearSolveFailure(SolveError):
    """A linear solve (KSP) did not converge; ``report`` holds its reason and the
    residual norms before and after (when they were computed)."""
