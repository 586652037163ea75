"""Progress bars for long loops (load steps, benchmark sweeps), switchable off.

:func:`progress` wraps an iterable in a tqdm bar on the first process: a notebook
widget in Jupyter when ``ipywidgets`` is there, a text bar when stderr is a terminal,
none otherwise (a pipe or a file gets the plain log lines only), when disabled, or on
the other processes. :func:`note` prints a line without breaking the bar; :func:`printer` and
:func:`add_output_arguments` give scripts their progress lines and output flags.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
from collections.abc import Callable, Iterable

from mpi4py import MPI
from tqdm import std


def _in_notebook() -> bool:
    try:
        shell = get_ipython().__class__.__name__  # type: ignore[name-defined]  # noqa: F821
    except NameError:
        return False
    return shell == "ZMQInteractiveShell" and importlib.util.find_spec("ipywidgets") is not None


def on_terminal() -> bool:
    """Whether stderr (where a text bar goes) is an interactive terminal."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced or closed streams
        return False


def progress(
    iterable: Iterable,
    description: str,
    enabled: bool = True,
    comm: MPI.Comm = MPI.COMM_WORLD,
    total: int | None = None,
):
    """``iterable`` with a progress bar (tqdm) on rank 0 of ``comm``: a widget in a
    notebook, a text bar on a terminal (:func:`on_terminal`); a plain pass-through when
    ``enabled`` is false or stderr is a pipe or a file. Not collective (each process
    iterates its own copy)."""
    if not enabled or comm.rank != 0:
        return iter(iterable)
    if _in_notebook():
        from tqdm import notebook

        return notebook.tqdm(iterable, desc=description, total=total)
    if not on_terminal():
        return iter(iterable)
    return std.tqdm(iterable, desc=description, total=total, leave=False)


def note(message: str) -> None:
    """Print ``message`` on stdout above a running text bar (tqdm's ``write``)."""
    std.tqdm.write(message)


def printer(enabled: bool = True, comm: MPI.Comm = MPI.COMM_WORLD) -> Callable[..., None]:
    """``print`` on rank 0 of ``comm`` when ``enabled``, else a function that prints
    nothing: the progress lines of a script. Not collective."""
    return print if enabled and comm.rank == 0 else _silent


def _silent(*args, **kwargs) -> None:
    pass


def add_output_arguments(parser: argparse.ArgumentParser, out: str, contents: str) -> None:
    """Add a script's output flags to ``parser``: ``--out`` (the results folder, default
    ``out``, holding ``contents``), ``--json`` (the summary's path, default
    OUT/summary.json) and ``--quiet`` (no progress lines)."""
    parser.add_argument(
        "--out", default=out, help=f"folder of the results: {contents} (default %(default)s)"
    )
    parser.add_argument(
        "--json", default=None, help="path of the JSON summary (default OUT/summary.json)"
    )
    parser.add_argument("--quiet", action="store_true", help="print no progress lines")


def add_law_arguments(parser: argparse.ArgumentParser, friction: float) -> None:
    """Add a contact script's flags to ``parser``: ``--degree`` (of the displacement, 1 or
    2; the multipliers are linear), ``--law`` (sticking, coulomb or frictionless) and
    ``--friction`` (Coulomb's coefficient, default ``friction``)."""
    parser.add_argument(
        "--degree",
        type=int,
        default=2,
        choices=[1, 2],
        help="polynomial degree of the displacement; the multipliers are linear "
        "(default %(default)s)",
    )
    parser.add_argument(
        "--law",
        default="sticking",
        choices=["sticking", "coulomb", "frictionless"],
        help="contact law of the interface (default %(default)s)",
    )
    parser.add_argument(
        "--friction",
        type=float,
        default=friction,
        help="Coulomb friction coefficient, with --law coulomb (default %(default)s)",
    )
