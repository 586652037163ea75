"""The package logs through ``logging`` (a logger per module) and never prints; programs
show the lines with a handler (:func:`xfem_contact.solvers.log_lines.lines_to`)."""

import datetime
import logging

import pytest

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.solvers.log_lines import lines_to


def test_a_solve_logs_on_the_module_logger_and_prints_nothing(caplog, capsys):
    problem = inclusion_problem(6, 1, "sticking")
    with caplog.at_level(logging.INFO, logger="xfem_contact"):
        report = problem.solve()
    newton = [r for r in caplog.records if r.name == "xfem_contact.solvers.newton"]
    assert len(newton) == report.iterations + 1  # one record per iterate, the first included
    assert all(r.levelno == logging.INFO for r in newton)
    assert newton[0].getMessage().startswith("  Newton  0: |F| = ")
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


def test_nothing_is_shown_without_a_handler(capsys):
    problem = inclusion_problem(6, 1, "sticking")
    problem.solve()
    assert logging.getLogger("xfem_contact").level == logging.NOTSET
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err == ""


def test_lines_to_gives_lines_and_marks_warnings():
    lines = []
    logger = logging.getLogger("xfem_contact.some_module")
    with lines_to(lines.append):
        logger.info("one")
        logger.debug("not shown")
        logger.warning("two")
    logger.info("after the block")
    assert lines == ["one", "warning: two"]
    assert logging.getLogger("xfem_contact").handlers[-1].__class__ is logging.NullHandler


def test_the_log_callback_of_solve_is_deprecated_and_still_called():
    lines = []
    problem = inclusion_problem(6, 1, "sticking")
    with pytest.warns(DeprecationWarning, match=r"solve\(log=\.\.\.\) is deprecated"):
        report = problem.solve(log=lines.append)
    assert len(lines) == report.iterations + 1


def test_phase_timings_are_dolfinx_timers():
    """The solve's wall times are those of DOLFINx's timers, in its table of timings."""
    from dolfinx.common import timing

    def recorded(name):
        try:
            return timing(f"xfem_contact: {name}")
        except RuntimeError:  # not timed yet in this process
            return 0, datetime.timedelta(0)

    before = {name: recorded(name) for name in ("Newton solve", "Newton set-up: forms")}
    problem = inclusion_problem(6, 1, "sticking")
    report = problem.solve()
    calls, total = recorded("Newton solve")
    assert calls == before["Newton solve"][0] + 1
    added = (total - before["Newton solve"][1]).total_seconds()
    assert report.total_time == pytest.approx(added, abs=2e-6)
    calls, total = recorded("Newton set-up: forms")
    added = (total - before["Newton set-up: forms"][1]).total_seconds()
    assert problem.solver_timings["forms"] == pytest.approx(added, abs=2e-6)
