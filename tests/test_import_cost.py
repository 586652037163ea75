"""What a run imports: ``import xfem_contact`` and the main demo's imports load no drawing,
meshing or VTK library, and the ``.vtu`` files of a run are written without VTK (the same
grids as VTK's writer). Each check runs a fresh interpreter: this process (conftest) has
long imported them."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest
import pyvista
from mpi4py import MPI

from xfem_contact.cases.paper import inclusion_problem
from xfem_contact.io.output import write_cut_geometry, write_lips
from xfem_contact.io.vtu import lips_arrays, subcell_arrays, write_vtu

#: Loaded only by what draws (matplotlib, pyvista), meshes (gmsh) or uses them
HEAVY = ("matplotlib", "pyvista", "gmsh", "vtkmodules", "scipy")


def loaded(code: str) -> set[str]:
    """The top-level packages among :data:`HEAVY` that ``code`` leaves in ``sys.modules``,
    run in a fresh interpreter."""
    probe = textwrap.dedent(code) + textwrap.dedent(
        f"""
        import sys
        print(sorted({{m.split(".")[0] for m in sys.modules}} & set({HEAVY!r})))
        """
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    return set(eval(result.stdout.strip().splitlines()[-1]))


def test_import_loads_no_drawing_meshing_or_vtk_library():
    assert loaded("import xfem_contact") == set()
    demo = """
        from xfem_contact.cases.paper import INCLUSION_CENTRE, inclusion_errors, inclusion_problem
        from xfem_contact.io.output import write_cut_geometry, write_fields, write_json, write_lips
        from xfem_contact.io.plots import Series, line_plot
        from xfem_contact.solvers.log_lines import lines_to
        from xfem_contact.solvers.options import LINEAR_PRESETS, preset
        """
    assert loaded(demo) == set()


def test_vtu_files_are_written_without_vtk(tmp_path):
    code = f"""
        import pathlib
        from xfem_contact.cases.paper import inclusion_problem
        from xfem_contact.io.output import write_cut_geometry, write_lips

        problem = inclusion_problem(8, 2, "sticking", "quadrilateral")
        problem.solve()
        u = [problem.space.field(problem.w, i, n) for i, n in enumerate(("u_minus", "u_plus"))]
        out = pathlib.Path({str(tmp_path)!r})
        write_lips(out / "result.vtu", problem.cut, *u)
        write_cut_geometry(out, problem.cut)
        """
    assert loaded(code) == set()
    for name in ("result", "subcells", "interface"):
        assert pyvista.read(tmp_path / f"{name}.vtu").n_cells > 0


@pytest.mark.parametrize("cell", ["quadrilateral", "triangle"])
def test_raw_vtu_equals_vtks(tmp_path, cell):
    """The raw ``.vtu`` written with numpy reads back as the grid VTK's own writer (LZ4)
    writes: points, cells, types and every array, values and dtypes."""
    problem = inclusion_problem(6, 2, "sticking", cell, comm=MPI.COMM_SELF)
    problem.solve()
    u = [problem.space.field(problem.w, i, n) for i, n in enumerate(("u_minus", "u_plus"))]
    arrays = lips_arrays(problem.cut, *u)
    grids = {}
    for compression in ("none", "lz4"):
        write_vtu(tmp_path / f"{compression}.vtu", arrays, compression)
        grids[compression] = pyvista.read(tmp_path / f"{compression}.vtu")
    raw, vtk = grids["none"], grids["lz4"]
    np.testing.assert_array_equal(raw.points, vtk.points)
    np.testing.assert_array_equal(raw.celltypes, vtk.celltypes)
    np.testing.assert_array_equal(raw.cell_connectivity, vtk.cell_connectivity)
    np.testing.assert_array_equal(raw.cell_offsets, vtk.cell_offsets)
    for mine, theirs in ((raw.point_data, vtk.point_data), (raw.cell_data, vtk.cell_data)):
        assert set(mine) == set(theirs) and len(mine) > 0
        for name in theirs:
            assert mine[name].dtype == theirs[name].dtype, name
            np.testing.assert_array_equal(mine[name], theirs[name])
    assert set(raw.cell_data) == {"side", "cut", "cell"} and "u" in raw.point_data


def test_unknown_compression_is_refused(tmp_path):
    problem = inclusion_problem(4, 1, "sticking", "quadrilateral", comm=MPI.COMM_SELF)
    with pytest.raises(ValueError, match="compression 'gzip' is not one of 'none', 'lz4'"):
        write_vtu(tmp_path / "x.vtu", subcell_arrays(problem.cut), "gzip")


def test_run_outputs_open_in_vtk(tmp_path):
    """The demo's writers: the lips grid and the cut's, each a whole readable ``.vtu``."""
    problem = inclusion_problem(6, 2, "sticking", "quadrilateral", comm=MPI.COMM_SELF)
    problem.solve()
    u = [problem.space.field(problem.w, i, n) for i, n in enumerate(("u_minus", "u_plus"))]
    write_lips(tmp_path / "result.vtu", problem.cut, *u)
    write_cut_geometry(tmp_path, problem.cut)
    lips = pyvista.read(tmp_path / "result.vtu")
    cells = pyvista.read(tmp_path / "subcells.vtu")
    assert np.isclose(lips.area, 1.0) and cells.area < 1.0
