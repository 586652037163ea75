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
    """Write a PNG of several curves (e.g. computed points and the exact curve)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(6, 4))
    for s in series:
        ax.plot(s.x, s.y, s.style, ms=3, label=s.label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
