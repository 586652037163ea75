"""Scenes with a crack: the [[cracks]] table, its level sets, its errors and its outputs."""

import json
import math
import pathlib

import xfem_contact  # noqa: F401  (before dolfinx)

# isort: split
import numpy as np
import pytest
from mpi4py import MPI
from test_scenes import to_toml

from xfem_contact.geometry.crack_paths import arc, polyline
from xfem_contact.scenes import cli
from xfem_contact.scenes.builder import build
from xfem_contact.scenes.scene import bundled_scenes, load_scene

SIGMA = 1e6


def edge_crack(cells=(12, 24), **crack) -> dict:
    """A plate 1 x 2 m with an edge crack of length 0.41 m from the left side, pulled by
    SIGMA on top and bottom; ``crack`` entries change the crack's table."""
    table = {"shape": "segment", "points": [[-0.1, 1.013], [0.41, 1.013]], **crack}
    if table["shape"] in ("arc", "expression"):
        table.pop("points")
    held = [([0.0, 0.0], 0), ([0.0, 0.0], 1), ([1.0, 0.0], 1)]
    return {
        "scene": {"name": "edge"},
        "mesh": {"corners": [[0, 0], [1, 2]], "cells": list(cells), "cell": "triangle"},
        "materials": {"steel": {"E": 210e9, "nu": 0.3}},
        "cracks": [table],
        "loads": [
            {"part": "top", "type": "traction", "value": [0.0, SIGMA]},
            {"part": "bottom", "type": "traction", "value": [0.0, -SIGMA]},
        ]
        + [
            {"type": "point_displacement", "point": p, "component": c, "value": 0.0}
            for p, c in held
        ],
    }


def test_paths_are_signed_distances():
    """phi: the distance to the (extended) curve, negative on its right; psi: along it
    beyond the nearer end, 0 at the tips; an extended end carries the crack on."""
    x = np.array([[0.5, 1.5, -0.5, 0.5], [0.2, -0.1, 0.3, -0.4]])
    phi, psi = polyline([[0, 0], [1, 0]]).levelsets()
    assert np.allclose(phi(x), [0.2, -0.1, 0.3, -0.4])
    assert np.allclose(psi(x), [-0.5, 0.5, 0.5, -0.5])
    phi, psi = polyline([[0, 0], [1, 0]]).levelsets((1.0, 0.0))  # runs on 1 m before 0
    assert np.allclose(psi(x), [-0.5, 0.5, -0.5, -0.5])  # x = -0.5 is on the crack now
    bent = polyline([[0, 0], [1, 0], [1, 1]])
    y = np.array([[1.5, 0.9, 1.2], [-0.1, 0.5, 1.5]])  # the corner, the 2nd leg, beyond
    phi, psi = bent.levelsets()
    assert np.allclose(phi(y), [-math.hypot(0.5, 0.1), 0.1, -0.2])
    assert np.allclose(psi(y), [-1.0, -0.5, 0.5]) and bent.length == 2.0
    quarter = arc([0, 0], 1.0, [0.0, math.pi / 2])
    phi, psi = quarter.levelsets()
    z = np.array([[0.9, 0.0, -1.0], [0.0, 0.5, 0.0]])
    assert np.allclose(phi(z), [0.1, 0.5, 0.0]) and np.allclose(psi(z), [0.0, 0.0, math.pi / 2])
    assert np.allclose(quarter.tangents, [[0, -1], [-1, 0]], atol=1e-15)


@pytest.mark.parametrize(
    "crack",
    [
        {"shape": "polyline", "points": [[-0.1, 1.013], [0.2, 1.013], [0.41, 1.05]]},
        {"shape": "arc", "centre": [-0.1, 0.513], "radius": 0.5, "angles_deg": [90, 40]},
        {"shape": "expression", "phi": "y - 1.013", "psi": "x - 0.41", "law": "frictionless"},
    ],
    ids=["polyline", "arc", "expression"],
)
def test_crack_shapes_load_and_cut(crack):
    """Each shape loads, and its cut has one tip inside the plate."""
    scene = load_scene(edge_crack(**crack))
    assert scene.cracks[0].shape == crack["shape"] and scene.cracks[0].law == crack.get(
        "law", "free"
    )
    problem, effects = build(scene)
    assert effects["crack"]["tips"] == 1 and effects["interfaces"] == ["crack"]
    (tip,) = problem.cut.crack.tips
    assert 0.2 < tip[0] < 0.43 and 0.8 < tip[1] < 1.1


BAD_CRACKS = {
    "3-point segment": (
        {"points": [[0, 1], [0.2, 1], [0.3, 1]]},
        "cracks[0].points: a segment has 2 points, got 3 (use shape 'polyline')",
    ),
    "coincident points": (
        {"shape": "polyline", "points": [[0, 1], [0, 1]]},
        "cracks[0].points: points 0 and 1 coincide",
    ),
    "full turn": (
        {"shape": "arc", "centre": [0.5, 1], "radius": 0.2, "angles_deg": [0, 360]},
        "cracks[0].angles_deg: the sweep |end - start| must be in (0, 360) degrees",
    ),
    "unknown law": ({"law": "glue"}, "cracks[0].law: string 'glue' is not valid; choose one of"),
    "coulomb": ({"law": "coulomb"}, "cracks[0].friction: required for law 'coulomb'"),
    "option": ({"friction": 0.3}, "cracks[0].friction: is not an option of law 'free'"),
    "unknown key": ({"tip": [0, 0]}, "cracks[0].tip: unknown key; valid: ['name', 'shape'"),
    "ring": ({"rings": [[0.2, 0.1]]}, "cracks[0].rings[0]: r_inf must be < r_sup"),
    "tip radius": ({"tip_radius": -1.0}, "cracks[0].tip_radius: must be > 0.0"),
    "material": ({"material": "glass"}, "cracks[0].material: 'glass': no such material"),
    "reference": ({"reference_K": [1e6]}, "cracks[0].reference_K: expected a list of 2 entries"),
    "reference value": ({"reference_K": [1e6, "x"]}, "cracks[0].reference_K[1]: expected a"),
    "source alone": (
        {"reference_source": "Tada"},
        "cracks[0].reference_source: a source needs reference_K = [K_I, K_II]",
    ),
    "expression": (
        {"shape": "expression", "phi": "y - 1"},
        "cracks[0].psi: required for shape 'expression' (its parameters: phi, psi)",
    ),
}


@pytest.mark.parametrize("change, start", BAD_CRACKS.values(), ids=BAD_CRACKS)
def test_bad_cracks_are_one_line_naming_the_key(change, start):
    data = edge_crack(**change)
    with pytest.raises(ValueError) as error:
        load_scene(data)
    assert str(error.value).startswith(start) and "\n" not in str(error.value)


def two_cracks(inner=((0.3013, 1.5013), (0.7013, 1.5013)), **crack) -> dict:
    """The edge-crack plate with its crack ``edge`` at y = 0.5013 and a second, ``inner``
    crack (a segment, rings shared)."""
    data = edge_crack(points=[[-0.1, 0.5013], [0.41, 0.5013]], name="edge", rings=[[0.12, 0.25]])
    data["cracks"].append(
        {"shape": "segment", "points": [list(p) for p in inner], "name": "inner"}
        | {"rings": [[0.12, 0.25]], **crack}
    )
    return data


SHARED_KEYS = {
    "name": ({"name": "edge"}, "cracks[1].name: 'edge' is the name of cracks[0] too"),
    "material": ({"material": "glass"}, "cracks[1].material: the cracks of a scene share"),
    "rings": ({"rings": [[0.1, 0.2]]}, "cracks[1].rings: the cracks of a scene share one rings"),
    "tip radius": ({"tip_radius": 0.3}, "cracks[1].tip_radius: the cracks of a scene share"),
}


@pytest.mark.parametrize("change, start", SHARED_KEYS.values(), ids=SHARED_KEYS)
def test_several_cracks_share_one_body(change, start):
    data = two_cracks(**change)
    data["materials"]["glass"] = {"E": 70e9, "nu": 0.2}
    with pytest.raises(ValueError) as error:
        load_scene(data)
    assert str(error.value).startswith(start) and "\n" not in str(error.value)


def with_inclusion(**interface) -> dict:
    """The edge-crack plate (crack at y = 0.5013) with a stiff bonded circular inclusion."""
    data = edge_crack(points=[[-0.1, 0.5013], [0.41, 0.5013]], rings=[[0.12, 0.25]])
    data["materials"]["stiff"] = {"E": 2100e9, "nu": 0.3}
    circle = {"shape": "circle", "centre": [0.5013, 1.5013], "radius": 0.2}
    data["interfaces"] = [circle | {"law": "bonded", "inside": "stiff", "name": "inc"}]
    data["interfaces"][0].update(interface)
    return data


INTERFACE_KEYS = {
    "outside": ({"outside": "stiff"}, "interfaces[0].outside: 'stiff': the cracks lie in"),
    "kinematics": ({"kinematics": "large"}, "interfaces[0].kinematics: 'large': with cracks"),
    "name": ({"name": "crack"}, "interfaces[0].name: 'crack' names a crack too"),
}


@pytest.mark.parametrize("change, start", INTERFACE_KEYS.values(), ids=INTERFACE_KEYS)
def test_interfaces_among_cracks_share_the_body(change, start):
    with pytest.raises(ValueError) as error:
        load_scene(with_inclusion(**change))
    assert str(error.value).startswith(start) and "\n" not in str(error.value)


def test_crack_and_interface_run(tmp_path, capsys):
    """A crack and a closed interface in one scene: K of the crack, the interface's
    samples; an interface the crack enters: exit 2, one line naming both."""
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(with_inclusion()))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    (tip,) = summary["cracks"]["crack"]["tips"]
    assert np.allclose(tip["position"], [0.41, 0.5013])
    assert summary["effects"]["interfaces"] == ["crack", "inc"]
    assert "inc" in summary["interfaces"]
    path.write_text(to_toml(with_inclusion(centre=[0.3, 0.5013], radius=0.15)))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out2"), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    start = f"error: {path}: cracks[0]: crack 'crack' enters the inside of interface 'inc'"
    assert len(err) == 1 and err[0].startswith(start), err


def test_two_cracks_run_K_and_lips_per_crack(tmp_path):
    """Two cracks in a scene: the run writes each crack's tips (one for the edge crack, two
    for the inner one) and lips."""
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(two_cracks()))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())["cracks"]
    assert list(summary) == ["edge", "inner"]
    (edge,) = summary["edge"]["tips"]
    assert np.allclose(edge["position"], [0.41, 0.5013])
    inner = sorted(tip["position"][0] for tip in summary["inner"]["tips"])
    assert np.allclose(inner, [0.3013, 0.7013])
    for tip in summary["inner"]["tips"]:  # a central crack of 0.4 m in a 1 m wide plate
        assert 0.9e6 < tip["rings"][0]["K_I"] < 1.0e6  # 0.94e6, 0.88e6 in a plate alone
    s = np.array(summary["inner"]["lips"]["s"])
    assert s.min() >= 0 and s.max() <= 0.4 + 1e-9
    assert {"lips_edge.png", "lips_inner.png"} <= {p.name for p in (tmp_path / "out").iterdir()}


def test_crossing_cracks_exit_2_one_line(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(two_cracks(inner=((0.2, 0.3), (0.25, 0.9)))))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    start = f"error: {path}: cracks[1]: cracks 'edge' and 'inner' come within"
    assert len(err) == 1 and err[0].startswith(start), err
    assert err[0].endswith("touching or crossing cracks are not handled")


BUILD_ERRORS = {
    "outside": (
        {"points": [[2.0, 1.013], [3.0, 1.013]]},
        "cracks[0].points: no end of the crack lies inside the body",
    ),
    "through": (
        {"points": [[-0.1, 1.013], [1.1, 1.013]]},
        "cracks[0].points: no end of the crack lies inside the body",
    ),
    "arc outside": (
        {"shape": "arc", "centre": [5, 5], "radius": 0.5, "angles_deg": [0, 90]},
        "cracks[0].angles_deg: no end of the crack lies inside the body",
    ),
    "expression outside": (
        {"shape": "expression", "phi": "y - 1.013", "psi": "x + 5"},
        "cracks[0]: The crack's tangential level set psi never changes sign on the mesh",
    ),
    "rings": ({"rings": [[0.01, 0.2]]}, "cracks[0].rings: ring r_inf = 0.01 m does not cover"),
}


@pytest.mark.parametrize("change, start", BUILD_ERRORS.values(), ids=BUILD_ERRORS)
def test_cracks_refused_when_built_name_the_key(tmp_path, capsys, change, start):
    """Errors found on the mesh: exit 2 and one line naming the key (``run`` builds
    the problem and the rings before solving)."""
    data = edge_crack(**change)
    path = tmp_path / "scene.toml"
    path.write_text(to_toml(data))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"error: {path}: {start}"), err


def test_bundled_crack_scenes_load():
    for name in ("edge_crack_tension", "griffith_crack"):
        scene = load_scene(bundled_scenes()[name])
        assert scene.cracks and scene.cracks[0].law == "free" and scene.degree == 2


#: Tada's K_I of the edge crack of :func:`edge_crack` (a / W = 0.41, a long strip), Pa m^1/2
TADA = 2.452e6


@pytest.mark.mpi
def test_edge_crack_run_writes_K_lips_and_opened_fields(tmp_path_factory, capsys):
    """The outputs of a crack scene (1 or 2 ranks): K_I, K_II, J, G per tip and ring in
    summary.json (K_I near the handbook's 2.45 MPa m^1/2 on this coarse mesh) and printed
    as a table (units, rings by their radii, the reference and the difference, the law
    and the loads), the lips opening to the tip, lips.png and the lips' grid with the
    opened displacement."""
    out = MPI.COMM_WORLD.bcast(
        str(tmp_path_factory.mktemp("crack")) if MPI.COMM_WORLD.rank == 0 else None, root=0
    )
    path = pathlib.Path(out) / "scene.toml"
    source = "Tada, a long strip"
    if MPI.COMM_WORLD.rank == 0:
        data = edge_crack(reference_K=[TADA, 0.0], reference_source=source)
        data["solver"] = {"load_steps": 2}
        path.write_text(to_toml(data))
    MPI.COMM_WORLD.barrier()
    capsys.readouterr()
    assert cli.main(["run", str(path), "--out", out, "--no-progress"]) == 0
    printed = capsys.readouterr().out.splitlines()
    MPI.COMM_WORLD.barrier()
    summary = json.loads((pathlib.Path(out) / "summary.json").read_text())
    crack = summary["cracks"]["crack"]
    assert crack["reference"] == {"K_I": TADA, "K_II": 0.0, "source": source}
    assert crack["law"] == {"law": "free"}
    (tip,) = crack["tips"]
    # K at every load step: the problem is linear, the first step's is half the last's
    steps = summary["steps"]
    assert [r["time"] for r in steps] == [0.5, 1.0] and steps[-1]["cracks"]["crack"] == [tip]
    (half,) = steps[0]["cracks"]["crack"]
    for r_half, r in zip(half["rings"], tip["rings"], strict=True):
        assert r_half["K_I"] == pytest.approx(0.5 * r["K_I"], rel=1e-9)
        assert r_half["J"] == pytest.approx(0.25 * r["J"], rel=1e-9)
    for record in steps:
        assert record["forces"]["balance_relative"] < 1e-8
    if MPI.COMM_WORLD.rank == 0:
        start = printed.index("crack 'crack': law of the lips free")
        table = printed[start:]
        loads = "traction on 'top' (0, 1e+06) Pa, traction on 'bottom' (0, -1e+06) Pa"
        assert table[1] == f"  loads: {loads}"
        assert table[2].startswith("  K in MPa m^1/2, J and G in J/m^2")
        for r, row in zip(tip["rings"], table[4:], strict=False):
            assert row.split() == [
                "0",
                f"{r['r_inf']:.4g}..{r['r_sup']:.4g}",
                f"{r['K_I'] / 1e6:.4f}",
                f"{r['K_II'] / 1e6:.4f}",
                f"{r['J']:.4g}",
                f"{r['G']:.4g}",
                f"{100 * (r['K_I'] / TADA - 1):+.2f}%",
                f"{100 * r['K_II'] / TADA:+.2f}%",
            ]
        assert table[4 + len(tip["rings"])].split()[:4] == ["0", "reference", "2.4520", "0.0000"]
        assert any(line.startswith(f"  reference: {source}") for line in table)
    assert np.allclose(tip["position"], [0.41, 1.013]) and np.allclose(tip["direction"], [1, 0])
    assert len(tip["rings"]) >= 1  # those of the default rings that fit
    for ring in tip["rings"]:
        assert set(ring) == {"r_inf", "r_sup", "K_I", "K_II", "J", "G"}
        assert ring["K_I"] == pytest.approx(2.452e6, rel=0.05)
        assert abs(ring["K_II"]) < 0.02 * ring["K_I"]
        assert ring["J"] == pytest.approx(ring["G"], rel=0.05)
    lips = crack["lips"]
    assert {"x", "y", "s", "opening", "slip"} <= set(lips) and "lambda_n" not in lips
    s, opening = np.array(lips["s"]), np.array(lips["opening"])
    assert s.min() >= 0.1 - 1e-9 and s.max() <= 0.51 + 1e-9  # the part inside the plate
    assert np.all(opening > 0) and opening[np.argmax(s)] < 0.2 * opening.max()
    if MPI.COMM_WORLD.rank == 0:
        names = {p.name for p in pathlib.Path(out).iterdir()}
        assert {"lips.png", "result.png", "displacement.bp", "summary.json"} <= names
        assert {"result.pvd", "interface.pvd", "result_steps"} <= names
        assert any(n.startswith("result") and n.endswith(".vtu") for n in names)
