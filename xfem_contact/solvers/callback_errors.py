"""Exceptions raised in the package's Python callbacks during a PETSc solve, raised as themselves.

petsc4py turns an exception raised in a Python callback (a SNES residual, Jacobian or
monitor, a Python preconditioner) into PETSc's error ``PETSC_ERR_PYTHON``: the solve
then raises ``PETSc.Error`` ("error code 101") with the callback's exception as its
``__cause__``. So an ``except Exception`` around a solve catches even a
``KeyboardInterrupt`` (Ctrl-C, or a SIGINT, while a factorisation runs is delivered in
the next callback) and turns an interrupt into a failed solve, and the message names no
cause. :func:`raised_as_themselves` raises the callback's own exception instead.
"""

from __future__ import annotations

import contextlib

from petsc4py import PETSc

#: PETSc's error code of an exception raised in a Python callback (``PETSC_ERR_PYTHON``)
PETSC_ERR_PYTHON = 101


def callback_exception(error: PETSc.Error) -> BaseException | None:
    """The exception a Python callback raised that ``error`` reports (through nested
    solves, e.g. a Python preconditioner's own KSP), or None when ``error`` is PETSc's
    own. Not collective."""
    cause = error
    while isinstance(cause, PETSc.Error):
        if cause.ierr != PETSC_ERR_PYTHON or cause.__cause__ is None:
            return None if cause is error else cause
        cause = cause.__cause__
    return cause


@contextlib.contextmanager
def raised_as_themselves():
    """Within the block, a ``PETSc.Error`` that reports a callback's exception
    (:func:`callback_exception`) is replaced by that exception (a ``KeyboardInterrupt``
    stays an interrupt; a ``ValueError`` of a check keeps its message); PETSc's own
    errors pass unchanged. Not collective (the exception is each process's own)."""
    try:
        yield
    except PETSc.Error as error:
        cause = callback_exception(error)
        if cause is None:
            raise
        raise cause from None
