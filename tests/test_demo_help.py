"""Every demo's ``--help`` is complete: the description is the first paragraph of the
demo's docstring, in whole sentences, and every option says what it does."""

import argparse
import ast
import pathlib
import runpy
import sys

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import pytest

DEMOS = sorted((pathlib.Path(__file__).resolve().parents[1] / "demos").glob("*.py"))


@pytest.mark.parametrize("demo", DEMOS, ids=[d.stem for d in DEMOS])
def test_demo_help_is_complete(demo, monkeypatch, capsys):
    """``python demos/X.py --help`` (run in this process): exit 0, the description
    whole sentences, every option with its help text."""
    parsers = []
    parse_args = argparse.ArgumentParser.parse_args

    def recorded(self, *args, **kwargs):
        parsers.append(self)
        return parse_args(self, *args, **kwargs)

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", recorded)
    monkeypatch.setattr(sys, "argv", [str(demo), "--help"])
    with pytest.raises(SystemExit) as exited:
        runpy.run_path(str(demo), run_name="__main__")
    assert exited.value.code == 0
    (parser,) = parsers
    paragraph = ast.get_docstring(ast.parse(demo.read_text())).split("\n\n")[0]
    description = " ".join(parser.description.split())
    assert description == " ".join(paragraph.split())
    assert description[0].isupper() and description.endswith("."), description
    silent = [a.option_strings[0] for a in parser._actions if not (a.help or "").strip()]
    assert not silent, f"options without help: {silent}"
    assert " ".join(paragraph.split()) in " ".join(capsys.readouterr().out.split())
