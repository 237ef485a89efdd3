# shipgym: every target creates/reuses .venv in the repository and installs what it needs from
# the lock files (requirements/lock.txt: core, lock-dev.txt: test and dev extras, lock-rl.txt:
# rl extra), then the project itself. `make help` lists the targets.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip
LOCK     := requirements/lock.txt
LOCK_DEV := requirements/lock-dev.txt
LOCK_RL  := requirements/lock-rl.txt
LOCK_RAY := requirements/lock-ray.txt
# Stamps: a changed lock file (or pyproject.toml) reinstalls. tests/test_lock.py looks for them.
STAMP     := $(VENV)/.lock-core
DEV_STAMP := $(VENV)/.lock-dev
RL_STAMP  := $(VENV)/.lock-rl
RAY_STAMP := $(VENV)/.lock-ray
# pytest-random-order seed of `make test-random` (unset: a new one each run, printed first)

SHELL := /bin/bash
.SHELLFLAGS := -o pipefail -ec
# pip install, quietly: this machine's pip configuration adds local package indexes that lack
# most names, and pip's "Location ... is ignored" notice for each of them is noise; so is
# setuptools' note on editable installs.
define pip_install
	@echo "pip install $(1)"
	@PYTHONWARNINGS="ignore:Editable installation" $(PIP) install --quiet $(1) 2>&1 | \
		{ grep -v "^WARNING: Location '.*' is ignored" || true; }
endef

.DEFAULT_GOAL := help
.PHONY: help demo test test-random test-slow bench rerecord lint docs docs-serve venv rl ray zoo lock dist dist-check clean

help: ## this list
	@echo "make targets (each creates/reuses .venv and installs the locked versions it needs):"
	@grep -hE '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | \
		awk 'BEGIN {FS = ":.*## "}; {printf "  %-12s %s\n", $$1, $$2}'

$(PY):
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found; install Python 3.11 or run 'make PYTHON=python3 ...'"; exit 1; }
	$(PYTHON) -m venv $(VENV)

# The locked pip first, then every locked package, then the project without dependencies (the
# lock has the build backend, so no isolated build environment is fetched).
$(STAMP): $(LOCK) pyproject.toml | $(PY)
	$(call pip_install,"$$(grep -m1 '^pip==' $(LOCK))")
	$(call pip_install,-r $(LOCK))
	$(call pip_install,--no-deps --no-build-isolation -e .)
	@touch $(STAMP)

# The test and dev extras (pytest, hypothesis, python-control, ruff, mypy).
$(DEV_STAMP): $(STAMP) $(LOCK_DEV)
	$(call pip_install,-r $(LOCK_DEV) -c $(LOCK))
	@touch $(DEV_STAMP)

venv: $(DEV_STAMP) ## the venv with the core, test and dev dependencies (no torch)

# The RL extra: torch on its own first, with plain pip, which picks the CPU build where one lies
# on the machine (a pip that finds only the package index's Linux build also installs that
# build's CUDA packages, which the lock leaves out); then stable-baselines3 and the rest of the
# extra. TORCH_PIP_ARGS adds pip options to the torch step only, e.g. an --extra-index-url of
# the CPU or of one CUDA build of torch.
TORCH_PIP_ARGS ?=
$(RL_STAMP): $(DEV_STAMP) $(LOCK_RL)
	$(call pip_install,"$$(grep -m1 '^torch==' $(LOCK_RL))" $(TORCH_PIP_ARGS) \
		-c $(LOCK) -c $(LOCK_DEV) -c $(LOCK_RL))
	$(call pip_install,-r $(LOCK_RL) -c $(LOCK) -c $(LOCK_DEV))
	@touch $(RL_STAMP)

rl: $(RL_STAMP) ## the venv plus the rl extra (torch 2.13.0 CPU build first, stable-baselines3)

# The ray extra (--executor ray of the benchmarks): Ray and what it needs.
$(RAY_STAMP): $(DEV_STAMP) $(LOCK_RAY)
	$(call pip_install,-r $(LOCK_RAY) -c $(LOCK) -c $(LOCK_DEV))
	@touch $(RAY_STAMP)

ray: $(RAY_STAMP) ## the venv plus the ray extra (sweeps as Ray tasks: --executor ray)

# The zoo extra (rl-zoo3) conflicts with the core pins (python-dateutil, pillow): it goes into
# .venv-zoo, a venv on top of .venv (a .pth adds .venv's packages after its own), so only what
# rl-zoo3 adds or needs older is installed there; not locked, not part of `make test`.
ZOO_VENV := .venv-zoo
zoo: $(RL_STAMP) ## rl-zoo3 2.9.2 in .venv-zoo on top of .venv (make test-slow then runs it)
	@test -x $(ZOO_VENV)/bin/python || $(PYTHON) -m venv $(ZOO_VENV)
	@base=$$($(PY) -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])'); \
	 own=$$($(ZOO_VENV)/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])'); \
	 echo "import site; site.addsitedir('$$base')" >"$$own/shipgym-venv.pth"
	$(ZOO_VENV)/bin/python -m pip install --quiet "rl_zoo3==2.9.2" -c $(LOCK_DEV) -c $(LOCK_RL) 2>&1 | \
		{ grep -v "^WARNING: Location '.*' is ignored" || true; }

# The harbour manoeuvre of Tomera (2014) in the lake-trial wind, PID + Kalman-Bucy filter:
# a rerun recording, PNG figures and metrics.md in runs/demo/.
demo: $(STAMP) ## the harbour manoeuvre: recording, figures and metrics in runs/demo/
	$(PY) -m shipgym.cli run harbour --wind 3@300 --observer kbf --controller pid-smooth \
		--no-progress \
		--json runs/demo/harbour.json --record runs/demo/harbour.rrd --report runs/demo

# The tests include stable-baselines3's check_env, so they need the RL extra. They run on
# TEST_WORKERS processes (pytest-xdist; auto: one a core, at most 4); TEST_WORKERS=0 runs them
# in this process, in file order. An idle worker steals queued tests from a busy one
# (--dist worksteal): the long, compile-heavy tests no longer leave one worker running alone
# at the end (a fresh clone's suite about 40 s shorter here).
TEST_WORKERS ?= auto
test: $(RL_STAMP) ## the test suite (slow tests skipped), on TEST_WORKERS processes
	$(PY) -m pytest -q -n $(TEST_WORKERS) --maxprocesses=4 --dist worksteal

test-random: $(RL_STAMP) ## the test suite in a shuffled order (SEED=N repeats an order)
	@seed=$${SEED:-$$(( RANDOM * 32768 + RANDOM ))}; \
	echo "shuffled test order, seed $$seed: 'make test-random SEED=$$seed' repeats it"; \
	echo "$(PY) -m pytest -q --random-order-bucket=global --random-order-seed=$$seed"; \
	$(PY) -m pytest -q --random-order-bucket=global --random-order-seed=$$seed

# With .venv-zoo (make zoo) the slow tests include rl-zoo3 training the shipped files.
test-slow: $(RL_STAMP) ## only the slow tests (the fuzz test of random episodes, ...)
	$(if $(wildcard $(ZOO_VENV)/bin/python),SHIPGYM_ZOO_PYTHON=$(abspath $(ZOO_VENV))/bin/python) \
		$(PY) -m pytest -q -m slow

bench: $(RL_STAMP) ## speed: headline ratios (runs/bench/bench.json), physics, disturbances, allocation
	$(PY) benchmarks/bench_summary.py
	$(PY) benchmarks/bench_physics.py
	$(PY) benchmarks/bench_disturbances.py
	$(PY) benchmarks/bench_allocation.py

rerecord: $(RL_STAMP) ## re-record the shipped baselines' reproduction fingerprints (tools/)
	$(PY) tools/rerecord_baselines.py

# The docs site (mkdocs.yml; the pages made from the code: tools/docs_hooks.py). The docs tools
# are in the dev lock, so make test builds the site too (tests/test_docs.py).
docs: $(DEV_STAMP) ## build the docs site into site/ (warnings are errors)
	NO_MKDOCS_2_WARNING=1 MPLBACKEND=Agg $(PY) -m mkdocs build --strict

docs-serve: $(DEV_STAMP) ## serve the docs site at http://127.0.0.1:8000, rebuilt on changes
	NO_MKDOCS_2_WARNING=1 MPLBACKEND=Agg $(PY) -m mkdocs serve --dev-addr 127.0.0.1:8000

lint: $(DEV_STAMP) ## ruff check and format check
	$(VENV)/bin/ruff check shipgym tests benchmarks tools
	$(VENV)/bin/ruff format --check shipgym tests benchmarks tools

# The sdist and the wheel of the working tree in dist/: python -m build without an isolated
# build environment (the locked setuptools and wheel build them, offline; the wheel is built
# from the sdist, so a file the sdist leaves out is missing from the wheel too), checked by
# twine; tools/wheel_assets.py counts the wheel's data files and fails where one the tree has
# is missing.
DIST := dist
dist: $(DEV_STAMP) ## the sdist and the wheel in dist/, twine-checked, their assets counted
	@mkdir -p $(DIST) && rm -f $(DIST)/shipgym-* $(DIST)/build.log
	@echo "$(PY) -m build --no-isolation --outdir $(DIST) . (its log: $(DIST)/build.log)"
	@$(PY) -m build --no-isolation --outdir $(DIST) . >$(DIST)/build.log 2>&1 || \
		{ tail -n 40 $(DIST)/build.log; exit 1; }
	@grep '^Successfully' $(DIST)/build.log
	$(VENV)/bin/twine check --strict $(DIST)/shipgym-*
	$(PY) tools/wheel_assets.py $(DIST)/shipgym-*.whl

# The wheel installed into a fresh venv of each Python in DIST_PYTHONS (their dependencies from
# the package index within pyproject's ranges, constrained by requirements/lock.txt) and
# tools/smoke.py run there from outside the repository (tools/dist_check.sh). A Python that is
# not found is skipped with a message, or fails the target where CI is true.
DIST_PYTHONS ?= python3.11 python3.12 python3.13
dist-check: dist ## the wheel in fresh venvs of Python 3.11, 3.12, 3.13: tools/smoke.py in each
	bash tools/dist_check.sh $(DIST)/shipgym-*.whl $(DIST_PYTHONS)

lock: ## regenerate requirements/lock*.txt from the ranges in pyproject.toml
	PYTHON=$(PYTHON) bash requirements/lock.sh

clean: ## remove the venv, caches and built distributions
	rm -rf $(VENV) .pytest_cache .ruff_cache .mypy_cache build dist *.egg-info
