# make demo / make test / make bench: each creates .venv when absent.
SHELL := /bin/bash
VENV := .venv
PY := $(VENV)/bin/python
MPIEXEC := $(VENV)/bin/mpiexec
# First Python >= 3.12 found: python3.12 on PATH, then pyenv's, then python3.
PYTHON ?= $(shell for p in python3.12 $$HOME/.pyenv/versions/3.12*/bin/python3.12 python3.13 python3; do \
	$$p -c 'import sys; assert sys.version_info >= (3, 12)' >/dev/null 2>&1 && { echo $$p; break; }; done)

.PHONY: demo test test-serial test-mpi test-notebooks docs bench bench-peer lint clean bytecode

$(VENV)/.installed: pyproject.toml setup.py xfem_contact/_bootstrap.py
	@test -n "$(PYTHON)" || { echo "error: no Python >= 3.12 found (set PYTHON=...)"; exit 1; }
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $@

# Bytecode of the package's own (editable) sources, brought up to date: pip compiles a
# wheel's at install, but with PYTHONDONTWRITEBYTECODE=1 (set on some machines, this one
# included) every process would compile the package's modules again (0.2 s a process).
bytecode: $(VENV)/.installed
	@$(PY) -m compileall -q xfem_contact >/dev/null

demo: $(VENV)/.installed bytecode
	$(PY) demos/inclusion_contact.py

test: $(VENV)/.installed bytecode
	$(MAKE) test-serial
	$(MAKE) test-mpi
	$(MAKE) test-notebooks
	$(MAKE) docs

# The tests compile their kernels at -O0, through DOLFINx's own JIT configuration file in
# a config folder of their own: the suite's meshes are small, so its time on an empty
# cache is the C compiler's (a crack's tip-zone kernel: about 30 s at -O1, 5 s at -O0).
# FFCx names a module by its flags, so these kernels never serve the demos or benchmarks.
# Test modules marked assembly_bound (assembling the same 3D kernels over many Newton
# steps) keep the library's -O1 (tests/conftest.py).
TEST_CONFIG := $(VENV)/test-config
TEST_ENV := XDG_CONFIG_HOME=$(CURDIR)/$(TEST_CONFIG)

$(TEST_CONFIG)/dolfinx/dolfinx_jit_options.json: Makefile
	@mkdir -p $(@D)
	@echo '{"cffi_extra_compile_args": ["-O0", "-g0"]}' > $@

# both cores (pytest-xdist), one test file per worker at a time (module fixtures built once)
test-serial: $(VENV)/.installed $(TEST_CONFIG)/dolfinx/dolfinx_jit_options.json
	$(TEST_ENV) $(PY) -m pytest -q -n 2 --dist loadfile tests

test-mpi: $(VENV)/.installed $(TEST_CONFIG)/dolfinx/dolfinx_jit_options.json
	$(TEST_ENV) $(MPIEXEC) -n 2 $(PY) -m pytest -q -m mpi -p no:cacheprovider tests

test-notebooks: $(VENV)/.installed $(TEST_CONFIG)/dolfinx/dolfinx_jit_options.json
	@if ls notebooks/*.ipynb >/dev/null 2>&1; then \
		$(TEST_ENV) $(PY) -m pytest -q -n 2 --nbmake notebooks; \
	else echo "no notebooks yet"; fi

# the documentation site, warnings as errors (make test builds it too)
docs: $(VENV)/.installed
	$(PY) -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

bench: $(VENV)/.installed bytecode
	$(PY) bench/quadrature.py
	$(PY) bench/contact_convergence.py
	$(PY) bench/scaling.py --ranks 2
	$(PY) bench/iterative.py --tiny
	$(PY) bench/rotating_inclusion.py --no-progress
	$(PY) bench/accuracy_vs_time.py --no-progress
	$(PY) bench/moving_interface.py --no-progress
	$(PY) bench/parameter_sweep.py --no-progress
	$(PY) bench/crack_convergence.py --no-progress
	$(PY) bench/inf_sup.py --elements P1-P1
	$(PY) bench/inf_sup.py --elements P2-P1
	$(PY) bench/inf_sup.py --circles 50 --sizes 8 16 32 64 --cells quadrilateral --elements P2-P1 --name inf_sup_P2-P1_quadrilateral
	$(PY) bench/inf_sup.py --elements P2-P2 --sizes 8 16 32 --circles 12 --treatments none restriction stabilized "stabilized, ghost 0.1" --name inf_sup_P2-P2
	$(PY) bench/inf_sup.py --circles 12 --treatments "stabilized, ghost 0.1" --name inf_sup_P1-P1_P2-P1_stabilized_ghost_0.1
	$(PY) bench/inf_sup.py --circles 12 --treatments "stabilized, aggregation 0.25" --name inf_sup_P1-P1_P2-P1_stabilized_aggregation_0.25
	$(PY) bench/inf_sup.py --study crack
	$(PY) bench/inf_sup.py --study 3d --sizes 4 8 12
	$(PY) bench/inf_sup.py --study 3d --cells hexahedron --elements P2-P1 --treatments restriction --sizes 4 8 --name inf_sup_3d_hexahedron_P2-P1_restriction_4_8
	$(PY) bench/inf_sup.py --study 3d --cells hexahedron --elements P2-P1 --treatments stabilized --sizes 4 8 12 --name inf_sup_3d_hexahedron_P2-P1_stabilized_4_8_12
	$(PY) bench/inf_sup.py --study 3d --cells tetrahedron --elements P2-P1 --treatments restriction --sizes 6 8 10 12 14 16 --name inf_sup_3d_tetrahedron_P2-P1_restriction_6_8_10_12_14_16
	$(PY) bench/sphere_unstructured.py
	$(PY) bench/inf_sup.py --study 3d --sizes 4 8 --spheres 12 --cells tetrahedron --treatments stabilized --name inf_sup_3d_spheres
	$(PY) bench/inf_sup.py --study 3d --sizes 4 8 --spheres 12 --cells tetrahedron --elements P1-P1 --treatments "stabilized, ghost 0.1" "stabilized, aggregation 0.25" --name inf_sup_3d_spheres_P1-P1_ghost_aggregation
	$(PY) bench/inf_sup.py --study crack --cells quadrilateral --elements P1-P1 P2-P1 --cracks 6 --name inf_sup_crack_quadrilateral
	$(PY) bench/multiplier_degree.py
	$(PY) bench/aggregation.py
	$(PY) bench/cut3d.py --sizes 4 8 16 32
	$(PY) bench/cut3d.py --fuzz 10000 --sizes
	$(PY) bench/cut3d_assembly.py --sizes 16 --quadrature-degrees 2 4 6
	$(PY) bench/scale3d.py --sizes 4 8 --direct-max 8
	$(PY) bench/accuracy_vs_time3d.py --quick --out bench/results/accuracy_vs_time3d_quick.json
	$(PY) bench/sphere_rate3d.py --sizes 4 8 12 16 --centres 5 --write
	$(PY) bench/robustness3d.py --write
	@if test -x $(PEER_PY); then $(PY) bench/peer_cut3d.py --peer-python $(PEER_PY); \
	else echo "skipped bench/peer_cut3d.py (the ngsxfem peer): 'make bench-peer' creates $(PEER_VENV) and runs it"; fi

# The optional peer (ngsxfem) in its own venv, never a dependency of the package
PEER_VENV := bench/.peer-venv
PEER_PY := $(PEER_VENV)/bin/python

$(PEER_VENV)/.installed:
	@test -n "$(PYTHON)" || { echo "error: no Python >= 3.12 found (set PYTHON=...)"; exit 1; }
	@test -x $(PEER_PY) || $(PYTHON) -m venv $(PEER_VENV)
	$(PEER_PY) -m pip install --quiet xfem ngsolve
	touch $@

bench-peer: $(VENV)/.installed bytecode $(PEER_VENV)/.installed
	$(PY) bench/peer_cut3d.py --peer-python $(PEER_PY)

lint: $(VENV)/.installed
	$(VENV)/bin/ruff check xfem_contact tests demos bench

clean:
	rm -rf $(VENV) build *.egg-info
