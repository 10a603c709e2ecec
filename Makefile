# ClothLight developer entry points. Both README commands go through here:
#   make demo   set up the environment and run the main job on the default (red cotton fitted to a real fabric)
#   make test   set up the environment and run the test suite
# and for development:
#   make test-fast  the pure-Python tier (no bpy, no renders, no bakes), in seconds
#   make lint       ruff, as .ci/run runs it before the tests
#
# The virtual environment lives outside the clone, keyed by the hash of everything that
# defines it, so repeated runs and fresh clones on the same machine reuse it; a new machine
# builds it from scratch.  Override with `make VENV=/some/path ...`.
PYTHON ?= python3.11
ENV_HASH := $(shell cat requirements.txt scripts/setup_env.py | sha256sum | cut -c1-12)
VENV ?= $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/clothlight/venv-$(ENV_HASH)
PY := $(VENV)/bin/python
STAMP := $(VENV)/.clothlight-installed
OUT ?= out

# numba keeps compiled kernels beside their sources (__pycache__), keyed by the source files: the
# kernels are compiled once per checkout here rather than during the first job, and the native slab
# library is built beside them (docs/transport.md).
KERNEL_STAMP := precompute/transport/__pycache__/.kernels-compiled

.PHONY: setup demo test test-fast lint bench extension clean

setup: $(STAMP) $(KERNEL_STAMP)

$(STAMP): requirements.txt scripts/setup_env.py
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	$(PY) scripts/setup_env.py
	@touch $(STAMP)
	@echo "environment ready: $(VENV)"

$(KERNEL_STAMP): $(STAMP) $(wildcard precompute/transport/*.py) precompute/tables/grids.py precompute/slab/layout.py \
		precompute/slab/native.py
	$(PY) -m precompute.transport.compile
	@touch $(KERNEL_STAMP)

demo: setup
	$(PY) scripts/run_demo.py --out $(OUT)

# pytest keeps its assertion-rewritten test modules as bytecode; where the environment sets
# PYTHONDONTWRITEBYTECODE it rewrites all of them in every worker on every run (~6 s a worker).
PYTEST = env -u PYTHONDONTWRITEBYTECODE $(PY) -m pytest

test: setup
	$(PYTEST)

# CLOTHLIGHT_TESTS_WITHOUT_BPY makes `import bpy` fail (tests/conftest.py): the tier must not need it.
test-fast: setup
	CLOTHLIGHT_TESTS_WITHOUT_BPY=1 $(PYTEST) -n auto -m "not blender and not render and not slow"

lint: setup
	$(PY) -m ruff check .

bench: setup
	$(PY) -m benchmarks

extension: setup
	$(PY) scripts/build_extension.py --output-dir dist --prebake-cloth

clean:
	rm -rf $(OUT) dist .pytest_cache
