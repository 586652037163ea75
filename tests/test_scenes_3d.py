"""Scenes on 3D meshes: boxes of tetrahedra and hexahedra, 3D interface shapes, face names,
the material mode, their outputs and pictures, the refusals of what exists in 2D only."""

import copy
import json
import tomllib

import numpy as np
import pytest
from mpi4py import MPI
from parallel import gathered_fields, max_relative_difference
from test_scenes import one_line_error

from xfem_contact.cases.solid import SPHERE_CENTRE, TRIAXIAL, sphere_errors, sphere_problem
from xfem_contact.scenes.builder import build, levelset
from xfem_contact.scenes.cli import main
from xfem_contact.scenes.expressions import numpy_field
from xfem_contact.scenes.records import InterfaceSpec
from xfem_contact.scenes.run import run
from xfem_contact.scenes.scene import bundled_scenes, load_scene


def sphere_scene(n: int = 4, **mesh) -> dict:
    """The bundled triaxial sphere scene as a dict, ``n`` cells per edge."""
    with open(bundled_scenes()["sphere_triaxial"], "rb") as f:
        data = tomllib.load(f)
    data["mesh"] |= {"cells": [n, n, n]} | mesh
    return data


def solved(scene, comm=MPI.COMM_WORLD):
    problem, _ = build(scene, comm)
    problem.solve()
    return problem


def test_sphere_scene_is_the_solid_case():
    """The bundled scene builds cases/solid.py's sticking sphere with the quadric level set:
    the same solution, and its pressure error (the geometry's) is small."""
    problem = solved(load_scene(sphere_scene()))
    assert problem.mesh.geometry.dim == 3
    assert problem.bulk.materials[1].plane == "3d"
    case = sphere_problem(4, 2, "sticking", levelset="quadric")
    # the same forms (their kernels compiled once for both)
    assert problem.residual(problem.w).signature() == case.residual(case.w).signature()
    case.solve()
    assert problem.w.x.array.shape == case.w.x.array.shape
    difference = np.abs(problem.w.x.array - case.w.x.array).max()
    assert difference < 1e-12 * np.abs(case.w.x.array).max()
    problem.stress = TRIAXIAL
    e_n, e_t = sphere_errors(problem)
    assert e_n < 1.5e-3 and e_t < 1.5e-2, (e_n, e_t)


def test_hexahedra_open_plane_is_exact():
    """Q2 hexahedra cut by the plane x = 0.55 with a free interface (the forms of
    tests/test_solid.py's inclined plane): E = 1, nu = 0 and the stress
    ``(x - 0.55) diag(2, -1, 3)``, traction-free on the plane, balanced by the body force
    ``(-2, 0, 0)``; its displacement, quadratic, held on the boundary by expressions of
    x, y, z, is what Q2 finds on each side."""
    exact = ["(x - 0.55) * 2 * x - 0.5 * (2 * x**2 - y**2 + 3 * z**2)", "-(x - 0.55) * y"]
    exact.append("(x - 0.55) * 3 * z")
    data = {
        "mesh": {"kind": "box", "cells": [2, 2, 2], "cell": "hexahedron"},
        "discretisation": {"degree": 2, "levelset_degree": 1, "quadrature_degree": 10},
        "materials": {"a": {"E": 1.0, "nu": 0.0}},
        "interfaces": [{"shape": "plane", "point": [0.55, 0, 0], "normal": [1, 0, 0]}],
        "loads": [{"part": "boundary", "type": "displacement", "value": exact}]
        + [{"type": "body_force", "value": [-2.0, 0.0, 0.0], "side": s} for s in (-1, 1)],
    }
    data["interfaces"][0]["law"] = "free"
    problem = solved(load_scene(data))
    assert problem.cut.num_cut_cells_global == 4
    V = problem.space.field_space(0)[0]
    x = V.tabulate_dof_coordinates()
    expected = np.stack([numpy_field(e, dim=3)(x.T) for e in exact], axis=1)
    for field, side in ((0, -1), (1, 1)):  # on the cells where the side is
        cells = np.flatnonzero(problem.cut.cell_sides != -side)
        dofs = np.unique(V.dofmap.list[cells])
        u = problem.space.field(problem.w, field).x.array.reshape(-1, 3)[dofs]
        assert np.abs(u - expected[dofs]).max() < 1e-10


def test_3d_outputs_and_show(tmp_path):
    """A 3D run folder: VTX fields, the lips grid tiling the cube exactly (positive cells),
    the interface surface carrying the law's state (the exact pressure n.sigma.n at its
    nodes, all sticking), and ``xfem-contact show`` drawing its pictures."""
    import pyvista

    data = sphere_scene()
    data["outputs"] = {"png": False}
    summary = run(load_scene(data), out=tmp_path, progress_bar=False)
    assert summary["dofs"]["multiplier"] > 0 and summary["iterations"] == 1
    for name in ("displacement.bp", "multiplier.bp", "stress.bp", "summary.json"):
        assert (tmp_path / name).exists(), name
    result = pyvista.read(tmp_path / "result.vtu")
    volumes = result.compute_cell_sizes(length=False, area=False)["Volume"]
    assert volumes.min() > 0 and abs(volumes.sum() - 1.0) < 1e-12
    assert set(np.unique(result.cell_data["side"])) == {-1, 1}
    surface = pyvista.read(tmp_path / "interface.vtu")
    x = surface.points - np.asarray(SPHERE_CENTRE)
    radius = np.linalg.norm(x, axis=1)
    assert np.abs(radius - 0.2).max() < 1e-12  # on phi_h = 0, which P2 holds exactly
    corners = surface.points[surface.cells.reshape(-1, 4)[:, 1:]]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    outward = np.einsum("ij,ij->i", normal, corners.mean(axis=1) - SPHERE_CENTRE)
    assert np.all(outward > 0)  # every triangle turned towards side +1
    n = x / radius[:, None]
    exact = np.einsum("ij,j,ij->i", n, TRIAXIAL, n)
    assert np.abs(surface.point_data["lambda_n"] - exact).max() < 0.1
    assert surface.point_data["slip"].shape == (surface.n_points, 3)
    assert np.all(surface.point_data["status"] == 1)  # sticking
    assert main(["show", str(tmp_path)]) == 0
    for name in ("result.png", "von_mises.png", "cut.png", "pressure.png", "traction.png"):
        assert (tmp_path / name).stat().st_size > 10_000, name
    assert json.loads((tmp_path / "summary.json").read_text())["scene"] == "sphere_triaxial"


@pytest.mark.mpi
@pytest.mark.parallel
def test_sphere_scene_parallel_equals_serial():
    """The 3D scene's fields gathered by position: 2 ranks = 1 rank."""
    scene = load_scene(sphere_scene())
    alone = gathered_fields(solved(scene, MPI.COMM_SELF))
    together = gathered_fields(solved(scene))
    for name, difference in max_relative_difference(together, alone).items():
        assert difference < 1e-10, (name, difference)


def spec(shape: str, **params) -> InterfaceSpec:
    return InterfaceSpec(shape=shape, law="bonded", inside="a", outside="a", params=params)


def test_3d_shapes_vanish_on_their_surface_with_unit_slope():
    """Each 3D shape's level set: zero on the exact surface, slope 1 across it there (the
    quadrics scaled by their smallest axis), negative inside."""
    rng = np.random.default_rng(3)
    d = rng.normal(size=(3, 50))
    d /= np.linalg.norm(d, axis=0)
    c = np.array([[0.4], [0.5], [0.6]])
    sphere = levelset(spec("sphere", centre=c.ravel().tolist(), radius=0.3), 3)
    assert np.abs(sphere(c + 0.3 * d)).max() < 1e-15
    assert np.allclose(sphere(c + 0.3001 * d), 1e-4, rtol=1e-3)
    assert np.all(sphere(c + 0.1 * d) < 0)
    axes = np.array([[0.35], [0.25], [0.15]])
    ellipsoid = levelset(spec("ellipsoid", centre=c.ravel().tolist(), axes=[0.35, 0.25, 0.15]), 3)
    assert np.abs(ellipsoid(c + axes * d)).max() < 1e-15
    assert np.all(ellipsoid(c + 0.5 * axes * d) < 0)
    cylinder = levelset(spec("cylinder", point=[0, 0, 0], axis=[0, 0, 2], radius=0.2), 3)
    ring = np.array([0.2 * np.cos(d[0]), 0.2 * np.sin(d[0]), 5 * d[1]])
    assert np.abs(cylinder(ring)).max() < 1e-14
    assert np.allclose(cylinder(ring * [[1.0005], [1.0005], [1.0]]), 1e-4, rtol=1e-3)
    plane = levelset(spec("plane", point=[0.5, 0, 0], normal=[3, 4, 0]), 3)
    assert np.allclose(plane(np.array([[1.1], [0.8], [7.0]])), (0.6 * 3 + 0.8 * 4) / 5)
    expression = levelset(spec("expression", expression="x + y + 2 * z - 1"), 3)
    assert np.allclose(expression(np.array([[1.0], [2.0], [3.0]])), 8.0)


def box(**interface) -> dict:
    """A small 3D scene dict: a unit box of tetrahedra, a bonded sphere."""
    return {
        "mesh": {"kind": "box", "cells": [2, 2, 2]},
        "materials": {"a": {"E": 1.0, "nu": 0.3}},
        "interfaces": [{"shape": "sphere", "centre": [0.5, 0.5, 0.5], "radius": 0.2} | interface],
        "loads": [{"part": "front", "type": "pressure", "value": 1.0}],
    }


def plane_scene(**interface) -> dict:
    return {
        "materials": {"a": {"E": 1.0, "nu": 0.3}},
        "interfaces": [{"shape": "circle", "centre": [0.5, 0.5], "radius": 0.2} | interface],
        "loads": [{"part": "top", "type": "pressure", "value": 1.0}],
    }


def with_load(data: dict, **load) -> dict:
    data = copy.deepcopy(data)
    data["loads"].append(load)
    return data


REFUSED = {
    "large sliding in 3D": (
        box(law="frictionless", kinematics="large"),
        "interfaces[0].kinematics",
        "2D only; valid on a 3D mesh: ['small']",
    ),
    "circle on a box": (
        box(shape="circle", centre=[0.5, 0.5]),
        "interfaces[0].shape",
        "'circle' is a 2D shape and the mesh is 3D: use 'sphere' or 'cylinder'",
    ),
    "sphere on a rectangle": (
        plane_scene(shape="sphere"),
        "interfaces[0].shape",
        "'sphere' is a 3D shape and the mesh is 2D: use 'circle'",
    ),
    "z on a rectangle": (
        plane_scene(shape="expression", expression="x + z", centre=None, radius=None),
        "interfaces[0].expression",
        "uses z, the third coordinate, on a 2D mesh",
    ),
    "2D centre on a box": (
        box(centre=[0.5, 0.5]),
        "interfaces[0].centre",
        "expected a list of 3 entries",
    ),
    "rotation on a box": (
        with_load(box(), part="left", type="rotation", angle_deg=1.0),
        "loads[1].type",
        "'rotation' is a load of 2D meshes",
    ),
    "spring on a box": (
        with_load(box(), part="left", type="tangential_spring", value=1.0),
        "loads[1].type",
        "'tangential_spring' is a load of 2D meshes",
    ),
    "traction of two on a box": (
        with_load(box(), part="left", type="traction", value=[1.0, 0.0]),
        "loads[1].value",
        "expected a list of 3 entries",
    ),
    "inner on a box": (
        with_load(box(), part="inner", type="pressure", value=1.0),
        "loads[1].part",
        "'inner': no such boundary part; known: ['back', 'bottom', 'boundary', 'front',",
    ),
    "front on a rectangle": (
        with_load(plane_scene(), part="front", type="pressure", value=1.0),
        "loads[1].part",
        "(front and back are the z faces of a 3D box)",
    ),
    "component 2 on a rectangle": (
        with_load(plane_scene(), type="point_displacement", point=[0, 0], component=2, value=0),
        "loads[1].component",
        "choose one of [0, 1]",
    ),
    "plane strain on a box": (
        box() | {"materials": {"a": {"E": 1.0, "nu": 0.3, "plane": "strain"}}},
        "materials.a.plane",
        "'strain' is not a mode of a 3D mesh; valid there: ['3d']",
    ),
    "3d on a rectangle": (
        plane_scene() | {"materials": {"a": {"E": 1.0, "nu": 0.3, "plane": "3d"}}},
        "materials.a.plane",
        "'3d' is not a mode of a 2D mesh; valid there: ['strain', 'stress']",
    ),
    "quadrilateral box": (
        box() | {"mesh": {"kind": "box", "cell": "quadrilateral"}},
        "mesh.cell",
        "choose one of ['tetrahedron', 'hexahedron']",
    ),
    "flat box": (
        box() | {"mesh": {"kind": "box", "corners": [[0, 0, 0], [1, 1, 0]]}},
        "mesh.corners",
        "the second corner must lie beyond (along x, y and z) the first",
    ),
}


@pytest.mark.parametrize("case", REFUSED)
def test_3d_refusals(case):
    data, key, fragment = REFUSED[case]
    interface = data["interfaces"][0]
    for name in [k for k, v in interface.items() if v is None]:
        del interface[name]
    one_line_error(data, key, fragment)


def test_box_scene_defaults_and_faces():
    """A box takes tetrahedra, 8 cells per edge, the unit cube and the mode 3d by default;
    its six faces and the expressions of x, y, z are known to the loads."""
    data = box(shape="expression", expression="(x - 0.5)**2 + (y - 0.5)**2 + z - 0.7")
    for name in ("centre", "radius"):
        del data["interfaces"][0][name]
    data["parts"] = {"lid": {"where": "z > 1 - 1e-9"}}
    faces = ("left", "right", "bottom", "top", "back", "front", "lid")
    data["loads"] = [{"part": face, "type": "pressure", "value": "1 + z"} for face in faces]
    scene = load_scene(data)
    assert (scene.gdim, scene.cell, scene.cells) == (3, "tetrahedron", (2, 2, 2))
    assert scene.corners == ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))
    assert scene.materials["a"].plane == "3d"
    assert_part_areas(scene, dict.fromkeys(faces, 1.0))


def assert_part_areas(scene, areas: dict) -> None:
    """Each named boundary part of the scene's mesh has the given area (m^2) to 1e-12."""
    import dolfinx.mesh

    from xfem_contact.mechanics.loads import boundary_facets
    from xfem_contact.scenes.builder import create_mesh, scene_parts

    meshed = create_mesh(scene)
    mesh, parts = meshed.mesh, scene_parts(scene, meshed)
    for name, area in areas.items():
        facets = boundary_facets(mesh, name, parts)
        x = mesh.geometry.x[dolfinx.mesh.entities_to_geometry(mesh, 2, facets)]
        found = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
        assert abs(found.sum() - area) < 1e-12, (name, found.sum())


def test_gmsh_3d_scene_with_named_surfaces(tmp_path):
    """A .geo with volumes and named physical surfaces: a 3D scene of tetrahedra whose
    loads name the surfaces; each named part is its whole unit face (area 1 exactly); a
    box's face name is refused (a gmsh file names its own parts)."""
    geo = tmp_path / "cube.geo"
    geo.write_text(
        'SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 1, 1, 1};\n'
        'Physical Volume("cube") = {1};\nPhysical Surface("xmin") = {1};\n'
        'Physical Surface("xmax") = {2};\n'
    )
    data = box(law="sticking")
    data["mesh"] = {"kind": "gmsh", "file": "cube.geo", "size": 0.3}
    data["loads"] = [
        {"part": "xmin", "type": "displacement", "value": [0.0, 0.0, 0.0]},
        {"part": "xmax", "type": "pressure", "value": 1.0},
    ]
    scene = load_scene(data, folder=tmp_path)
    assert (scene.gdim, scene.cell) == (3, "tetrahedron")
    assert_part_areas(scene, {"xmin": 1.0, "xmax": 1.0})
    with pytest.raises(ValueError, match="no such boundary part"):
        load_scene(with_load(data, part="left", type="pressure", value=1.0), folder=tmp_path)


@pytest.mark.parametrize(
    "interface, volume, area",
    [
        (  # a cylinder across the cube: its section times 1, its lateral area
            {"shape": "cylinder", "point": [0.5, 0.5, 0], "axis": [0, 0, 2], "radius": 0.25},
            np.pi * 0.25**2,
            2 * np.pi * 0.25,
        ),
        (  # an ellipsoid inside: 4/3 pi a b c
            {"shape": "ellipsoid", "centre": [0.5, 0.5, 0.5], "axes": [0.35, 0.25, 0.15]},
            4 / 3 * np.pi * 0.35 * 0.25 * 0.15,
            None,
        ),
    ],
)
def test_3d_shapes_cut_the_box(interface, volume, area):
    """A scene's 3D shapes as the cut sees them (P2 tetrahedra, 4 per edge): the volume
    inside and the interface's area against the exact ones."""
    import dolfinx.fem

    from xfem_contact.cases.paper import integrate
    from xfem_contact.fem.cutmesh import CutMesh
    from xfem_contact.scenes.builder import create_mesh, interface_levelsets

    data = box() | {"interfaces": [interface], "mesh": {"kind": "box", "cells": [4, 4, 4]}}
    scene = load_scene(data)
    mesh = create_mesh(scene).mesh
    cut = CutMesh(mesh, interface_levelsets(scene), degree=2)
    one = dolfinx.fem.Constant(mesh, 1.0)
    assert abs(integrate(one * cut.dx(-1)) / volume - 1) < 1e-4
    if area is not None:
        assert abs(integrate(one * cut.dGamma) / area - 1) < 1e-3
