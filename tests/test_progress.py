"""A progress bar over load steps on a terminal only, and log lines printed above it."""

import argparse
import subprocess
import sys

import pytest
from test_scenes import base

from xfem_contact.io import progress as progress_module
from xfem_contact.io.progress import note, progress
from xfem_contact.scenes.run import run
from xfem_contact.scenes.scene import load_scene
from xfem_contact.solvers.log_lines import lines_to


@pytest.fixture(scope="module")
def scene():
    return load_scene(base(law="frictionless") | {"solver": {"load_steps": 3}})


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("terminal", [True, False])
@pytest.mark.parametrize("enabled", [True, False])
def test_load_steps_bar_on_a_terminal_only(scene, capsys, monkeypatch, enabled, terminal):
    monkeypatch.setattr(progress_module, "on_terminal", lambda: terminal)
    with lines_to(note):  # as the command line shows them
        summary = run(scene, progress_bar=enabled)
    assert summary["load_steps"] == 3
    captured = capsys.readouterr()
    assert ("t: load steps" in captured.err) == (enabled and terminal)  # the bar, on stderr
    assert captured.out.count("load step ") == 3  # the lines, on stdout either way
    if not terminal:  # plain lines: no carriage return, no bar
        assert "\r" not in captured.out + captured.err
        assert "|" not in captured.err


def test_progress_passes_items_through(capsys, monkeypatch):
    assert list(progress(range(4), "items", enabled=False)) == [0, 1, 2, 3]
    assert list(progress(range(4), "items")) == [0, 1, 2, 3]  # capsys: not a terminal
    assert "items" not in capsys.readouterr().err
    monkeypatch.setattr(progress_module, "on_terminal", lambda: True)
    assert list(progress(range(4), "items")) == [0, 1, 2, 3]
    assert "items" in capsys.readouterr().err


def test_no_bar_into_a_pipe():
    code = (
        "from xfem_contact.io.progress import note, progress\n"
        "for i in progress(range(3), 'piped'):\n"
        "    note(f'line {i}')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "line 0\nline 1\nline 2\n"
    assert "piped" not in done.stderr and "\r" not in done.stderr


@pytest.mark.parametrize("enabled", [True, False])
def test_a_scripts_printer_prints_on_the_first_process_when_enabled(capsys, enabled):
    say = progress_module.printer(enabled)
    say("a progress line")
    assert ("a progress line" in capsys.readouterr().out) == enabled


def test_output_arguments_give_out_json_and_quiet():
    parser = argparse.ArgumentParser()
    progress_module.add_output_arguments(parser, "results/x", "VTX, summary.json")
    args = parser.parse_args(["--quiet"])
    assert (args.out, args.json, args.quiet) == ("results/x", None, True)
    assert "VTX, summary.json" in parser.format_help()
