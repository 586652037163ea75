"""The package's log records as lines, for programs that show them.

Library modules log on ``logging.getLogger(__name__)`` (Newton's iterates, load steps,
warnings) and never print; the package's logger ``"xfem_contact"`` has a
``NullHandler``, so nothing shows unless a program asks. :func:`lines_to` is how the
scene command line and the demos ask: each record of the block becomes one line given
to a function (``print``, or :func:`xfem_contact.io.progress.note` above a progress bar).
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable

#: The logger of the whole package (every module's logger is below it)
PACKAGE = "xfem_contact"


class LineHandler(logging.Handler):
    """Each record as one line to ``write``: the message, prefixed by ``warning: `` for
    warnings and errors."""

    def __init__(self, write: Callable[[str], None], level: int = logging.INFO):
        super().__init__(level)
        self.write = write

    def emit(self, record: logging.LogRecord) -> None:
        try:
            message = record.getMessage()
            if record.levelno >= logging.WARNING:
                message = f"warning: {message}"
            self.write(message)
        except Exception:  # logging's convention: a handler never raises
            self.handleError(record)


@contextlib.contextmanager
def lines_to(write: Callable[[str], None] | None, level: int = logging.INFO):
    """Give the package's records of ``level`` and above to ``write`` while the block
    runs (``None``: nothing is installed). Not collective: install it on the processes
    that should show the lines (e.g. rank 0)."""
    if write is None:
        yield
        return
    logger = logging.getLogger(PACKAGE)
    handler = LineHandler(write, level)
    kept = logger.level
    logger.addHandler(handler)
    if logger.getEffectiveLevel() > level:
        logger.setLevel(level)
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.setLevel(kept)
