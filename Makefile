# make run  : set-up + the main job on embedded defaults
# make test : set-up + the whole test suite
# make bench: set-up + the benchmarks (JSON under logs/bench/)
SHELL := /bin/bash
PY ?= python3
# pytest-xdist processes for `make test` (a test file stays in one process: its module fixtures are built once)
TEST_WORKERS ?= 2
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
# the CPU wheel of torch 2.13.0 for the venv's Python (its tag, e.g. cp311: the venv's, or PY's before the venv
# exists) where the machine keeps one (PIP_FIND_LINKS folders), else empty
PY_TAG := $(shell $(if $(wildcard $(BIN)/python),$(BIN)/python,$(PY)) -c 'import sys; print("cp%d%d" % sys.version_info[:2])' 2>/dev/null)
TORCH_WHEEL := $(firstword $(wildcard $(addsuffix /torch-2.13.0+cpu-$(PY_TAG)-$(PY_TAG)-*.whl,$(PIP_FIND_LINKS))))
export MUJOCO_GL ?= osmesa
export PYOPENGL_PLATFORM ?= osmesa

.PHONY: setup run test bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/system_deps.sh
	bash scripts/system_deps.sh
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip "uv==0.13.8"
	# The CPU build of torch: a bare `torch` requirement could pull a multi-GB CUDA build. Where this machine keeps
	# its wheel on disk (PIP_FIND_LINKS) uv installs that file together with the rest, in one resolution (~39 s
	# here, against ~29 s for pip's torch install alone before uv's ~39 s: uv does not look in PIP_FIND_LINKS by
	# itself); elsewhere pip takes `torch==2.13.0` first. The rest through uv: the same versions as pip (compared
	# with pip freeze), in less than half pip's time here. --compile-bytecode as pip does: without the .pyc files
	# every process (PYTHONDONTWRITEBYTECODE is set on these machines) compiles the libraries it imports again,
	# 8.2 s instead of 4.6 s for the campaign's imports.
	torch="$(TORCH_WHEEL)"; if [ -z "$$torch" ]; then $(BIN)/python -m pip install -q "torch==2.13.0"; fi; \
	$(BIN)/uv pip install -q --compile-bytecode --python $(BIN)/python $$torch -e ".[test,cluster]"
	touch $(STAMP)

run: setup
	$(BIN)/wrp-eval run experiments/quickstart.yaml

test: setup
	$(BIN)/lint-imports --no-cache
	$(BIN)/ruff check wrp_eval tests scripts
	# mypy (one process, ~50 s on a fresh clone) type-checks beside the suite; its report follows the suite's,
	# and either failing fails the target. The numba kernels compile in the suite's processes as they need them:
	# compiling them all first in one process (37.5 s beside mypy) made the part after lint 284 s against 272 s
	# (a fresh kernel cache each, session 24). --durations: the slowest tests, for the next cut.
	$(BIN)/mypy > $(VENV)/mypy.log 2>&1 & typing=$$!; trap 'kill $$typing 2>/dev/null' INT TERM; \
	$(BIN)/python -m pytest -q -p no:cacheprovider -n $(TEST_WORKERS) --dist loadfile --durations=15; tests=$$?; \
	wait $$typing; typed=$$?; echo "mypy:"; cat $(VENV)/mypy.log; \
	if [ $$tests -ne 0 ]; then exit $$tests; fi; exit $$typed

bench: setup
	$(BIN)/wrp-eval bench --out logs/bench/

clean:
	rm -rf $(VENV) build *.egg-info
