"""The on-disk kernel cache knows the runtime layout: a new layout version compiles new
kernels instead of loading those of an older layout (``runtime_abi.LAYOUT_VERSION``)."""

import dolfinx.fem
import numpy as np
import pytest
import ufl
from conftest import unit_square

import xfem_contact
from xfem_contact.codegen import runtime_abi
from xfem_contact.fem import forms


def compile_in(cache_dir, cut):
    """Compile ``x^2 dx(-1)`` as a fresh process would (empty in-process cache, the
    on-disk cache ``cache_dir``): the JIT module's name, whether FFCx generated C code
    (False: loaded from the disk cache), the C code and the runtime kernel keys."""
    forms._cache.clear()
    x = ufl.SpatialCoordinate(cut.mesh)
    f = xfem_contact.form(x[0] ** 2 * cut.dx(-1), jit_options={"cache_dir": str(cache_dir)})
    (compiled,) = forms._cache.values()
    keys = sorted(k.key for k in compiled.kernels.values())
    assert keys, "the form has runtime kernels"
    value = dolfinx.fem.assemble_scalar(f)
    return compiled.module.__name__, compiled.code[1] is not None, compiled.code[1], keys, value


def test_a_new_layout_version_recompiles(tmp_path, monkeypatch):
    monkeypatch.setattr(forms, "_cache", {})
    mesh = unit_square(3, "triangle")
    cut = xfem_contact.CutMesh(mesh, lambda x: np.hypot(x[0] - 0.5, x[1] - 0.5) - 0.3)
    version = runtime_abi.LAYOUT_VERSION

    name, generated, code, keys, value = compile_in(tmp_path, cut)
    assert generated and all(f"kernel key {k}," in code for k in keys)
    # A restart with the same version loads the module from disk: no new C code
    again, generated_again, _, keys_again, _ = compile_in(tmp_path, cut)
    assert (again, generated_again, keys_again) == (name, False, keys)

    monkeypatch.setattr(runtime_abi, "LAYOUT_VERSION", version + 1)
    new, generated_new, code_new, keys_new, value_new = compile_in(tmp_path, cut)
    assert new != name, "the layout version is not in the JIT module's signature"
    assert generated_new, "a kernel of the old layout was loaded from the disk cache"
    assert set(keys_new).isdisjoint(keys), "the layout version is not in the kernel keys"
    assert all(f"kernel key {k}," in code_new for k in keys_new)
    assert value_new == pytest.approx(value, rel=1e-14)  # the new kernels read the rules
    assert len(list(tmp_path.glob("libffcx_forms_*.c"))) == 2


def test_dolfinx_configuration_files_take_precedence_over_the_defaults(tmp_path, monkeypatch):
    """A user's ``dolfinx_jit_options.json`` (DOLFINx's documented configuration: the
    config home's, then the working directory's over it) sets the compile flags of the
    cut forms too, over :data:`forms.JIT_DEFAULTS`."""
    home, work = tmp_path / "config", tmp_path / "work"
    (home / "dolfinx").mkdir(parents=True)
    work.mkdir()
    monkeypatch.setenv("XDG_CONFIG_HOME", str(home))
    monkeypatch.chdir(work)
    assert forms.configured_jit_options() == {}
    (home / "dolfinx" / "dolfinx_jit_options.json").write_text(
        '{"cffi_extra_compile_args": ["-O0"], "timeout": 7}'
    )
    (work / "dolfinx_jit_options.json").write_text('{"timeout": 9}')
    assert forms.configured_jit_options() == {"cffi_extra_compile_args": ["-O0"], "timeout": 9}
