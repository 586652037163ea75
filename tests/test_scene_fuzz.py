"""Seeded random mutations of the bundled scenes: each validates or is one clear line.

A mutation deletes a key, changes a value's type, puts a number out of range or makes
it non-finite, adds an unknown key, puts a huge power in an expression or breaks the
TOML syntax. :func:`load_scene` must then return a scene (nothing is built or solved
here) or raise a ``ValueError``/``NotImplementedError`` whose message is one line
``KEY: message``; where the mutation names a key, the error names that key (or one
above or below it). Never another exception, a hang (a per-case timeout) or a
compiler error (nothing reaches FFCx). A few refused cases go through the command
line in subprocesses: exit code 2 and exactly the one line ``error: FILE: message``.
"""

import faulthandler
import math
import os
import pathlib
import random
import re
import shutil
import signal
import subprocess
import sys
import time
import tomllib

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import pytest
from test_scenes import to_toml

from xfem_contact.scenes.scene import bundled_scenes, load_scene

CASES = 200
SECONDS_PER_CASE = 5.0
ROOT = pathlib.Path(__file__).resolve().parents[1]
SCENES = bundled_scenes()
FOLDER = next(iter(SCENES.values())).parent
TEXTS = {name: path.read_text() for name, path in SCENES.items()}
KINDS = ("delete", "type", "range", "nonfinite", "unknown", "power", "syntax")
#: A key path (``interfaces[0].radius``, ``materials.'a b'.E``) or a place in the file
_PART = r"(?:[A-Za-z0-9_-]+|'[^']*'|\"[^\"]*\")"
KEY = re.compile(rf"{_PART}(?:\.{_PART}|\[\d+\])*|line \d+, column \d+|end of document|file")
POWERS = ("9**9**9*x", "x**(9**9**9)", "(x + 1)**1e9", "2**x", "x" + "**16" * 40, "10**400 * x")


def key_of(path: tuple) -> str:
    """The key path of ``path`` as the errors write it."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            name = part if re.fullmatch(r"[A-Za-z0-9_-]+", part) else repr(part)
            text = f"{text}.{name}" if text else name
    return text


def walk(value, path=()):
    """Every (path, value) below ``value`` (itself included)."""
    yield path, value
    if isinstance(value, dict | list):
        for key, child in value.items() if isinstance(value, dict) else enumerate(value):
            yield from walk(child, (*path, key))


def at(data, path):
    for key in path:
        data = data[key]
    return data


def is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def other_type(rng: random.Random, value):
    """A value of another type than ``value`` (bool, int, float, str, list, table)."""
    candidates = [True, 7, 0.5, "text", [1.0, 2.0, 3.0], {"k": 1}, []]
    return rng.choice([c for c in candidates if type(c) is not type(value)])


def mutate(case: int):
    """Case ``case``: (scene name, kind, data dict or TOML text, the mutated key path)."""
    rng = random.Random(case)
    name, kind = rng.choice(sorted(SCENES)), KINDS[case % len(KINDS)]
    if kind == "syntax":
        text = TEXTS[name]
        spots = [m.start() for m in re.finditer(r"[=\]\[\"]", text)]
        where = rng.choice(spots)
        edits = (
            lambda: text[:where] + text[where + 1 :],  # drop one = [ ] or "
            lambda: text[:where] + '"' + text[where:],  # an unterminated string
            lambda: text[:where] + " = = " + text[where:],
            lambda: text[: rng.randrange(len(text))],  # cut short
            lambda: text + "\n" + text.split("\n\n")[0],  # a table given twice
        )
        return name, kind, rng.choice(edits)(), None
    data = tomllib.loads(TEXTS[name])
    every = [(p, v) for p, v in walk(data) if p]
    if kind == "delete":
        path, _ = rng.choice(every)
        del at(data, path[:-1])[path[-1]]
    elif kind == "type":
        path, value = rng.choice(every)
        at(data, path[:-1])[path[-1]] = other_type(rng, value)
    elif kind in ("range", "nonfinite"):
        path, _ = rng.choice([(p, v) for p, v in every if is_number(v)])
        range_values = (-1, 0, -0.5, 1e30, -1e30, 10**30)
        values = range_values if kind == "range" else (math.inf, -math.inf, math.nan)
        at(data, path[:-1])[path[-1]] = rng.choice(values)
    elif kind == "unknown":
        tables = [(p, v) for p, v in walk(data) if isinstance(v, dict)]
        path, table = rng.choice(tables)
        table["bogus_key"] = 1
        path = (*path, "bogus_key")
    else:  # a huge power where an expression goes: a load value (entry) or a part
        places = [p for p, v in every if "value" in p and not isinstance(v, list)]
        places += [p for p, _ in every if p[-1] in ("where", "expression")]
        path = rng.choice(places)
        at(data, path[:-1])[path[-1]] = rng.choice(POWERS)
    return name, kind, data, path


class Hang(BaseException):
    """A case over its time (not an Exception: nothing in load_scene may catch it)."""


def _alarm(signum, frame):
    raise Hang()


def validate(case: int, tmp: pathlib.Path):
    """(name, kind, path, error message or None) of case ``case``, timed out per case."""
    name, kind, source, path = mutate(case)
    if isinstance(source, str):
        file = tmp / f"case{case}.toml"
        file.write_text(source)
        source = file
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, SECONDS_PER_CASE)  # a hang in Python code
    faulthandler.dump_traceback_later(4 * SECONDS_PER_CASE, exit=True)  # ... or in C code
    try:
        load_scene(source, folder=FOLDER)
        return name, kind, path, None
    except (ValueError, NotImplementedError) as error:
        return name, kind, path, str(error)
    except Hang:
        pytest.fail(f"case {case} ({kind} of {name} at {path}) takes over {SECONDS_PER_CASE} s")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        faulthandler.cancel_dump_traceback_later()
        signal.signal(signal.SIGALRM, previous)


def on_one_branch(key: str, path: tuple) -> bool:
    """Whether the error's ``key`` is the mutated key, one above it or one below it."""
    mutated = key_of(path)
    return any(
        a == b or a.startswith(b + ".") or a.startswith(b + "[")
        for a, b in ((key, mutated), (mutated, key))
    )


def test_mutated_scenes_validate_or_fail_on_one_line(tmp_path):
    start, problems, outcomes = time.perf_counter(), [], []
    for case in range(CASES):
        try:
            name, kind, path, message = validate(case, tmp_path)
        except Exception as error:  # any other exception type is a failure of the case
            problems.append(f"case {case}: {type(error).__name__}: {error}")
            continue
        outcomes.append((kind, message is None))
        where = f"case {case} ({kind} of {name} at {path and key_of(path)}): {message!r}"
        if message is None:
            # never valid: a non-finite number, a huge power, an unknown key (but PETSc's)
            if kind in ("nonfinite", "power") or (kind == "unknown" and "petsc" not in path):
                problems.append(f"{where}: accepted")
            continue
        key = message.split(": ", 1)[0]
        if "\n" in message or ": " not in message or not KEY.fullmatch(key):
            problems.append(f"{where}: not one line 'KEY: message'")
        elif kind in ("type", "range", "nonfinite", "unknown", "power"):
            if not on_one_branch(key, path):
                problems.append(f"{where}: does not name the mutated key")
        if kind == "power" and not re.search(r"exponent|finite|expected a number", message):
            problems.append(f"{where}: does not say why the power is refused")
    seconds = time.perf_counter() - start
    print(f"{CASES} mutated scenes validated in {seconds:.1f} s")
    assert not problems, "\n".join(problems)
    refused = {kind for kind, valid in outcomes if not valid}
    assert refused == set(KINDS), f"mutations never refused: {set(KINDS) - refused}"
    assert 0.05 * CASES < sum(valid for _, valid in outcomes) < 0.8 * CASES


def test_refused_mutations_are_one_line_and_exit_2_on_the_command_line(tmp_path):
    """The first refused case of 5 kinds, as TOML files run by the CLI in subprocesses:
    exit code 2, stderr exactly ``error: FILE: `` and load_scene's message, no traceback."""
    shutil.copy(FOLDER / "plate_with_hole.geo", tmp_path)  # beside the scene files
    chosen = {}
    for case in range(CASES):
        name, kind, source, path = mutate(case)
        if kind in chosen or kind not in ("syntax", "nonfinite", "power", "type", "delete"):
            continue
        file = tmp_path / f"{kind}.toml"
        file.write_text(source if isinstance(source, str) else to_toml(source))
        try:
            load_scene(file)
        except (ValueError, NotImplementedError) as error:
            chosen[kind] = (file, str(error))
    assert len(chosen) == 5, chosen.keys()
    env = os.environ | {"PYTHONPATH": str(ROOT)}
    runs = []
    for kind, (file, message) in chosen.items():
        command = [sys.executable, "-m", "xfem_contact.scenes.cli", "run", str(file)]
        command += ["--out", str(tmp_path / f"out_{kind}")]
        process = subprocess.Popen(command, env=env, text=True, stdout=-1, stderr=-1)
        runs.append((kind, file, message, process))
    for kind, file, message, process in runs:
        out, err = process.communicate(timeout=120)
        assert process.returncode == 2, (kind, out, err)
        assert err.splitlines() == [f"error: {file}: {message}"], (kind, err)
        assert out == "" and not (tmp_path / f"out_{kind}").exists()
