# The two commands a user needs: `make demo` and `make test`. Both set everything up first.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: setup acados prebuild demo showcase study test test-fast lint bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

setup: $(STAMP)

# Optional: acados (SQP_RTI + HPIPM), the peer `bench --only nmpc` measures our fast path
# against. Its package ships a slim CasADi (no IPOPT) over ours; reinstalling our pinned
# CasADi afterwards restores IPOPT and keeps acados working (its generated code links its own
# libraries).
ACADOS_STAMP := $(VENV)/.acados
$(ACADOS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet --no-deps comma-deps-acados
	$(PY) -m pip install --quiet --force-reinstall --no-deps \
		"casadi==$$($(PY) -c 'import importlib.metadata as m; print(m.version("casadi"))')"
	$(PY) -c "from experiments.bench.acados_peer import acados_unavailable as u; \
		import sys; sys.exit(u() or 0)"
	touch $(ACADOS_STAMP)

acados: $(ACADOS_STAMP)

demo: setup prebuild
	$(PY) -m scripts.demo

showcase: setup prebuild
	$(PY) -m experiments.showcase

study: setup
	$(VENV)/bin/study --out out/study

# The simulator's compiled loops built once into numba's cache, before the processes that fly it
# start (on a fresh clone pytest's workers, or the demo's endpoints, each compiled them at once
# otherwise: vehicle_sim/prebuild.py).
prebuild: setup
	$(PY) -m vehicle_sim.prebuild

test: setup lint prebuild
	$(PY) -m pytest -n 4 --dist worksteal -q --durations=15

test-fast: setup prebuild
	$(PY) -m pytest -n 2 --dist worksteal -q -m "not slow"

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

bench: setup
	$(VENV)/bin/bench

clean:
	rm -rf $(VENV) out .pytest_cache
