"""Engineering outputs: stresses, reactions and the global balance, interface point data,
pictures coloured from exact zero."""

import xfem_contact  # noqa: F401

# isort: split
import pathlib

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import pyvista
from mpi4py import MPI
from test_scenes import base

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.io.pictures import colour_range
from xfem_contact.mechanics.materials import Material
from xfem_contact.mechanics.reactions import balance
from xfem_contact.mechanics.stress import StressFields
from xfem_contact.scenes.run import build, run
from xfem_contact.scenes.scene import load_scene

#: Global balance: reactions + applied loads = 0, relative to the largest force
BALANCE = 1e-8


def plate(law: str | None, cells: int = 12, **options) -> dict:
    """A plate fixed at the bottom, sheared and compressed on top, with an inclusion."""
    data = base(law=law, **options) if law else base()
    data["mesh"]["cells"] = [cells, cells]
    data["materials"]["m"]["nu"] = 0.3
    data["loads"][1] = {"part": "top", "type": "traction", "value": [0.4e6, -1.0e6]}
    return data


def solved(data: dict, comm=MPI.COMM_WORLD):
    problem, _ = build(load_scene(data), comm)
    problem.solve()
    return problem


@pytest.mark.mpi
@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize(
    "law, options", [("bonded", {}), ("coulomb", {"friction": 0.3}), ("frictionless", {})]
)
def test_reactions_balance_the_loads(law, options):
    forces = [
        balance(problem, problem.w)
        for problem in (
            solved(plate(law, **options), comm) for comm in (MPI.COMM_WORLD, MPI.COMM_SELF)
        )
    ]
    for f in forces:
        assert f["balance_relative"] < BALANCE, f
        assert set(f["reactions"]) == {"bottom"}  # corners of left/right are bottom's
        np.testing.assert_allclose(f["reactions"]["bottom"], [-0.4e6, 1.0e6], rtol=1e-8)
        np.testing.assert_allclose(f["applied_loads"], [0.4e6, -1.0e6], rtol=1e-12)
        # a floating inclusion with no load: the interface carries no net force
        (resultant,) = f["interface_resultants"].values()
        assert np.abs(resultant).max() < 1e-8 * 1e6
    # 2 ranks = 1 rank
    np.testing.assert_allclose(
        forces[0]["reactions"]["bottom"], forces[1]["reactions"]["bottom"], rtol=1e-10
    )


def test_plain_scene_reactions_balance_the_loads():
    problem, _ = build(load_scene(plate(None)), MPI.COMM_WORLD)
    u = problem.solve().w
    forces = balance(problem, u)
    assert forces["balance_relative"] < BALANCE, forces
    np.testing.assert_allclose(forces["reactions"]["bottom"], [-0.4e6, 1.0e6], rtol=1e-8)
    assert forces["interface_resultants"] == {}
    assert balance(problem, problem.w) == forces  # the problem keeps its solution


def test_point_supports_and_parts_share_out_the_reactions():
    data = plate("sticking")
    data["loads"] = [
        {"part": "left", "type": "displacement", "value": 0.0, "component": 0},
        {"part": "bottom", "type": "displacement", "value": 0.0, "component": 1},
        {"part": "right", "type": "pressure", "value": 1.0e6},
        {"part": "top", "type": "pressure", "value": 2.0e6},
    ]
    problem = solved(data)
    forces = balance(problem, problem.w)
    assert forces["balance_relative"] < BALANCE, forces
    np.testing.assert_allclose(forces["reactions"]["left"], [1.0e6, 0.0], atol=1e-6)
    np.testing.assert_allclose(forces["reactions"]["bottom"], [0.0, 2.0e6], atol=1e-6)


def test_interface_resultant_balances_the_load_on_the_inclusion():
    problem = inclusion_problem(10, 2, "sticking")  # body-force free, pressure outside
    problem.solve()
    forces = balance(problem, problem.w)
    assert forces["balance_relative"] < BALANCE, forces
    (resultant,) = forces["interface_resultants"].values()
    assert np.abs(resultant).max() < 1e-10  # the inclusion carries no load (N/m)


@pytest.mark.parametrize("law, options", [("coulomb", {"friction": 0.3}), ("bonded", {})])
def test_forces_at_a_state_are_those_of_the_problem_solved_to_it(law, options):
    """The balance at a state ``w`` other than the problem's solution is that of the
    problem solved to ``w``: every term (bulk, laws, springs) is evaluated at ``w``."""
    data = plate(law, **options)
    data["loads"].append({"part": "left", "type": "tangential_spring", "value": 1e9})
    problem = solved(data)
    half = problem.w.copy()
    at_half = balance(problem, problem.w)
    problem.loads.set_time(2.0)
    problem.solve()
    at_full = balance(problem, problem.w)
    problem.loads.set_time(1.0)  # the loads of the first state, the solution of the second
    again = balance(problem, half)
    for key in ("reactions", "interface_resultants"):
        for name, force in at_half[key].items():
            np.testing.assert_allclose(again[key][name], force, rtol=1e-10, atol=1e-6)
    for name, force in at_half["reactions"].items():  # the second state's differ
        assert (
            np.abs(np.subtract(at_full["reactions"][name], force)).max() > 0.1 * np.abs(force).max()
        )
    assert again["balance_relative"] < BALANCE, again


def test_tangential_springs_are_reactions():
    data = plate("sticking")
    data["loads"].append({"part": "left", "type": "tangential_spring", "value": 1e9})
    problem = solved(data)
    forces = balance(problem, problem.w)
    assert set(forces["reactions"]) == {"bottom", "tangential_springs"}
    assert np.abs(forces["reactions"]["tangential_springs"]).max() > 1e3  # it carries load
    assert forces["balance_relative"] < BALANCE, forces


@pytest.fixture(scope="module")
def coulomb_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("coulomb")
    data = plate("coulomb", cells=10, friction=0.3)
    data["solver"] = {"load_steps": 2}
    summary = run(load_scene(data), out, progress_bar=False)
    return out, summary


def test_summary_has_reactions_and_balance(coulomb_run):
    _, summary = coulomb_run
    forces = summary["forces"]
    assert forces["balance_relative"] < BALANCE
    assert set(forces) >= {"reactions", "applied_loads", "interface_resultants", "balance"}
    status = summary["interface_samples"]["status"]
    assert set(status) <= {0, 1, 2} and {1, 2} <= set(status)  # stick and slip both


def test_result_vtu_carries_stress_and_von_mises(coulomb_run):
    out, _ = coulomb_run
    grid = pyvista.read(out / "result.vtu")
    sigma = np.asarray(grid.point_data["stress"]).reshape(-1, 3, 3)
    vm = np.asarray(grid.point_data["von_mises"])
    s = sigma - np.trace(sigma, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
    # von Mises is interpolated on its own (DG1): equal to that of the stress at the
    # DG1 nodes, apart from it in between where the stress changes sign
    rel = np.abs(vm - np.sqrt(1.5 * (s**2).sum(axis=(1, 2)))) / vm.max()
    assert vm.min() >= 0 and np.median(rel) < 1e-3
    # plane strain: sigma_zz = nu (sigma_xx + sigma_yy), nu = 0.3
    np.testing.assert_allclose(
        sigma[:, 2, 2], 0.3 * (sigma[:, 0, 0] + sigma[:, 1, 1]), atol=1e-8 * vm.max()
    )
    # equilibrium at the top: sigma_yy = -1e6, sigma_xy = 0.4e6 on average there
    top = grid.points[:, 1] > 1 - 1e-9
    assert abs(sigma[top, 1, 1].mean() + 1.0e6) < 0.05e6
    assert abs(sigma[top, 0, 1].mean() - 0.4e6) < 0.05e6
    assert (out / "stress.bp").is_dir()


def test_interface_vtu_carries_the_laws_state(coulomb_run):
    out, summary = coulomb_run
    grid = pyvista.read(out / "interface.vtu")
    data = {k: np.asarray(grid.point_data[k]) for k in ("lambda_n", "lambda_t", "gap", "slip")}
    status = np.asarray(grid.point_data["status"])
    assert set(np.unique(status)) <= {0, 1, 2} and {1, 2} <= set(np.unique(status))
    samples = summary["interface_samples"]
    # the nodes see the same ranges as the rule points
    for key in ("lambda_n", "lambda_t"):
        scale = np.abs(samples[key]).max()
        assert np.abs(data[key]).max() == pytest.approx(scale, rel=0.3)
    # closed where in contact (up to the weak enforcement between the rule points)
    u = np.abs(pyvista.read(out / "result.vtu").point_data["u"]).max()
    assert np.all(np.abs(data["gap"][status > 0]) < 1e-2 * u)


def test_summary_has_a_balanced_record_per_load_step(coulomb_run):
    """One record per load step (pseudo-times 0.5, 1): the loads follow the factor t, the
    reactions balance them at every step, the last record's forces are the summary's."""
    _, summary = coulomb_run
    steps = summary["steps"]
    assert [(r["step"], r["time"]) for r in steps] == [(1, 0.5), (2, 1.0)]
    assert [r["iterations"] for r in steps] == summary["iterations_per_step"]
    for record in steps:
        assert record["forces"]["balance_relative"] < BALANCE, record["forces"]
        assert {"open", "stick", "slip"} & set(record["status"]), record["status"]
    half, full = (np.array(r["forces"]["applied_loads"]) for r in steps)
    assert np.abs(full).max() > 1e4 and np.allclose(half, 0.5 * full, rtol=1e-12, atol=0)
    bottom = [np.array(r["forces"]["reactions"]["bottom"]) for r in steps]
    assert not np.allclose(bottom[0], bottom[1])
    assert summary["forces"] == steps[-1]["forces"]
    # the interface's points open / sticking / sliding per step; the last step's are the
    # samples' of the summary
    (name,) = summary["interfaces"]
    codes = np.bincount(summary["interfaces"][name]["samples"]["status"], minlength=3)
    assert list(steps[-1]["interfaces"][name].values()) == codes.tolist()
    assert [sum(r["interfaces"][name].values()) for r in steps] == [codes.sum()] * 2


def test_pvd_series_opens_every_step(coulomb_run):
    """result.pvd and interface.pvd: pyvista (ParaView's reader) opens them, one data set
    per load step at its pseudo-time, each with the arrays and size of the final grids."""
    out, _ = coulomb_run
    final = {name: pyvista.read(out / f"{name}.vtu") for name in ("result", "interface")}
    arrays = {"result": {"u", "stress", "von_mises"}, "interface": {"lambda_n", "status"}}
    for name, grid in final.items():
        reader = pyvista.get_reader(out / f"{name}.pvd")
        assert reader.time_values == [0.5, 1.0]
        steps = []
        for t in reader.time_values:
            reader.set_active_time_value(t)
            (step,) = reader.read()
            assert step.n_points == grid.n_points and step.n_cells == grid.n_cells
            assert arrays[name] <= set(step.point_data.keys())
            assert set(step.cell_data.keys()) == set(grid.cell_data.keys())
            steps.append(step)
        key = "u" if name == "result" else "lambda_n"
        np.testing.assert_array_equal(steps[-1].point_data[key], grid.point_data[key])
        assert not np.allclose(steps[0].point_data[key], steps[1].point_data[key])


@pytest.mark.parametrize("cell, per_square", [("quadrilateral", 1), ("triangle", 2)])
def test_plain_scene_series_holds_the_mesh_nodes(tmp_path, cell, per_square):
    """A plain (uncut) scene: result.pvd has a P2 / Q2 grid per step (quadratic cells at
    the nodes of u's space), the linear response scales with the load factor, the last step
    is result.vtu, the pictures are drawn; no interface series."""
    data = plate(None, cells=4)
    data["mesh"]["cell"] = cell
    data["solver"] = {"load_steps": 2}
    summary = run(load_scene(data), tmp_path, progress_bar=False)
    assert [r["forces"]["balance_relative"] < BALANCE for r in summary["steps"]] == [True] * 2
    reader = pyvista.get_reader(tmp_path / "result.pvd")
    assert reader.time_values == [0.5, 1.0]
    steps = []
    for t in reader.time_values:
        reader.set_active_time_value(t)
        steps.append(reader.read()[0])
    assert steps[0].n_points == (2 * 4 + 1) ** 2 and steps[0].n_cells == 4 * 4 * per_square
    # quadratic cells with their nodes in VTK's order: each the area of its mesh cell
    areas = steps[1].compute_cell_sizes()["Area"]
    np.testing.assert_allclose(areas, 1 / 16 / per_square, rtol=1e-12)
    assert {"u", "stress", "von_mises"} <= set(steps[1].point_data.keys())
    u = [np.asarray(step.point_data["u"]) for step in steps]
    np.testing.assert_allclose(u[0], 0.5 * u[1], rtol=0, atol=1e-12 * np.abs(u[1]).max())
    final = pyvista.read(tmp_path / "result.vtu")
    np.testing.assert_array_equal(final.point_data["u"], u[1])
    assert not (tmp_path / "interface.pvd").exists()
    assert (tmp_path / "result.png").exists()


def _lips_by_position(grid) -> np.ndarray:
    """Rows ``(side, x, y, ux, uy)`` of a lips grid, one per distinct (side, point),
    sorted: comparable between runs that number and divide the points differently."""
    side = np.zeros(grid.n_points)
    side[grid.cell_connectivity] = np.repeat(
        np.asarray(grid.cell_data["side"]), np.diff(grid.cell_offsets)
    )
    rows = np.c_[side, grid.points[:, :2], np.asarray(grid.point_data["u"])[:, :2]]
    _, first = np.unique(np.round(rows[:, :3], 9), axis=0, return_index=True)
    return rows[first]


@pytest.mark.mpi
def test_parallel_series_has_pvtu_pieces_and_equals_serial(tmp_path_factory):
    """Under MPI each step is a .pvtu of the ranks' pieces; read through the .pvd, every
    step equals a serial run's (same points per side, displacements to 1e-9)."""
    comm = MPI.COMM_WORLD
    folder = tmp_path_factory.mktemp("series") if comm.rank == 0 else None
    folder = pathlib.Path(comm.bcast(str(folder), root=0))
    data = plate("coulomb", cells=8, friction=0.3)
    data["solver"] = {"load_steps": 2}
    summary = run(load_scene(data), folder / "parallel", progress_bar=False)
    assert len(summary["steps"]) == 2
    if comm.rank == 0:
        run(load_scene(data), folder / "serial", progress_bar=False, comm=MPI.COMM_SELF)
    comm.barrier()
    steps = folder / "parallel" / "result_steps"
    if comm.size > 1:
        assert (steps / "result_000002.pvtu").exists()
        assert (steps / f"result_000002_r{comm.rank}.vtu").exists()
        assert (folder / "parallel" / "result.pvtu").exists()
    if comm.rank == 0:
        readers = [
            pyvista.get_reader(folder / run_ / "result.pvd") for run_ in ("serial", "parallel")
        ]
        assert readers[0].time_values == readers[1].time_values == [0.5, 1.0]
        for t in readers[0].time_values:
            rows = []
            for reader in readers:
                reader.set_active_time_value(t)
                (grid,) = reader.read()
                rows.append(_lips_by_position(grid.cast_to_unstructured_grid()))
            assert rows[0].shape == rows[1].shape
            np.testing.assert_allclose(rows[1][:, :3], rows[0][:, :3], atol=1e-12)
            scale = np.abs(rows[0][:, 3:]).max()
            np.testing.assert_allclose(rows[1][:, 3:], rows[0][:, 3:], atol=1e-9 * scale)


def test_show_draws_von_mises_and_the_traction(coulomb_run):
    out, _ = coulomb_run
    for name in ("von_mises.png", "traction.png", "pressure.png", "result.png"):
        image = pyvista.read(out / name)
        assert np.asarray(image.point_data.active_scalars).std() > 0, name


def test_stress_fields_are_exact_for_a_uniform_strain():
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 4, 4)
    u = dolfinx.fem.Function(dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,))))
    u.interpolate(lambda x: np.vstack([1e-3 * x[0] + 2e-3 * x[1], -0.5e-3 * x[1]]))
    E, nu = 100e6, 0.3
    fields = StressFields([("", Material(E, nu), u)])
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    eps = np.array([[1e-3, 1e-3], [1e-3, -0.5e-3]])
    sigma = np.zeros((3, 3))
    sigma[:2, :2] = 2 * mu * eps + lam * np.trace(eps) * np.eye(2)
    sigma[2, 2] = nu * np.trace(sigma)
    s = sigma - np.trace(sigma) / 3 * np.eye(3)
    values = fields.stress[0].x.array.reshape(-1, 9)
    np.testing.assert_allclose(values, np.tile(sigma.ravel(), (values.shape[0], 1)), atol=1e-6)
    np.testing.assert_allclose(fields.von_mises[0].x.array, np.sqrt(1.5 * (s**2).sum()))


def test_colour_range_starts_at_exact_zero():
    values, clim = colour_range(np.array([4.84e-22, 1.0, 2.0]))
    assert values[0] == 0.0 and clim == (0.0, 2.0)
    assert colour_range(np.array([-3.0, -1e-20]))[1] == (-3.0, 0.0)
    assert colour_range(np.zeros(3))[1] == (0.0, 1.0)
