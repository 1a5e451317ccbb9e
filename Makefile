# Every target creates or refreshes .venv itself: a fresh clone needs only Python 3.11 and pip.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# Three installs in the one .venv: the core package alone (what `make demo` needs), the core and
# the docs extra (`make docs`: the site needs no PyTorch, pyproject.toml), and everything
# (every extra and the dev tools: `make test`, `make lint`, `make bench`). Each has its stamp, so
# `make demo` then `make test` adds the rest, and `make test` then `make demo` or `make docs`
# installs nothing.
CORE_STAMP := $(VENV)/.core-stamp
DOCS_STAMP := $(VENV)/.docs-stamp
STAMP := $(VENV)/.installed-stamp
# The CPU build of PyTorch, pinned and installed before the extras so that pip never resolves
# a newer (CUDA, several-GB) torch for Stable-Baselines3.
TORCH := torch==2.13.0

.PHONY: venv gl browser demo test docs lint bench clean clean-cache

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --upgrade pip

$(CORE_STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install -e .
	touch $(CORE_STAMP)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install $(TORCH)
	$(PY) -m pip install -e ".[all,dev]" $(TORCH)
	touch $(STAMP) $(CORE_STAMP) $(DOCS_STAMP)

$(DOCS_STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install -e ".[docs]"
	touch $(DOCS_STAMP) $(CORE_STAMP)

venv: $(STAMP)

# MuJoCo's offscreen renderer needs a GL library (EGL, else OSMesa). Where neither is found and
# apt-get may be used (root), install Mesa's EGL; otherwise carry on: rendering then falls back to
# the 2-D renderer (skidnav.physics.backend).
gl:
	-@if ! ldconfig -p 2>/dev/null | grep -q -e 'libEGL.so.1' -e 'libOSMesa.so'; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "installing Mesa EGL for offscreen rendering"; \
	    (apt-get install -y -q libegl1 libegl-mesa0 libgl1-mesa-dri >/dev/null 2>&1 || \
	     (apt-get update -q >/dev/null 2>&1 && apt-get install -y -q libegl1 libegl-mesa0 libgl1-mesa-dri >/dev/null 2>&1)) || \
	      echo "no GL library: MuJoCo pictures fall back to the 2-D renderer"; \
	  else echo "no GL library: MuJoCo pictures fall back to the 2-D renderer"; fi; \
	fi

# The browser tests (tests/docs/, tests/browser_support.py) drive Debian's chromium through its
# chromedriver: a browser downloaded at run time would fail here. Where either is missing and
# apt-get may be used (root), install both; otherwise say so, and the tests fail under make test.
browser:
	-@if ! command -v chromium >/dev/null || ! command -v chromedriver >/dev/null; then \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    echo "installing chromium and chromium-driver for the browser tests"; \
	    (apt-get install -y -q chromium chromium-driver >/dev/null 2>&1 || \
	     (apt-get update -q >/dev/null 2>&1 && apt-get install -y -q chromium chromium-driver >/dev/null 2>&1)) || \
	      echo "could not install chromium: the browser tests will fail"; \
	  else echo "no chromium: install chromium and chromium-driver for the browser tests"; fi; \
	fi

# Runs the demo, writes its report and prints the report's one-line verdict and path.
demo: $(CORE_STAMP)
	$(VENV)/bin/skidnav run configs/quick.toml --out runs/quick --report

# SKIDNAV_MAKE_TEST=1: everything optional is installed, so a test that needs it fails rather
# than skips. The notebooks are executed top to bottom (nbmake) once the suite has compiled the
# kernels.
test: lint gl browser
	SKIDNAV_MAKE_TEST=1 $(PY) -m pytest
	SKIDNAV_MAKE_TEST=1 $(PY) -m pytest --nbmake notebooks

# The documentation site, into site/ (mkdocs.yml): every warning, a broken link, anchor or image
# among them, is an error. (Not --quiet: it would silence the warnings that --strict counts.)
# Open site/index.html from disk or serve site/: both work, search included.
docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks docs/tools
	$(VENV)/bin/ruff format --check src tests benchmarks docs/tools
	$(VENV)/bin/mypy src
	$(VENV)/bin/lint-imports --no-cache

bench: $(STAMP)
	$(PY) benchmarks/run_all.py

# The current commit's key figures and time to learn measured and recorded, then every figure
# named that moved by more than FACTOR (default 2) since the last commit recorded on this
# machine (docs/speed.md).
.PHONY: bench-compare
bench-compare: $(STAMP)
	$(PY) benchmarks/history.py compare $(if $(FACTOR),--factor $(FACTOR))

# numba's on-disk cache does not notice edits to helpers inlined from another module:
# after changing a kernel, clear it.
clean-cache:
	find src tests -name "*.nbi" -delete -o -name "*.nbc" -delete
	rm -rf "$${XDG_CACHE_HOME:-$$HOME/.cache}/skidnav/numba"

clean: clean-cache
	rm -rf $(VENV) runs site .pytest_cache .mypy_cache .ruff_cache
