"""Phase timings with DOLFINx's timers (:class:`dolfinx.common.Timer`).

A phase is timed by a timer started at :func:`phase` and read by :func:`seconds`; named
phases are also recorded in DOLFINx's table of timings under ``"xfem_contact: NAME"``
(:func:`dolfinx.common.list_timings` shows them, summed over the calls).
"""

from __future__ import annotations

from dolfinx.common import Timer


def phase(name: str) -> Timer:
    """A started timer of the phase ``name``. Not collective."""
    return Timer(f"xfem_contact: {name}")


def seconds(timer: Timer) -> float:
    """Stop ``timer``, record it in DOLFINx's table and return its wall time (s). Not
    collective."""
    elapsed = timer.stop().total_seconds()
    timer.flush()
    return elapsed
