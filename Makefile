# shipgym: every target creates/reuses .venv in the repository and installs what it needs.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-core

.PHONY: demo test bench lint venv rl clean

$(PY):
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "error: $(PYTHON) not found; install Python 3.11 or run 'make PYTHON=python3 ...'"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(STAMP): $(PY) pyproject.toml
	$(PY) -m pip install --quiet -e ".[test,dev]"
	@touch $(STAMP)

RL_STAMP := $(VENV)/.installed-rl

venv: $(STAMP)

# Optional RL extra: torch's CPU build first (pinned, so pip never pulls CUDA), then SB3.
$(RL_STAMP): $(STAMP)
	$(PY) -m pip install --quiet "torch==2.13.0"
	$(PY) -m pip install --quiet -e ".[rl]"
	@touch $(RL_STAMP)

rl: $(RL_STAMP)

# The harbour manoeuvre of Tomera (2014) in the lake-trial wind, PID + Kalman-Bucy filter:
# a rerun recording, PNG figures and metrics.md in runs/demo/.
demo: $(STAMP)
	$(PY) -m shipgym.cli run harbour --wind 3@300 --observer kbf --controller pid-smooth \
		--no-progress \
		--json runs/demo/harbour.json --record runs/demo/harbour.rrd --report runs/demo

# The tests include stable-baselines3's check_env, so they need the RL extra.
test: $(RL_STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) benchmarks/bench_physics.py

lint: $(STAMP)
	$(VENV)/bin/ruff check shipgym tests benchmarks
	$(VENV)/bin/ruff format --check shipgym tests benchmarks

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache .mypy_cache build *.egg-info
