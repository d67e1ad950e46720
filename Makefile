# sarfe — the two commands: `make demo` (set up + run the door trim case), `make test` (set up + tests).
# Everything a fresh Debian machine needs is installed by `make setup` (called by both).

PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
# One BLAS thread per process: on 2 shared cores oversubscribed BLAS threads cost 10-100x.
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1
export MPLBACKEND := Agg
# gmsh's wheel links FLTK/OpenGL even headless; these are the Debian libraries it needs.
# chromium: the report test renders report.html in a real headless browser (skipped without it).
APT_PACKAGES := libglu1-mesa libgl1 libxcursor1 libxft2 libxinerama1 libgomp1 chromium

.PHONY: setup system-deps test test-all demo bench clean

setup: $(VENV)/.installed

system-deps:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	fi

$(VENV)/.installed: pyproject.toml | system-deps
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[dev]'
	touch $@

test: setup
	$(PY) -m pytest -q

test-all: setup
	$(PY) -m pytest -q -m ''

demo: setup
	$(VENV)/bin/sarfe solve cases/door_trim.yaml

bench: setup
	$(PY) benchmarks/run_all.py

clean:
	rm -rf $(VENV) results .pytest_cache
