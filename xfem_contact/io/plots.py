"""Plots of interface quantities (matplotlib, no display needed)."""

from __future__ import annotations

import pathlib
import typing

import numpy as np


class Series(typing.NamedTuple):
    """One curve: abscissae, ordinates, matplotlib format string and legend label."""

    x: np.ndarray
    y: np.ndarray
    style: str
    label: str


def line_plot(
    path: str | pathlib.Path, series: list[Series], xlabel: str, ylabel: str, title: str
) -> pathlib.Path:
    """Write a PNG of several curves (e.g. computed points and the exact curve).

    Draws on a :class:`matplotlib.figure.Figure` of its own with the Agg canvas: no
    pyplot, so neither the process's backend nor pyplot's figure list is touched.
    Labels in Unicode (``λₙ``), not mathtext (whose parser is slow to build)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(6, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for s in series:
        ax.plot(s.x, s.y, s.style, ms=3, label=s.label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path


def interface_abscissa(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, str]:
    """A coordinate along the interface for points ``(x, y)`` (m), shape ``(n,)`` each.

    Returns the polar angle (degrees, in (-180, 180]) about the points' centroid,
    or, for points on a straight line (a line interface), the position (m)
    along that line from the centroid; and the axis label saying which.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    centred = np.c_[x - x.mean(), y - y.mean()]
    if x.size < 3:
        return centred[:, 0], "x - mean x (m)"
    _, sv, vt = np.linalg.svd(centred, full_matrices=False)
    if sv[1] <= 1e-6 * sv[0]:
        return centred @ vt[0], "position along the interface (m)"
    theta = np.degrees(np.arctan2(centred[:, 1], centred[:, 0]))
    return theta, "polar angle about the interface centroid (degrees)"


def plot_pressure(
    abscissa: np.ndarray,
    values: np.ndarray,
    path: str | pathlib.Path,
    exact: float | typing.Callable[[np.ndarray], np.ndarray] | None = None,
    xlabel: str = "polar angle about the interface centroid (degrees)",
    title: str = "Contact pressure on the interface",
    applied: np.ndarray | None = None,
) -> pathlib.Path:
    """PNG of the contact pressure (multiplier ``lambda_n``, Pa; negative in
    compression) at interface points against a coordinate along the interface.

    Args:
        abscissa: Coordinate of each point, shape ``(n,)`` (e.g. from
            :func:`interface_abscissa`); points are sorted by it.
        values: ``lambda_n`` at the points (Pa), shape ``(n,)``.
        path: The PNG file.
        exact: The exact pressure (Pa): a constant or a function of the abscissa,
            drawn dashed; ``None`` for none.
        xlabel: Label of the abscissa.
        title: Title of the plot.
        applied: The applied (augmented) pressure ``P_n = min(0, lambda_n + r g_n)``
            at the points (Pa), shape ``(n,)``: zero where the interface is open.
    """
    s, p = np.asarray(abscissa, dtype=np.float64), np.asarray(values, dtype=np.float64)
    order = np.argsort(s)
    series = [Series(s[order], p[order], ".", "X-FEM multiplier λₙ")]
    if applied is not None:
        a = np.asarray(applied, dtype=np.float64)[order]
        series.append(Series(s[order], a, "x", "applied $P_n = \\min(0, \\lambda_n + r g_n)$"))
    if exact is not None:
        t = np.linspace(s.min(), s.max(), 400) if s.size else np.zeros(0)
        e = np.full_like(t, exact) if np.isscalar(exact) else np.asarray(exact(t), dtype=float)
        series.append(Series(t, e, "k--", "exact"))
    return line_plot(path, series, xlabel, "contact pressure λₙ (Pa)", title)


#: Colours and labels of the contact status codes (:mod:`xfem_contact.io.interface_data`)
STATUS_STYLE = {0: ("#9a9a9a", "open"), 1: ("#1f5fbf", "stick"), 2: ("#d2452b", "slip")}


def plot_traction(
    abscissa: np.ndarray,
    samples: dict,
    path: str | pathlib.Path,
    friction: float | None = None,
    xlabel: str = "polar angle about the interface centroid (degrees)",
    title: str = "Tangential traction on the interface",
) -> pathlib.Path:
    """PNG of the tangential traction (Pa) at interface points, each point coloured by
    its contact status (open, stick, slip), with the Coulomb bound ``+-mu |P_n|``.

    Args:
        abscissa: Coordinate of each point, shape ``(n,)``; points are sorted by it.
        samples: ``P_t`` (applied tangential traction, Pa; ``lambda_t`` without it),
            ``P_n`` (Pa) and ``status`` (0, 1, 2), each of length ``n``.
        path: The PNG file.
        friction: Coulomb's coefficient (the bound is drawn), or None.
        xlabel: Label of the abscissa.
        title: Title of the plot.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    s = np.asarray(abscissa, dtype=np.float64)
    order = np.argsort(s)
    s = s[order]
    t = np.asarray(samples.get("P_t", samples.get("lambda_t")), dtype=np.float64)[order]
    status = np.asarray(samples.get("status", np.zeros(s.size)), dtype=np.int64)[order]
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(6, 4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    if friction is not None and "P_n" in samples:
        bound = friction * np.abs(np.asarray(samples["P_n"], dtype=np.float64)[order])
        ax.plot(s, bound, "k--", lw=0.8, label=f"±μ|Pₙ| (μ = {friction:g})")
        ax.plot(s, -bound, "k--", lw=0.8)
    ax.plot(s, t, "-", color="#c8c8c8", lw=0.8, zorder=1)
    for code, (colour, label) in STATUS_STYLE.items():
        mine = status == code
        if mine.any():
            ax.plot(s[mine], t[mine], ".", ms=4, color=colour, label=f"{label} ({mine.sum()})")
    ax.axhline(0.0, color="black", lw=0.5)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("tangential traction Pₜ (Pa)")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path


def plot_lips(
    lips: dict, path: str | pathlib.Path, xlabel: str, title: str = "Crack lips"
) -> pathlib.Path:
    """PNG of a crack's opening ``[u].n`` and slip ``[u].t`` (m) against the abscissa
    ``s`` along its lips and, below, the multipliers ``lambda_n``, ``lambda_t`` (Pa) when
    the law has them.

    Args:
        lips: ``s``, ``opening``, ``slip`` (and ``lambda_n``, ``lambda_t``), each a list
            over the points (the ``lips`` of a crack in ``summary.json``).
        path: The PNG file.
        xlabel: Label of ``s``.
        title: Title of the plot.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    s = np.asarray(lips["s"], dtype=np.float64)
    order = np.argsort(s)
    panels = [(("opening", "opening [u]·n"), ("slip", "slip [u]·t"), "jump (m)")]
    if lips.get("lambda_n"):
        panels.append((("lambda_n", "λₙ"), ("lambda_t", "λₜ"), "multiplier (Pa)"))
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig = Figure(figsize=(6, 2.5 + 2 * len(panels)))
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (*curves, ylabel) in zip(axes, panels, strict=True):
        for (key, label), style in zip(curves, (".-", "x-"), strict=True):
            if lips.get(key):
                ax.plot(s[order], np.asarray(lips[key])[order], style, ms=3, lw=0.8, label=label)
        ax.axhline(0.0, color="black", lw=0.5)
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=8)
    axes[0].set_title(title)
    axes[-1].set_xlabel(xlabel)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    return path
