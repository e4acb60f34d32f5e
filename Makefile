# One-command set-up, tests, demo and benchmarks (Debian 12, run as root).
#   make demo   installs what is missing, builds, runs the main demo
#   make test   installs what is missing, builds, lints, runs the C++ and Python tests
#   make lint   black --check and flake8 (settings: pyproject.toml, .flake8), clang-format (.clang-format)
#   make docs   installs the documentation's packages, builds the site (docs/_build/html)
#   make bench  the benchmarks (bench/); make bench-large: the 1.6e7-dof solve
SHELL := /bin/bash
.ONESHELL:
.SHELLFLAGS := -euo pipefail -c

VENV    := .venv
PY      := $(VENV)/bin/python
DEBS    := python3-dolfinx python3-petsc4py python3-mpi4py python3-gmsh \
           python3-scipy python3-sympy python3-matplotlib python3-pytest python3-pytest-xdist \
           python3-pybind11 pybind11-dev libeigen3-dev libgtest-dev libdolfinx-dev cmake g++ make \
           python3-venv python3-setuptools python3-wheel python3-pip python3-tqdm \
           python3-slepc4py python3-threadpoolctl python3-h5py-mpi openmpi-bin libopenblas-dev \
           black flake8 clang-format
# the documentation site (make docs) and its test (tests/test_docs.py: headless Chromium)
DOCS_DEBS := python3-sphinx python3-myst-parser furo libjs-mathjax chromium python3-pil
CXX_BUILD := build/cpp
CXX_FILES := $(wildcard bem_cpp/src/*.cpp bem_cpp/include/bem/*.hpp bem_cpp/tests/*.cpp bem_cpp/tests/*.hpp) \
             bem_cpp/bindings.cpp fem_py/mesh/cpp/placed_cells.cpp
SOURCES := $(wildcard bem_cpp/src/*.cpp bem_cpp/include/bem/*.hpp) bem_cpp/bindings.cpp \
           fem_py/mesh/cpp/placed_cells.cpp fem_py/mesh/cpp/CMakeLists.txt setup.py pyproject.toml

.PHONY: setup debs debs-docs venv build lint test test-cpp test-py demo bench bench-large study docs clean

setup: debs build

# install the packages of $(1) that are missing
define install_debs
	missing=$$(for p in $(1); do dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q "install ok installed" || echo $$p; done)
	if [ -n "$$missing" ]; then
	  echo "installing Debian packages:" $$missing
	  export DEBIAN_FRONTEND=noninteractive
	  apt-get update -q
	  apt-get install -y -q --no-install-recommends $$missing
	fi
endef

debs:
	$(call install_debs,$(DEBS))

debs-docs:
	$(call install_debs,$(DOCS_DEBS))

$(PY):
	/usr/bin/python3 -m venv --system-site-packages $(VENV)

venv: $(PY)

# Editable install; the stamp is rebuilt whenever a C++ source or the build files change.
$(VENV)/.built: $(PY) $(SOURCES)
	$(PY) -m pip install --no-build-isolation --no-deps --no-index -q -e .
	touch $@

build: debs $(VENV)/.built

# the site is built (its demo runs included) before pytest, in a process of its own;
# tests/test_docs.py then checks it (rebuilding only what changed)
test: setup debs-docs lint test-cpp docs test-py

# formatters and linter from Debian (black 23, flake8 5, clang-format 14); the tree must pass all
lint: debs venv
	$(PY) -m black --check --quiet .
	$(PY) -m flake8 .
	clang-format --dry-run --Werror $(CXX_FILES)

test-cpp:
	cmake -S bem_cpp -B $(CXX_BUILD) -DCMAKE_BUILD_TYPE=Release > /dev/null
	cmake --build $(CXX_BUILD) -j 2 > /dev/null
	ctest --test-dir $(CXX_BUILD) --output-on-failure

# one pytest worker per core (at most 4; a file's tests stay on one worker, so its module
# fixtures are built once); one BLAS/OpenMP thread per worker, so workers do not oversubscribe
# the cores (the runs the tests start under mpirun have one thread per rank already)
test-py:
	OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -q -n auto --maxprocesses 4 --dist loadfile

demo: setup
	$(PY) demos/demo_signorini_square.py

bench: setup
	$(PY) bench/bem_assembly.py
	$(PY) bench/steklov_mpi.py
	$(PY) bench/steklov_mpi.py --shapes box --sizes 32 64 --layouts 1x1 1x2 2x1
	$(PY) bench/pgpm_profile.py
	$(PY) -m bench.peers
	$(PY) bench/strong_scaling.py --output bench/scaling.md
	$(PY) bench/strong_scaling.py --shape box --method ssn --repeat 2 --output bench/scaling_box.md
	$(PY) bench/outputs.py
	$(PY) bench/speed.py
	$(PY) bench/solid.py
	$(PY) bench/elastic_counts.py
	$(PY) bench/elastic.py --dim 2
	$(PY) bench/elastic.py --dim 3

# the 1.6e7-dof run of bench/speed.py (nested, the compact data; ~10 min, ~18 GB)
bench-large: setup
	$(PY) bench/speed.py --sizes 4000 --data compact --kinds nested

study: setup
	$(PY) -m study

# warnings are errors (-W, nitpicky); the demos run at small sizes (docs/_ext/fembem_docs)
docs: build debs-docs
	$(PY) -m sphinx -b html -W --keep-going -n -q docs docs/_build/html
	echo "open docs/_build/html/index.html"

clean:
	rm -rf build $(VENV) *.egg-info bem_cpp/*.so fem_py/mesh/*.so docs/_build docs/api docs/demos
