"""Scenes: validation errors, effect selection, TOML round trip, CLI."""

import json

import pytest
from mpi4py import MPI

from xfem_contact import cli
from xfem_contact.scene import bundled_scenes, load_scene
from xfem_contact.simulate import build, run


def base(**interface):
    """A small valid scene dict; ``interface`` entries add one interface."""
    data = {
        "scene": {"name": "t"},
        "mesh": {"corners": [[0, 0], [1, 1]], "cells": [6, 6]},
        "materials": {"m": {"E": 100e6, "nu": 0.0}},
        "loads": [
            {"part": "bottom", "type": "displacement", "value": [0.0, 0.0]},
            {"part": "top", "type": "pressure", "value": 1.0},
        ],
    }
    if interface:
        data["interfaces"] = [{"shape": "circle", "centre": [0.5, 0.5], "radius": 0.2, **interface}]
    return data


@pytest.mark.parametrize(
    "law, multipliers, tangential, solver",
    [
        (None, 0, False, "KSP"),
        ("free", 0, False, "KSP"),
        ("bonded", 2, False, "KSP"),
        ("frictionless", 1, False, "SNES"),
        ("coulomb", 2, True, "SNES"),
        ("sticking", 2, True, "SNES"),
    ],
)
def test_only_named_effects_are_built(law, multipliers, tangential, solver):
    data = base(law=law, friction=0.5) if law else base()
    if law in ("frictionless", "coulomb", "sticking", "free"):
        # keep the inclusion in place: fix the plate fully, press the inclusion through it
        data["loads"] = [
            {"part": "boundary", "type": "displacement", "value": [0.0, 0.0]},
            {"type": "body_force", "value": [0.0, -1e3], "side": -1},
        ]
    problem, effects = build(load_scene(data))
    assert effects["multipliers"] == multipliers
    assert effects["tangential_multiplier"] == tangential
    assert effects["solver"].startswith(solver)
    assert effects["cut"] == (law is not None) and effects["enrichment"] == (law is not None)
    assert effects["pairing"] is False
    if law is None:
        assert not hasattr(problem, "cut")  # plain DOLFINx elasticity: nothing cut
    else:
        assert problem.space.multiplier_components == multipliers


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d.update(colour="red"), "Unknown key"),
        (lambda d: d["mesh"].update(cell="hexagon"), "mesh.cell"),
        (lambda d: d["materials"]["m"].update(E=-1.0), "Young's modulus"),
        (lambda d: d["materials"]["m"].pop("nu"), "needs"),
        (lambda d: d.update(materials={}), "no material"),
        (
            lambda d: d["loads"].append({"part": "roof", "type": "pressure", "value": 1}),
            "no such boundary part",
        ),
        (
            lambda d: d["loads"].append({"part": "top", "type": "gravity", "value": 1}),
            "loads\\[2\\].type",
        ),
        (lambda d: d["loads"].append({"part": "top", "type": "pressure"}), "needs a value"),
        (
            lambda d: d.update(interfaces=[{"shape": "circle", "law": "glue"}]),
            "interfaces\\[0\\].law",
        ),
        (lambda d: d.update(interfaces=[{"shape": "blob"}]), "interfaces\\[0\\].shape"),
        (
            lambda d: d.update(interfaces=[{"shape": "circle", "inside": "steel"}]),
            "no such material",
        ),
        (
            lambda d: d.update(interfaces=[{"shape": "expression", "expression": "os.system(1)"}]),
            "unknown names",
        ),
        (lambda d: d.update(parts={"p": {"where": "x +"}}), "Cannot read"),
        (lambda d: d["mesh"].update(kind="sphere"), "mesh.kind"),
        (
            lambda d: d["loads"].append({"part": "inner", "type": "pressure", "value": 1}),
            "no such boundary part",
        ),
    ],
)
def test_validation_errors_name_the_problem(change, message):
    data = base()
    change(data)
    with pytest.raises(ValueError, match=message):
        load_scene(data)


def test_large_kinematics_refused_clearly():
    with pytest.raises(NotImplementedError, match="not available yet"):
        load_scene(base(law="frictionless", kinematics="large"))


def test_level_set_that_never_crosses_is_refused():
    data = base(law="bonded")
    data["interfaces"][0]["centre"] = [5.0, 5.0]
    with pytest.raises(ValueError, match="never crosses"):
        build(load_scene(data))


def test_bundled_scenes_load():
    names = bundled_scenes()
    assert {
        "case1_straight_interface",
        "case2_sticking_inclusion",
        "bonded_inclusion",
        "hydrostatic_frictionless",
        "plain_plate",
        "elliptic_inclusion_shear",
        "case3_annulus_no_rotation",
    } <= set(names)
    for path in names.values():
        load_scene(path)


@pytest.mark.mpi
def test_cli_run_and_summary(tmp_path_factory):
    """TOML -> scene -> run -> summary.json, on 1 or 2 ranks (CLI in-process)."""
    out = MPI.COMM_WORLD.bcast(
        str(tmp_path_factory.mktemp("run")) if MPI.COMM_WORLD.rank == 0 else None, root=0
    )
    assert cli.main(["run", "case1_straight_interface", "--out", out, "--quiet"]) == 0
    MPI.COMM_WORLD.barrier()
    summary = json.loads((__import__("pathlib").Path(out) / "summary.json").read_text())
    assert summary["effects"]["solver"].startswith("KSP")
    assert summary["fields"] == ["u_minus", "u_plus"]
    assert summary["dofs"]["enriched"] == 2 * 3 * 41
    assert summary["ranks"] == MPI.COMM_WORLD.size


def test_run_contact_scene_reports_newton():
    summary = run(load_scene(bundled_scenes()["hydrostatic_frictionless"]), out=None, log=None)
    assert summary["effects"]["solver"].startswith("SNES")
    assert summary["iterations"] <= 10
    assert summary["contact_status"]["contact"] > 0
