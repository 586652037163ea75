"""Scenes: validation errors, effect selection, TOML round trip, CLI."""

import json
import math

import xfem_contact

# isort: split
import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from xfem_contact.cases.rotation import svk_annulus_pressure
from xfem_contact.fem.cutmesh import CutMesh
from xfem_contact.scenes import cli
from xfem_contact.scenes.run import build, levelset, run
from xfem_contact.scenes.scene import bundled_scenes, load_scene
from xfem_contact.solvers.log_lines import lines_to
from xfem_contact.solvers.newton import NewtonFailure


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


def to_toml(data: dict) -> str:
    """A scene dict as TOML text: one ``key = value`` line per table (inline tables)."""

    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float) and not math.isfinite(v):
            return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
        if isinstance(v, int | float):
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list | tuple):
            return "[" + ", ".join(map(value, v)) + "]"
        return "{" + ", ".join(f"{json.dumps(k)} = {value(x)}" for k, x in v.items()) + "}"

    return "".join(f"{json.dumps(key)} = {value(v)}\n" for key, v in data.items())


def coulomb_friction(law: str) -> dict:
    """The friction key a law takes: Coulomb's only (any other law refuses it)."""
    return {"friction": 0.5} if law == "coulomb" else {}


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
    data = base(law=law, **coulomb_friction(law)) if law else base()
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
        assert problem.cut is None and problem.laws == {}  # plain elasticity: nothing cut
    else:
        assert problem.space.multiplier_components == multipliers


@pytest.mark.parametrize("law", ["bonded", "sticking"])
def test_multiplier_degree_makes_the_multiplier_p2(law):
    data = base(law=law, multiplier_degree=2)
    problem, effects = build(load_scene(data))
    assert problem.law().multiplier_degree == 2
    assert effects["laws"]["interface0"]["multiplier_degree"] == 2
    element = problem.space.W.sub(2).ufl_element()
    assert element.embedded_superdegree == 2


def interface(**table) -> dict:
    """A scene change: the interfaces are one given by its table."""
    return lambda d: d.update(interfaces=[table])


def circle(**change) -> dict:
    """A scene change: one circle (centre, radius) with ``change`` (None deletes a key)."""
    table = {"shape": "circle", "centre": [0.5, 0.5], "radius": 0.2} | change
    return interface(**{k: v for k, v in table.items() if v is not None})


def add_load(**table):
    return lambda d: d["loads"].append(table)


def set_in(*path, value=None, delete=False):
    """A scene change: set (or delete) the value at ``path`` (keys and list indices)."""

    def change(d):
        for key in path[:-1]:
            d = d[key]
        if delete:
            del d[path[-1]]
        else:
            d[path[-1]] = value

    return change


def one_line_error(data, key, fragment, error=ValueError, folder=None):
    """The scene's error: of type ``error``, one line ``KEY: message`` holding ``fragment``."""
    with pytest.raises(error) as raised:
        load_scene(data, folder=folder)
    message = str(raised.value)
    assert message.splitlines() == [message], message
    assert message.startswith(f"{key}: "), message
    assert fragment in message, message
    return message


BAD_SCENES = {
    "unknown top-level key": (set_in("colour", value="red"), "colour", "unknown key; valid: ["),
    "unknown interface key": (circle(colour=1), "interfaces[0].colour", "unknown key"),
    "cell choice": (
        set_in("mesh", "cell", value="hexagon"),
        "mesh.cell",
        "choose one of ['quadrilateral', 'triangle']",
    ),
    "negative E": (set_in("materials", "m", "E", value=-1.0), "materials.m.E", "must be > 0.0"),
    "nu out of range": (set_in("materials", "m", "nu", value=0.5), "materials.m.nu", "(-1.0, 0.5)"),
    "E missing": (set_in("materials", "m", "E", delete=True), "materials.m.E", "required"),
    "E nan": (set_in("materials", "m", "E", value=float("nan")), "materials.m.E", "got nan"),
    "no material": (set_in("materials", value={}), "materials", "no material"),
    "material not a table": (
        set_in("materials", "m", value="steel"),
        "materials.m",
        "expected a table, got string 'steel'",
    ),
    "unknown part": (
        add_load(part="roof", type="pressure", value=1),
        "loads[2].part",
        "'roof': no such boundary part; known: ['bottom', 'boundary', 'left', 'right', 'top']",
    ),
    "annulus part on a rectangle": (
        add_load(part="inner", type="pressure", value=1),
        "loads[2].part",
        "no such boundary part",
    ),
    "load type": (
        add_load(part="top", type="gravity", value=1),
        "loads[2].type",
        "choose one of ['pressure',",
    ),
    "load without value": (
        add_load(part="top", type="pressure"),
        "loads[2].value",
        "required for a 'pressure' load",
    ),
    "inf load": (set_in("loads", 1, "value", value=float("inf")), "loads[1].value", "got inf"),
    "-inf load entry": (
        set_in("loads", 0, "value", 1, value=float("-inf")),
        "loads[0].value[1]",
        "must be a finite number, got -inf",
    ),
    "string where a number goes": (
        set_in("loads", 0, "value", value=[0.0, "zero"]),
        "loads[0].value[1]",
        "unknown name 'zero'",
    ),
    "traction given as a scalar": (
        add_load(part="top", type="traction", value=1.0),
        "loads[2].value",
        "expected a list of 2 entries, got number 1.0",
    ),
    "displacement expression without component": (
        set_in("loads", 0, "value", value="x"),
        "loads[0].value",
        "needs component",
    ),
    "body force on a part": (
        add_load(part="top", type="body_force", value=[0, 1]),
        "loads[2].part",
        "is not a key of a 'body_force' load (its keys: value, side, path)",
    ),
    "side of a displacement": (
        set_in("loads", 0, "side", value=1),
        "loads[0].side",
        "is not a key of a 'displacement' load",
    ),
    "point displacement without point": (
        add_load(type="point_displacement", component=0, value=0.0),
        "loads[2].point",
        "required",
    ),
    "component True": (
        add_load(type="point_displacement", point=[0, 0], component=True, value=0.0),
        "loads[2].component",
        "boolean True is not valid; choose one of [0, 1]",
    ),
    "law choice": (circle(law="glue"), "interfaces[0].law", "choose one of ['free', 'bonded'"),
    "shape choice": (interface(shape="blob"), "interfaces[0].shape", "choose one of ['circle',"),
    "shape missing": (interface(radius=0.2), "interfaces[0].shape", "required"),
    "circle without radius": (
        circle(radius=None),
        "interfaces[0].radius",
        "required for shape 'circle' (its parameters: centre, radius)",
    ),
    "circle without centre": (circle(centre=None), "interfaces[0].centre", "required"),
    "zero radius": (circle(radius=0.0), "interfaces[0].radius", "must be > 0.0, got 0.0"),
    "radius a string": (
        circle(radius="big"),
        "interfaces[0].radius",
        "expected a number, got string 'big'",
    ),
    "centre of three": (
        circle(centre=[0.5, 0.5, 0.5]),
        "interfaces[0].centre",
        "expected a list of 2 entries",
    ),
    "ellipse without axes": (
        interface(shape="ellipse", centre=[0.5, 0.5]),
        "interfaces[0].axes",
        "required for shape 'ellipse' (its parameters: centre, axes, angle, angle_deg)",
    ),
    "negative ellipse axis": (
        interface(shape="ellipse", centre=[0.5, 0.5], axes=[0.2, -0.1]),
        "interfaces[0].axes[1]",
        "must be > 0.0",
    ),
    "zero normal": (
        interface(shape="line", point=[0.5, 0.5], normal=[0, 0]),
        "interfaces[0].normal",
        "non-zero",
    ),
    "radius of a line": (
        interface(shape="half-plane", point=[0.5, 0.5], normal=[0, 1], radius=1.0),
        "interfaces[0].radius",
        "is not a parameter of shape 'half-plane' (its parameters: point, normal)",
    ),
    "expression missing": (interface(shape="expression"), "interfaces[0].expression", "required"),
    "coulomb without friction": (circle(law="coulomb"), "interfaces[0].friction", "required"),
    "negative friction": (circle(friction=-0.1), "interfaces[0].friction", "must be >= 0.0"),
    "lbb choice": (circle(lbb="magic"), "interfaces[0].lbb", "choose one of ['stabilized'"),
    "multiplier degree choice": (
        circle(multiplier_degree=3),
        "interfaces[0].multiplier_degree",
        "integer 3 is not valid; choose one of [1, 2]",
    ),
    "multiplier degree a string": (
        circle(multiplier_degree="2"),
        "interfaces[0].multiplier_degree",
        "choose one of [1, 2]",
    ),
    "multiplier degree of a free interface": (
        circle(law="free", multiplier_degree=2),
        "interfaces[0].multiplier_degree",
        "is not an option of law 'free'",
    ),
    "friction on a sticking law": (
        circle(law="sticking", friction=0.3),
        "interfaces[0].friction",
        "is not an option of law 'sticking'",
    ),
    "ellipse angle in degrees as radians": (
        interface(shape="ellipse", centre=[0.5, 0.5], axes=[0.2, 0.1], angle=30),
        "interfaces[0].angle",
        "is in radians (30 rad is more than a turn); use angle_deg",
    ),
    "ellipse angle twice": (
        interface(shape="ellipse", centre=[0.5, 0.5], axes=[0.2, 0.1], angle=0.5, angle_deg=30),
        "interfaces[0].angle_deg",
        "give the angle once",
    ),
    "missing material": (circle(inside="steel"), "interfaces[0].inside", "no such material"),
    "expression name": (
        interface(shape="expression", expression="os.system(1)"),
        "interfaces[0].expression",
        "'os.system', not a function",
    ),
    "huge power": (
        interface(shape="expression", expression="9**9**9*x"),
        "interfaces[0].expression",
        "the exponent of ** must be a number of size at most 16",
    ),
    "long expression": (
        interface(shape="expression", expression="x" + " + x" * 200),
        "interfaces[0].expression",
        "at most 500",
    ),
    "non-finite constant": (
        set_in("loads", 1, "value", value="1e300 * 1e300 * x"),
        "loads[1].value",
        "is not a finite number",
    ),
    "comparison in a load": (
        set_in("loads", 1, "value", value="x < 0.5"),
        "loads[1].value",
        "comparison",
    ),
    "part syntax": (set_in("parts", value={"p": {"where": "x +"}}), "parts.p.where", "cannot read"),
    "mesh kind": (set_in("mesh", "kind", value="sphere"), "mesh.kind", "choose one of"),
    "cells of one": (set_in("mesh", "cells", value=[6]), "mesh.cells", "a list of 2 entries"),
    "cells bool": (
        set_in("mesh", "cells", value=[6, True]),
        "mesh.cells[1]",
        "expected an integer, got boolean True",
    ),
    "cells float": (set_in("mesh", "cells", value=[6.5, 6]), "mesh.cells[0]", "an integer"),
    "inverted corners": (
        set_in("mesh", "corners", value=[[1, 1], [0, 0]]),
        "mesh.corners",
        "the second corner must lie right of and above the first",
    ),
    "radii of a rectangle": (
        set_in("mesh", "radii", value=[1, 2]),
        "mesh.radii",
        "is for mesh.kind = 'annulus', not 'rectangle'",
    ),
    "degree True": (
        set_in("discretisation", value={"degree": True}),
        "discretisation.degree",
        "choose one of [1, 2]",
    ),
    "huge quadrature degree": (
        set_in("discretisation", value={"quadrature_degree": 1000}),
        "discretisation.quadrature_degree",
        "must be in [1, 30]",
    ),
    "scene name a path": (set_in("scene", "name", value="../x"), "scene.name", "use letters"),
    "interfaces a table": (
        set_in("interfaces", value={"shape": "circle"}),
        "interfaces",
        "expected a list of tables ([[interfaces]])",
    ),
    "png yes": (set_in("outputs", value={"png": "yes"}), "outputs.png", "expected true or false"),
}


@pytest.mark.parametrize("change, key, fragment", BAD_SCENES.values(), ids=BAD_SCENES)
def test_validation_errors_are_one_line_naming_the_key(change, key, fragment):
    data = base()
    change(data)
    one_line_error(data, key, fragment)


def test_names_with_spaces_are_kept_and_quoted_in_errors():
    data = base(law="bonded", inside="soft rock")
    data["materials"]["soft rock"] = {"E": 1e9, "nu": 0.2}
    data["parts"] = {"left edge": {"where": "x < 1e-9"}}
    data["loads"].append({"part": "left edge", "type": "pressure", "value": 1.0})
    scene = load_scene(data)
    assert scene.interfaces[0].inside == "soft rock" and "soft rock" in scene.materials
    assert scene.parts == {"left edge": "x < 1e-9"}
    data["materials"]["soft rock"]["nu"] = 0.7
    one_line_error(data, "materials.'soft rock'.nu", "must be in (-1.0, 0.5), got 0.7")


LARGE_SLIDING_REFUSALS = {
    "unsupported law": (
        {"law": "sticking", "kinematics": "large"},
        "interfaces[0].law",
        "'sticking' is not available in large sliding (kinematics = 'large'); valid: "
        "('frictionless', 'coulomb', 'free', 'bonded')",
    ),
    "restriction": (
        {"law": "frictionless", "kinematics": "large", "lbb": "restriction"},
        "interfaces[0].lbb",
        "valid: ('stabilized', 'none')",
    ),
    "slave and master on one side": (
        {"law": "frictionless", "kinematics": "large", "slave": 1, "master": 1},
        "interfaces[0].master",
        "slave and master are both side 1",
    ),
    "slave in small sliding": (
        {"law": "frictionless", "slave": 1},
        "interfaces[0].slave",
        "only with kinematics = 'large'",
    ),
    "pairing of a typo": (
        {"law": "frictionless", "kinematics": "large", "pairing": "often"},
        "interfaces[0].pairing",
        "choose one of ['iterate', 'step']",
    ),
}


@pytest.mark.parametrize(
    "interface, key, fragment", LARGE_SLIDING_REFUSALS.values(), ids=LARGE_SLIDING_REFUSALS
)
def test_large_sliding_input_errors_name_the_key(interface, key, fragment):
    one_line_error(base(**interface), key, fragment)


def test_rotation_of_a_missing_part_names_the_parts():
    data = base(law="frictionless", kinematics="large")
    data["loads"].append({"part": "inner", "type": "rotation", "value": 0.1})
    one_line_error(data, "loads[2].part", "'inner': no such boundary part")


def test_bundled_rotating_inclusion_turns_a_right_angle():
    """The bundled case-3 scene: 4 load steps of pi/8, every slave point paired and
    changing master cell each step, the pressure uniform to round-off."""
    scene = load_scene(bundled_scenes()["case3_rotating_inclusion"])
    summary = run(scene, progress_bar=False)
    assert summary["effects"]["kinematics"] == "large" and summary["effects"]["pairing"]
    assert len(summary["pairing"]) == 4
    counts = [step["interface0"] for step in summary["pairing"]]
    assert all(c["unpaired"] == 0 and c["paired"] > 0 for c in counts)
    assert all(c["changed"] == c["paired"] for c in counts[1:])
    lam = np.array(summary["interface_samples"]["lambda_n"])
    reference = svk_annulus_pressure()
    assert np.abs(lam / reference - 1.0).max() < 1e-3


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
        "plate_with_hole_inclusion",
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
    assert summary["versions"] == xfem_contact.versions()  # xfem-contact, DOLFINx, FFCx, ...


def circle_without_radius() -> str:
    data = base(law="bonded")
    del data["interfaces"][0]["radius"]
    return to_toml(data)


@pytest.mark.parametrize(
    "text, line",
    [
        (
            circle_without_radius(),
            "interfaces[0].radius: required for shape 'circle' (its parameters: centre, radius)",
        ),
        (
            "[mesh\ncells = [2, 2]\n[materials.m]\nE = 1.0\nnu = 0.0\n",
            "line 1, column 6: TOML syntax error: Expected ']' at the end of a table declaration",
        ),
        (
            to_toml(base()).replace('"value" = 1.0', '"value" = 1e400'),
            "loads[1].value: must be a finite number, got inf",
        ),
        (
            to_toml(base()).replace('"value" = 1.0', '"value" = "9**9**9*x"'),
            "loads[1].value: '9**9**9*x' raises to the power '9 ** 9': the exponent of ** must "
            "be a number of size at most 16",
        ),
        (b"\xff\xfe".decode("latin-1"), "file: not UTF-8 text (byte 0: invalid start byte)"),
    ],
    ids=["missing radius", "TOML syntax", "inf", "huge power", "not UTF-8"],
)
def test_cli_bad_input_is_one_line_and_exit_2(tmp_path, capsys, text, line):
    path = tmp_path / "scene.toml"
    path.write_bytes(text.encode("latin-1" if "\xff" in text else "utf-8"))
    args = ["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]
    assert cli.main(args) == 2
    captured = capsys.readouterr()
    assert captured.err.splitlines() == [f"error: {path}: {line}"]
    assert captured.out == "" and not (tmp_path / "out").exists()
    assert cli.main([*args, "--debug"]) == 2  # the traceback too, then the same line
    err = capsys.readouterr().err.splitlines()
    assert err[0] == "Traceback (most recent call last):" and err[-1] == f"error: {path}: {line}"


def test_cli_missing_scene_file_exit_2(capsys):
    assert cli.main(["run", "nowhere.toml"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("error: nowhere.toml: no such scene file")
    assert "'plain_plate'" in err[0]  # the bundled scenes are the choices


def test_cli_scenes_show_prints_a_bundled_scene(capsys):
    """``scenes --show NAME`` prints the bundled TOML as it is; an unknown NAME: exit 2,
    one line naming every bundled scene."""
    assert cli.main(["scenes", "--show", "case2_sticking_inclusion"]) == 0
    out = capsys.readouterr().out
    path = bundled_scenes()["case2_sticking_inclusion"]
    assert out == path.read_text(encoding="utf-8") and 'law = "sticking"' in out
    assert cli.main(["scenes", "--show", "case9"]) == 2
    captured = capsys.readouterr()
    err = captured.err.splitlines()
    assert captured.out == "" and len(err) == 1 and "'case9'" in err[0]
    assert all(name in err[0] for name in bundled_scenes())


def test_cli_error_at_build_is_one_line_and_leaves_no_stale_summary(tmp_path, capsys):
    """A geometry error found when building: exit 2, and the summary.json of an earlier
    run in the folder is gone (a summary.json is always a finished run's)."""
    data = base(law="bonded")
    data["interfaces"][0]["centre"] = [5.0, 5.0]
    path, out = tmp_path / "scene.toml", tmp_path / "out"
    path.write_text(to_toml(data))
    out.mkdir()
    (out / "summary.json").write_text('{"scene": "an earlier run"}')
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.splitlines()
    # the nearest node (1, 1) lies 4 sqrt(2) - 0.2 m outside the circle, (0, 0) 5 sqrt(2) - 0.2
    assert err == [
        f"error: {path}: interfaces[0]: The interface does not cross the mesh: its level set "
        "never crosses zero (it is >= 0 at every node, from 5.45685 to 6.87107), so no node "
        "lies inside it. Move or enlarge the interface, or refine the mesh, so that it "
        "crosses the mesh"
    ]
    assert not (out / "summary.json").exists()


def circle(centre, radius) -> dict:
    return {"shape": "circle", "centre": centre, "radius": radius}


@pytest.mark.parametrize(
    "interfaces, key, fragment",
    [
        (
            [circle([0.45, 0.45], 0.01)],  # between the nodes
            "interfaces[0]",
            "so no node lies inside it. Move or enlarge",
        ),
        ([circle([0.5, 0.5], 5.0)], "interfaces[0]", "every node lies inside it. Move or shrink"),
        (
            [circle([0.25, 0.5], 0.2), circle([0.3, 0.5], 0.2)],
            "interfaces[1]",
            "overlaps interface 'i0' (mesh nodes lie inside both)",
        ),
        (
            [circle([0.25, 0.5], 0.2), {"shape": "expression", "expression": "sqrt(x - 0.5)"}],
            "interfaces[1]",
            "node(s), e.g. at x = (0, 0): give one that is finite on the whole mesh",
        ),
    ],
    ids=["between nodes", "around the mesh", "overlapping", "NaN"],
)
@pytest.mark.filterwarnings("ignore:invalid value encountered in sqrt")
@pytest.mark.mpi
def test_a_bad_interface_is_named_by_its_key(interfaces, key, fragment):
    """An interface that misses the mesh, overlaps another or is NaN: one line starting
    with its key (``interfaces[1]: ...``), saying what to do."""
    data = base(law="bonded")
    data["interfaces"] = [
        {"name": f"i{k}", "law": "bonded"} | spec for k, spec in enumerate(interfaces)
    ]
    with pytest.raises(ValueError) as raised:
        build(load_scene(data))
    text = str(raised.value)
    assert text.startswith(f"{key}: ") and fragment in text and text.splitlines() == [text], text


def test_cli_newton_failure_exit_3_with_the_iterations(tmp_path, capsys):
    path, out = tmp_path / "scene.toml", tmp_path / "out"
    path.write_text(to_toml(pressed_inclusion("coulomb", max_iterations=1, load_steps=2)))
    out.mkdir()
    (out / "summary.json").write_text('{"scene": "an earlier run"}')
    assert cli.main(["run", str(path), "--out", str(out), "--quiet"]) == 3
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith(f"error: {path}: Scene 't', load step 1/2 (time 0.5)")
    assert err[0].endswith(")") and "Newton failed (SNES reason" in err[0]
    assert err[1].startswith("  iterate  0  |F| = ") and err[2].startswith("  iterate  1")
    assert len(err) == 3 and "Traceback" not in err
    assert not (out / "summary.json").exists()


def test_write_json_is_atomic(tmp_path):
    """A failure while writing leaves the previous summary whole and no temporary file:
    a disk that fills up after 1000 bytes (a file size limit), a value JSON cannot hold."""
    import resource
    import signal

    from xfem_contact.io.output import write_json

    path = tmp_path / "summary.json"
    write_json(path, {"scene": "previous"})
    big = {"scene": "new", "samples": list(range(20000))}
    limits = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past it: OSError
    try:
        resource.setrlimit(resource.RLIMIT_FSIZE, (1000, limits[1]))
        with pytest.raises(OSError):
            write_json(path, big)
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, limits)
        signal.signal(signal.SIGXFSZ, handler)
    with pytest.raises(TypeError):
        write_json(path, big | {"bad": object()})
    assert json.loads(path.read_text()) == {"scene": "previous"}
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]
    write_json(path, {"scene": "new", "x": np.float64(1.5), "a": np.arange(2)})
    assert json.loads(path.read_text()) == {"scene": "new", "x": 1.5, "a": [0, 1]}


def test_run_contact_scene_reports_newton():
    summary = run(load_scene(bundled_scenes()["hydrostatic_frictionless"]), out=None)
    assert summary["effects"]["solver"].startswith("SNES")
    assert summary["iterations"] <= 10
    assert summary["contact_status"]["contact"] > 0


# -- load steps and solver options --------------------------------------------------------


def pressed_inclusion(law: str, **solver) -> dict:
    """A plate fixed all round, its inclusion pushed down by a body force."""
    data = base(law=law, **coulomb_friction(law))
    data["loads"] = [
        {"part": "boundary", "type": "displacement", "value": [0.0, 0.0]},
        {"type": "body_force", "value": [0.0, -1e3], "side": -1},
    ]
    if solver:
        data["solver"] = solver
    return data


def test_load_factor_scales_every_load_of_a_linear_problem():
    data = base(law="bonded")
    data["loads"].append({"part": "right", "type": "displacement", "value": 1e-4, "component": 0})
    data["loads"].append({"type": "body_force", "value": [0.0, -1e3]})
    problem, _ = build(load_scene(data))
    full = problem.solve().w.x.array.copy()
    problem.loads.set_time(0.25)
    quarter = problem.solve().w.x.array
    assert np.abs(full).max() > 0
    assert np.allclose(quarter, 0.25 * full, rtol=0, atol=1e-12 * np.abs(full).max())


@pytest.mark.parametrize("law", ["frictionless", "sticking"])
def test_load_steps_end_at_the_one_step_solution(law):
    """Frictionless and sticking contact are path independent: 3 steps = 1 step."""
    one = run(load_scene(pressed_inclusion(law)))
    three = run(load_scene(pressed_inclusion(law, load_steps=3)))
    assert three["load_steps"] == 3 and len(three["iterations_per_step"]) == 3
    a, b = (np.array(s["interface_samples"]["lambda_n"]) for s in (one, three))
    assert np.abs(a).max() > 0
    assert np.allclose(a, b, rtol=0, atol=1e-8 * np.abs(a).max())


def test_coulomb_steps_respect_the_cone_and_print_a_line_per_step():
    lines = []
    with lines_to(lines.append):
        summary = run(load_scene(pressed_inclusion("coulomb", load_steps=2)))
    s = {k: np.array(v) for k, v in summary["interface_samples"].items()}
    # the raw multipliers (P_t is clamped into the cone by construction): within the
    # cone up to h times the pressure scale (h = 1/6, the base scene's cells)
    tol = np.abs(s["lambda_n"]).max() / 6
    assert np.all(np.abs(s["lambda_t"]) <= 0.5 * np.abs(s["lambda_n"]) + tol)
    assert np.all(s["lambda_n"] <= tol)
    assert sum("load step" in line for line in lines) == 2
    assert sum("Newton" in line for line in lines) >= 2


def test_newton_failure_is_reported_with_its_history():
    data = pressed_inclusion("coulomb", max_iterations=1, load_steps=2)
    with pytest.raises(NewtonFailure, match="load step 1/2") as failure:
        run(load_scene(data))
    assert "iterate  0" in str(failure.value) and "iterate  1" in str(failure.value)
    assert len(failure.value.report.residuals) == 2


@pytest.mark.parametrize(
    "solver, key, fragment",
    [
        ({"load_steps": 0}, "solver.load_steps", "must be in [1, 10000], got 0"),
        ({"load_steps": 1.5}, "solver.load_steps", "expected an integer, got number 1.5"),
        ({"load_steps": True}, "solver.load_steps", "expected an integer, got boolean True"),
        ({"max_iterations": 2.5}, "solver.max_iterations", "expected an integer"),
        ({"rtol": -1.0}, "solver.rtol", "must be > 0.0"),
        ({"atol": float("nan")}, "solver.atol", "must be a finite number, got nan"),
        ({"steps": 3}, "solver.steps", "unknown key; valid: ['load_steps',"),
        ({"petsc": {"pc_type": [1]}}, "solver.petsc.pc_type", "a string, number or boolean"),
        ({"petsc": {"ksp_rtol": float("inf")}}, "solver.petsc.ksp_rtol", "got inf"),
        ({"petsc": "lu"}, "solver.petsc", "expected a table of PETSc options"),
    ],
)
def test_solver_table_errors(solver, key, fragment):
    data = base()
    data["solver"] = solver
    one_line_error(data, key, fragment)


# -- several interfaces -------------------------------------------------------------------


def two_inclusions(centres=((0.28, 0.5), (0.72, 0.5)), radius=0.12, **change) -> dict:
    """Two frictionless inclusions in a plate under hydrostatic pressure 1 Pa."""
    data = base()
    data["mesh"]["cells"] = [16, 16]
    data["interfaces"] = [
        {"name": f"inc{k}", "shape": "circle", "centre": list(c), "radius": radius}
        | {"law": "frictionless"}
        for k, c in enumerate(centres)
    ]
    data["interfaces"][1].update(change)
    data["loads"] = [
        {"part": p, "type": "pressure", "value": 1.0} for p in ("left", "right", "bottom", "top")
    ] + [
        {"type": "point_displacement", "point": [0.5, 0.0], "component": 0, "value": 0.0},
        {"type": "point_displacement", "point": [0.5, 1.0], "component": 0, "value": 0.0},
        {"type": "point_displacement", "point": [0.0, 0.5], "component": 1, "value": 0.0},
    ]
    return data


def test_two_inclusions_under_hydrostatic_pressure():
    """Same material everywhere: the exact stress is -1 Pa I, so P_n = -1 on both circles."""
    scene = load_scene(two_inclusions())
    problem, effects = build(scene)
    assert effects["interfaces"] == ["inc0", "inc1"]

    def length(cut):
        one = dolfinx.fem.assemble_scalar(xfem_contact.form(1.0 * cut.dGamma))
        return cut.mesh.comm.allreduce(one, op=MPI.SUM)

    # the union's interface is each circle's own cut, exactly
    alone = [CutMesh(problem.mesh, levelset(spec), degree=2) for spec in scene.interfaces]
    total = length(problem.cut)
    assert abs(total - sum(length(c) for c in alone)) < 1e-13
    assert abs(total - 2 * 2 * np.pi * 0.12) < 1e-3 * total
    summary = run(scene)
    assert "interface_samples" not in summary  # one set of samples per interface instead
    for name, side in (("inc0", -1), ("inc1", 1)):
        s = {k: np.array(v) for k, v in summary["interfaces"][name]["samples"].items()}
        assert np.all(np.sign(s["x"] - 0.5) == side)  # the samples of that interface only
        assert np.all(np.abs(s["P_n"] + 1.0) < 2e-2)


@pytest.mark.parametrize(
    "change, error, message",
    [
        ({"centre": [0.3, 0.5]}, ValueError, "overlap"),  # intersecting
        ({"centre": [0.28, 0.5], "radius": 0.05}, ValueError, "overlap"),  # nested
        ({"centre": [0.5, 0.5]}, ValueError, "cuts the same"),  # 1 mesh cell apart
        ({"outside": "other"}, NotImplementedError, "interfaces\\[1\\].outside"),
        ({"name": "inc0"}, ValueError, "unique"),
    ],
)
def test_several_interfaces_errors(change, error, message):
    data = two_inclusions(**change)
    data["materials"]["other"] = {"E": 1e9, "nu": 0.0}
    with pytest.raises(error, match=message):
        build(load_scene(data))


def two_laws(which=("bonded", "coulomb")) -> dict:
    """A plate under uniform compression with a bonded inclusion (left) and a Coulomb
    inclusion (right, friction 1: it sticks), both of the plate's material, far apart;
    ``which`` keeps one or both. The exact stress is uniform, diag(-1, -2) Pa."""
    data = base()
    data["mesh"] = {"corners": [[0, 0], [2, 1]], "cells": [20, 10]}
    specs = {
        "bonded": {"name": "bonded", "centre": [0.5, 0.5], "law": "bonded"},
        "coulomb": {"name": "coulomb", "centre": [1.5, 0.5], "law": "coulomb", "friction": 1.0},
    }
    data["interfaces"] = [{"shape": "circle", "radius": 0.2} | specs[k] for k in which]
    data["loads"] = [
        {"part": "left", "type": "pressure", "value": 1.0},
        {"part": "right", "type": "pressure", "value": 1.0},
        {"part": "bottom", "type": "pressure", "value": 2.0},
        {"part": "top", "type": "pressure", "value": 2.0},
        {"type": "point_displacement", "point": [1.0, 0.0], "component": 0, "value": 0.0},
        {"type": "point_displacement", "point": [1.0, 1.0], "component": 0, "value": 0.0},
        {"type": "point_displacement", "point": [0.0, 0.5], "component": 1, "value": 0.0},
    ]
    return data


def test_two_laws_in_one_plate_equal_each_law_alone():
    """Each interface keeps its own law, multiplier field, measure and samples: with both
    inclusions of the plate's material the stress stays uniform, so the two-law scene
    gives each interface the multipliers of that law's one-inclusion scene."""
    both = run(load_scene(two_laws()))
    assert both["effects"]["laws"]["bonded"]["law"] == "bonded"
    assert both["effects"]["laws"]["coulomb"]["friction"] == 1.0
    assert both["fields"] == ["u_minus", "u_plus", "multiplier_bonded", "multiplier_coulomb"]
    assert both["effects"]["solver"].startswith("SNES")
    for name in ("bonded", "coulomb"):
        alone = run(load_scene(two_laws((name,))))
        a, b = (s["interfaces"][name]["samples"] for s in (both, alone))
        order_a, order_b = (np.lexsort(np.round([s["x"], s["y"]], 10)) for s in (a, b))
        scale = np.abs(b["lambda_n"]).max()  # the traction scale (2 Pa)
        for key in ("lambda_n", "lambda_t"):
            x, y = np.array(a[key])[order_a], np.array(b[key])[order_b]
            assert x.size == y.size > 0
            assert np.abs(x - y).max() < 1e-6 * scale, (name, key)
        theta = np.arctan2(
            np.array(a["y"]) - 0.5, np.array(a["x"]) - (0.5 if name == "bonded" else 1.5)
        )
        exact = -1.5 + 0.5 * np.cos(2 * theta)  # n.sigma.n of diag(-1, -2)
        assert np.abs(np.array(a["lambda_n"]) - exact).max() < 0.05


def test_materials_differ_by_inclusion():
    """The bundled two-inclusion scene: the stiff material only inside its own inclusion."""
    scene = load_scene(bundled_scenes()["two_inclusions"])
    problem, effects = build(scene)
    E = problem.bulk.materials[-1].ufl_E  # a DG0 field: side -1 holds two materials
    cut = problem.cut
    x = dolfinx.mesh.compute_midpoints(cut.mesh, 2, np.arange(cut.cell_sides.size, dtype=np.int32))
    inside_a = np.hypot(x[:, 0] - 0.5, x[:, 1] - 0.5) < 0.15
    inside_b = np.hypot(x[:, 0] - 1.5, x[:, 1] - 0.5) < 0.15
    values = E.x.array[E.function_space.dofmap.list[: cut.cell_sides.size, 0]]
    assert np.all(values[inside_a] == 1e9) and np.all(values[inside_b] == 100e6)
    problem.materials[-1]["bonded_stiff"].E = 2e9  # a Constant-like parameter: refills E
    values = E.x.array[E.function_space.dofmap.list[: cut.cell_sides.size, 0]]
    assert np.all(values[inside_a] == 2e9) and np.all(values[inside_b] == 100e6)
    assert effects["interfaces"] == ["bonded_stiff", "coulomb"]
    assert set(effects["laws"]) == {"bonded_stiff", "coulomb"}


# -- gmsh meshes ----------------------------------------------------------------------------


def gmsh_scene(**mesh) -> dict:
    """The bundled plate with a hole, meshed coarsely, a frictionless inclusion above it."""
    data = base(law="frictionless")
    data["mesh"] = {
        "kind": "gmsh",
        "file": "plate_with_hole.geo",
        "cell": "quadrilateral",
        "geometry_degree": 2,
        "size": 0.08,
    } | mesh
    data["interfaces"][0] |= {"centre": [0.5, 0.8], "radius": 0.1}
    data["loads"] = [
        {"part": "bottom", "type": "displacement", "value": [0.0, 0.0]},
        {"part": "top", "type": "pressure", "value": 1e5},
        {"part": "hole", "type": "pressure", "value": 0.0},
    ]
    return data


SCENES = bundled_scenes()["plate_with_hole_inclusion"].parent


@pytest.mark.mpi
def test_gmsh_scene_runs_with_named_parts():
    """A .geo with physical curves: loads on named parts; same on 1 and 2 ranks."""
    scene = load_scene(gmsh_scene(), folder=SCENES)
    summary = run(scene)
    alone = run(scene, comm=MPI.COMM_SELF)
    a, b = (np.array(s["interface_samples"]["lambda_n"]) for s in (summary, alone))
    order_a = np.lexsort([summary["interface_samples"][k] for k in ("x", "y")])
    order_b = np.lexsort([alone["interface_samples"][k] for k in ("x", "y")])
    assert np.allclose(a[order_a], b[order_b], rtol=0, atol=1e-9 * np.abs(a).max())
    assert summary["effects"]["interface"] == "frictionless"
    s = {k: np.array(v) for k, v in summary["interface_samples"].items()}
    assert summary["contact_status"]["contact"] > 0
    # the top pressure goes through the inclusion: compression on its top and bottom
    assert s["P_n"][np.abs(s["x"] - 0.5) < 0.03].min() < -1e4
    assert summary["dofs"]["standard"] > 0


@pytest.mark.parametrize(
    "mesh, load, key, fragment",
    [
        ({}, {"part": "roof", "type": "pressure", "value": 1}, "loads[3].part", "'hole'"),
        ({"file": "nowhere.geo"}, None, "mesh.file", "'nowhere.geo': no such file"),
        (
            {"file": "plate_with_hole_inclusion.toml"},
            None,
            "mesh.file",
            "expected a .geo or .msh file",
        ),
        ({"kind": "rectangle"}, None, "mesh.file", "is for mesh.kind = 'gmsh', not 'rectangle'"),
        ({"size": -0.1}, None, "mesh.size", "must be > 0.0"),
        ({"file": 3}, None, "mesh.file", "expected a string, got integer 3"),
    ],
)
def test_gmsh_scene_errors(mesh, load, key, fragment):
    data = gmsh_scene(**mesh)
    if load:
        data["loads"].append(load)
    one_line_error(data, key, fragment, folder=SCENES)


def test_gmsh_3d_file_takes_3d_keys(tmp_path):
    """A 3D .geo makes a 3D scene: 2D cells and 2D shapes refused, naming the 3D ones."""
    ball = tmp_path / "ball.geo"
    ball.write_text(
        'SetFactory("OpenCASCADE");\nSphere(1) = {0, 0, 0, 0.5};\n'
        'Physical Volume("ball", 7) = {1};\nPhysical Surface("hole", 3) = {1};\n'
    )
    data = gmsh_scene(file=str(ball))
    one_line_error(data, "mesh.cell", "choose one of ['tetrahedron', 'hexahedron']")
    data["mesh"]["cell"] = "tetrahedron"
    one_line_error(data, "interfaces[0].shape", "'circle' is a 2D shape and the mesh is 3D")


def test_msh_file_takes_its_own_cells(tmp_path):
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(SCENES / "plate_with_hole.geo"))
        gmsh.model.mesh.generate(2)
        gmsh.write(str(tmp_path / "plate.msh"))
    finally:
        gmsh.finalize()
    data = gmsh_scene(file=str(tmp_path / "plate.msh"))
    with pytest.raises(ValueError, match="read from the .msh file"):
        load_scene(data)
    for key in ("cell", "geometry_degree", "size"):
        data["mesh"].pop(key)
    scene = load_scene(data)
    problem, _ = build(scene)
    assert problem.mesh.topology.cell_name() == "triangle"
