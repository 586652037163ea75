"""Load paths: the factor of a load as a function of the pseudo-time ``t``.

Every load and prescribed displacement is its full value times a factor ``f(t)``.
The default factor is ``f(t) = t`` (one load factor for all loads); a
:class:`LoadPath` is a piecewise-linear ramp through ``(time, factor)`` points, held
constant before the first point and after the last; a *stage* ``(start, end)`` is
the ramp from 0 at ``start`` to 1 at ``end``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from xfem_contact.mechanics.parameters import is_number


class LoadPath:
    """A piecewise-linear factor of pseudo-time through ``points`` ``[(t, f), ...]``
    (dimensionless; times strictly increasing; constant outside); ``None``: ``f = t``."""

    def __init__(self, points: Sequence[Sequence[float]] | None = None, name: str = "path"):
        self.points = None
        if points is None:
            return
        try:
            array = np.asarray(points, dtype=float)
        except (TypeError, ValueError):
            array = np.zeros((0, 0))
        if array.ndim != 2 or array.shape[1] != 2 or array.shape[0] < 1:
            raise ValueError(
                f"{name} must be a list of (time, factor) pairs, e.g. [(0, 0), (1, 1)], "
                f"got {points!r}"
            )
        if not np.isfinite(array).all():
            raise ValueError(f"{name} must hold finite numbers, got {points!r}")
        if np.any(np.diff(array[:, 0]) <= 0):
            times = array[:, 0].tolist()
            raise ValueError(f"{name}: the times must increase strictly, got {times}")
        self.points = array

    def __call__(self, t: float) -> float:
        """The factor at pseudo-time ``t``."""
        if self.points is None:
            return float(t)
        return float(np.interp(t, self.points[:, 0], self.points[:, 1]))

    @property
    def end(self) -> float:
        """The last time of the path (1 for the default ``f = t``)."""
        return 1.0 if self.points is None else float(self.points[-1, 0])

    def __repr__(self) -> str:
        return "LoadPath(f = t)" if self.points is None else f"LoadPath({self.points.tolist()})"


def stage_path(name: str, stages: Mapping[str, tuple[float, float]]) -> LoadPath:
    """The ramp of stage ``name``: 0 up to its start, 1 from its end on."""
    if name not in stages:
        raise ValueError(f"Unknown load stage {name!r}; valid: {sorted(stages)}")
    start, end = stages[name]
    return LoadPath([(start, 0.0), (end, 1.0)], name=f"stage {name!r}")


def check_stage(name, start, end) -> tuple[float, float]:
    """A stage's ``(start, end)``: finite numbers, ``start < end``."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"A stage name must be a non-empty string, got {name!r}")
    for label, value in (("start", start), ("end", end)):
        if not is_number(value):
            raise ValueError(f"stage {name!r}: {label} must be a number, got {value!r}")
        if not np.isfinite(value):
            raise ValueError(f"stage {name!r}: {label} must be finite, got {value}")
    if not start < end:
        raise ValueError(f"stage {name!r}: start {start} must be before end {end}")
    return float(start), float(end)


def load_steps(n: int, end: float = 1.0) -> np.ndarray:
    """The pseudo-times ``t_k = k end / n``, k = 1..n, of ``n`` equal steps (n >= 1)."""
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ValueError(f"The number of load steps must be an integer >= 1, got {n!r}")
    if not (is_number(end) and np.isfinite(end) and end > 0):
        raise ValueError(f"The end time must be a finite number > 0, got {end!r}")
    return np.arange(1, n + 1) * (end / n)
