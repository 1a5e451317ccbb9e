# Every target creates or refreshes .venv itself: a fresh clone needs only Python 3.11 and pip.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed-stamp
# The CPU build of PyTorch, pinned and installed before the extras so that pip never resolves
# a newer (CUDA, several-GB) torch for Stable-Baselines3.
TORCH := torch==2.13.0

.PHONY: venv gl demo test lint bench clean clean-cache

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet $(TORCH)
	$(PY) -m pip install --quiet -e ".[dev,physics,deep]" $(TORCH)
	touch $(STAMP)

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

# Runs the demo, writes its report and prints the report's one-line verdict and path.
demo: $(STAMP) gl
	$(VENV)/bin/skidnav run configs/quick.toml --out runs/quick --report

test: lint gl
	$(PY) -m pytest

lint: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/ruff format --check src tests benchmarks
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
	find src tests -name '*.nbi' -delete -o -name '*.nbc' -delete

clean: clean-cache
	rm -rf $(VENV) runs .pytest_cache .mypy_cache .ruff_cache
