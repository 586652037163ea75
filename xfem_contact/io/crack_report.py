"""Stress intensity factors as text a fracture user reads: one table per crack.

:func:`tip_records` turns the ring results of every tip
(:meth:`~xfem_contact.mechanics.fracture.TipIntegrals.evaluate`) into plain records
(the ``tips`` of a scene's ``summary.json``); :func:`crack_table` prints them, one row
per tip and ring (the ring named by its radii), with K_I, K_II (in the unit stated in
the header), J and G (J/m^2), the reference where one is given and the difference from
it, then notes: the law of the lips, the loads, what the reference includes and the
sign convention of K. Pure functions of numbers: not collective.
"""

from __future__ import annotations

import dataclasses
import math
import textwrap
from collections.abc import Sequence

import numpy as np

from xfem_contact.mechanics.fracture import Ring, RingResult, spread

#: The units of K: (threshold of max |K| in Pa m^1/2, scale, label), first match wins
K_UNITS = ((1e5, 1e6, "MPa m^1/2"), (1e2, 1e3, "kPa m^1/2"), (0.0, 1.0, "Pa m^1/2"))
#: The units of the loads' values, by load kind
LOAD_UNITS = {"traction": "Pa", "pressure": "Pa", "body force": "N/m^3", "displacement": "m"}
#: Width of the notes under a table (characters) and their indent
WIDTH, INDENT = 100, {"initial_indent": "  ", "subsequent_indent": "    "}
#: A mode's reference below this fraction of |K_ref| counts as zero (differences are
#: then relative to |K_ref|)
ZERO_MODE = 1e-12


@dataclasses.dataclass(frozen=True)
class Reference:
    """Reference stress intensity factors of every tip of a crack.

    Attributes:
        K_I: Mode I (Pa m^1/2).
        K_II: Mode II (Pa m^1/2), in the tips' frames (see :func:`crack_table`).
        source: Where it comes from and what it includes (e.g. "Griffith, infinite
            plate: the finite plate raises K"), printed under the table.
    """

    K_I: float
    K_II: float
    source: str = ""

    def __post_init__(self):
        for name in ("K_I", "K_II"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"reference {name} must be a number (Pa m^1/2), got {value!r}")
            if not math.isfinite(value):
                raise ValueError(f"reference {name} must be finite (Pa m^1/2), got {value!r}")

    @property
    def magnitude(self) -> float:
        """``sqrt(K_I^2 + K_II^2)`` (Pa m^1/2)."""
        return math.hypot(self.K_I, self.K_II)

    def difference(self, mode: str, K: float) -> float:
        """``K / K_ref - 1`` of ``mode`` (``"K_I"`` or ``"K_II"``); ``(K - K_ref) /
        |K_ref|`` when that mode's reference is zero; nan when both are."""
        ref, scale = getattr(self, mode), self.magnitude
        if scale == 0.0:
            return math.nan
        return (K - ref) / (ref if abs(ref) > ZERO_MODE * scale else scale)


def tip_records(tips, directions, results) -> list[dict]:
    """Plain records of the tips: ``[{position, direction, rings: [{r_inf, r_sup, K_I,
    K_II, J, G}]}]`` (m, Pa m^1/2, J/m^2) from the tips' positions ``(ntips, gdim)``,
    directions and ring results (:class:`~xfem_contact.mechanics.fracture.RingResult`
    per tip and ring)."""
    return [
        {
            "position": np.asarray(position).tolist(),
            "direction": np.asarray(direction).tolist(),
            "rings": [
                {
                    "r_inf": r.ring.r_inf,
                    "r_sup": r.ring.r_sup,
                    "K_I": r.K_I,
                    "K_II": r.K_II,
                    "J": r.J,
                    "G": r.G,
                }
                for r in per_ring
            ],
        }
        for position, direction, per_ring in zip(tips, directions, results, strict=True)
    ]


def k_unit(values: Sequence[float]) -> tuple[float, str]:
    """``(scale, label)`` of the unit to print K values in (:data:`K_UNITS`)."""
    largest = max((abs(v) for v in values if math.isfinite(v)), default=0.0)
    return next((scale, label) for low, scale, label in K_UNITS if largest >= low)


def load_words(loads, t: float | None = None) -> str:
    """The applied loads of a :class:`~xfem_contact.mechanics.loads.Loads` in words, at
    pseudo-time ``t`` (default: the loads' time): kind, part, value times the load path's
    factor, unit. Supports held at zero are left out."""
    t = loads.time if t is None else t
    words = []
    for load in loads.items:
        unit = LOAD_UNITS.get(load.kind)
        if unit is None:
            continue
        factor, value = load.path(t), load.value
        if callable(value) or isinstance(value, dict):
            shown = "an expression" if callable(value) else "a value per side"
            shown += f" x {factor:.4g}"
        elif hasattr(value, "ufl_shape"):
            shown = f"a UFL expression x {factor:.4g}"
        else:
            scaled = factor * np.asarray(value, dtype=float)
            if load.kind == "displacement" and not np.any(scaled):
                continue  # a support
            shown = (
                f"{float(scaled):.4g}"
                if scaled.ndim == 0
                else "(" + ", ".join(f"{v:.4g}" for v in scaled) + ")"
            )
        part = f" on {load.part!r}" if load.part else ""
        words.append(f"{load.kind}{part} {shown} {unit}")
    return ", ".join(words) or "none"


def _law_words(law: dict) -> str:
    """``{"law": name, option: value, ...}`` as ``name (option value, ...)``."""
    options = ", ".join(
        f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in law.items() if k != "law"
    )
    return law.get("law", "?") + (f" ({options})" if options else "")


def crack_table(
    name: str,
    tips: list[dict],
    law: dict,
    loads: str | None = None,
    reference: Reference | None = None,
    modulus: float | None = None,
) -> list[str]:
    """The text lines of one crack's table and notes.

    Args:
        name: The crack's name.
        tips: :func:`tip_records` of its tips.
        law: The law of its lips (``law.describe()``: ``{"law": name, options}``).
        loads: The loads in words (:func:`load_words`); None leaves the line out.
        reference: The reference K of every tip, or None.
        modulus: ``E'`` (Pa), for the reference's ``G = (K_I^2 + K_II^2) / E'``.

    Returns:
        Lines: a title (crack, law, loads), the header (units), a row per tip and
        ring, a reference row per tip, then notes on the reference, the rings'
        agreement and the sign convention (K_I under contact).
    """
    K_all = [r[m] for tip in tips for r in tip["rings"] for m in ("K_I", "K_II")]
    scale, unit = k_unit(K_all + ([reference.K_I, reference.K_II] if reference else []))
    lines = [f"crack {name!r}: law of the lips {_law_words(law)}"]
    if loads is not None:
        lines.append(f"  loads: {loads}")
    lines.append(f"  K in {unit}, J and G in J/m^2; ring: r_inf..r_sup (m) from the tip")
    header = f"  {'tip':>3}  {'ring':<15} {'K_I':>10} {'K_II':>10} {'J':>10} {'G':>10}"
    if reference is not None:
        header += f" {'K_I vs ref':>11} {'K_II vs ref':>11}"
    lines.append(header)
    negative = []
    for k, tip in enumerate(tips):
        for r in tip["rings"]:
            ring = f"{r['r_inf']:.4g}..{r['r_sup']:.4g}"
            row = (
                f"  {k:>3}  {ring:<15} {r['K_I'] / scale:>10.4f} {r['K_II'] / scale:>10.4f} "
                f"{r['J']:>10.4g} {r['G']:>10.4g}"
            )
            if reference is not None:
                row += (
                    f" {100 * reference.difference('K_I', r['K_I']):>+10.2f}%"
                    f" {100 * reference.difference('K_II', r['K_II']):>+10.2f}%"
                )
            lines.append(row)
            if r["K_I"] < 0:
                negative.append(r["K_I"] / math.hypot(r["K_I"], r["K_II"]))
        if reference is not None:
            G = "" if modulus is None else f"{reference.magnitude**2 / modulus:.4g}"
            lines.append(
                f"  {k:>3}  {'reference':<15} {reference.K_I / scale:>10.4f} "
                f"{reference.K_II / scale:>10.4f} {'':>10} {G:>10}"
            )
    count = len(lines)  # the notes follow, wrapped
    at = ", ".join(
        f"tip {k} at ({', '.join(f'{x:.4g}' for x in tip['position'])}) m"
        for k, tip in enumerate(tips)
    )
    lines.append(f"{at}; each ring: q = 1 within r_inf of the tip, 0 beyond r_sup")
    spreads = [_ring_spread(tip["rings"]) for tip in tips if len(tip["rings"]) > 1]
    if spreads:
        lines.append(f"the rings agree to {100 * max(spreads):.2g} % of max |K| per tip")
    if reference is not None:
        lines.append(
            "reference: "
            + (reference.source or "given")
            + "; vs ref = K / K_ref - 1 per mode ((K - K_ref) / sqrt(K_I_ref^2 + "
            "K_II_ref^2) where the mode's reference is 0)"
        )
    lines.append(
        "signs, in each tip's frame (x1 ahead of the tip, x2 to its left): K_I > 0 opens "
        "the lips; K_II > 0 moves the x2 > 0 lip toward x1 > 0 relative to the other"
    )
    contact = law.get("law", "free") != "free"
    if contact:
        lines.append(
            "contact on the lips: closed lips carry K_I = 0 in the exact solution (they "
            "cannot interpenetrate); a small negative K_I of closed lips is the "
            "discretisation's"
            + (f" (here down to {100 * min(negative):.2g} % of |K|)" if negative else "")
        )
    elif negative:
        lines.append(
            f"K_I < 0 with free lips (down to {100 * min(negative):.2g} % of |K|): the lips "
            "pass through each other here; a contact law on the crack keeps them apart"
        )
    return lines[:count] + [
        wrapped for line in lines[count:] for wrapped in textwrap.wrap(line, WIDTH, **INDENT)
    ]


def _ring_spread(rings: list[dict]) -> float:
    """The largest ring-to-ring spread of K_I and K_II of a tip's ring records
    (:func:`~xfem_contact.mechanics.fracture.spread`)."""
    results = [
        RingResult(Ring(r["r_inf"], r["r_sup"]), r["K_I"], r["K_II"], r["J"], r["G"]) for r in rings
    ]
    ranges = spread(results)
    return max(ranges["K_I"], ranges["K_II"])
