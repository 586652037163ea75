"""A progress bar over load steps, switchable off, and log lines printed above it."""

import pytest
from test_scenes import base

from xfem_contact.io.progress import progress
from xfem_contact.scenes.run import run
from xfem_contact.scenes.scene import load_scene


@pytest.fixture(scope="module")
def scene():
    return load_scene(base(law="frictionless") | {"solver": {"load_steps": 3}})


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("enabled", [True, False])
def test_load_steps_bar(scene, capsys, enabled):
    summary = run(scene, log=print, progress_bar=enabled)
    assert summary["load_steps"] == 3
    captured = capsys.readouterr()
    assert ("t: load steps" in captured.err) == enabled  # the bar, on stderr
    assert captured.out.count("load step ") == 3  # the lines, on stdout either way


def test_progress_passes_items_through(capsys):
    assert list(progress(range(4), "items", enabled=False)) == [0, 1, 2, 3]
    assert list(progress(range(4), "items")) == [0, 1, 2, 3]
    assert "items" in capsys.readouterr().err
