# `make` installs into .venv (and compiles the numba kernels into their cache: python -m
# vibroimpact.warm, so that no job of a build compiles one) and builds every figure and report
# of the default config, then Snakemake's own report of that build (results/report.html);
# `make test` installs and runs the linter (ruff: the rules in pyproject.toml), the format
# of the Snakemake files (snakefmt), the import-layer contracts, then the fast suite, the
# slow (stress/convergence) suite on two workers, the end-to-end workflow and SLURM suites
# (one session on two workers: the test config is built once, on one worker, while the other
# runs the suites that build their own copies; the SLURM suite installs and starts a
# one-node cluster, as root); `make lint` runs Snakemake's linter, ruff and snakefmt.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
CORES  ?= all
# the fast suite's tests and the slow suite's independent stress tests on both cores
# (pytest-xdist; the fast suite is CPU-bound, mostly numba compilation on a fresh clone)
FAST_WORKERS ?= -n 2
SLOW_WORKERS ?= -n 2
# the workflow and SLURM suites on both cores: every test of the built test config on one
# worker (xdist group `built`, tests/conftest.py), the other tests grouped by module
WORKFLOW_WORKERS ?= -n 2 --dist loadgroup
# your own config, layered on config/config.yaml: make CONFIG=my_study.yaml
CONFIG ?=
CONFIG_ARGS := $(if $(CONFIG),--configfile $(CONFIG))

.PHONY: all plan report stale clean-stale test test-fast test-slow bench lint clean
# checks the config, prints the plan, recovers from a killed run, then runs Snakemake; then
# writes Snakemake's report of the build, whole or not at all
all: $(STAMP)
	$(BIN)/python -m vibroimpact run --cores $(CORES) $(CONFIG_ARGS)
	$(BIN)/python -m vibroimpact report $(CONFIG_ARGS)

report: $(STAMP)
	$(BIN)/python -m vibroimpact report $(CONFIG_ARGS)

plan: $(STAMP)
	$(BIN)/python -m vibroimpact plan --cores $(CORES) $(CONFIG_ARGS)

# outputs of the config's entries that it no longer builds (an earlier config's figures of the
# same study ...): `stale` lists them, `clean-stale` removes them (README, "Outputs")
stale: $(STAMP)
	$(BIN)/python -m vibroimpact.pipeline.stale $(CONFIG_ARGS)

clean-stale: $(STAMP)
	$(BIN)/python -m vibroimpact.pipeline.stale --delete $(CONFIG_ARGS)

$(STAMP): environment.txt pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -r environment.txt
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --no-build-isolation --no-deps -e .
	$(BIN)/python -m vibroimpact.warm --jobs 2
	touch $(STAMP)

# the seconds-long checks first: a lint failure stops the build before the half-hour suites
test: $(STAMP)
	$(BIN)/ruff check src tests benchmarks workflow/scripts
	$(BIN)/snakefmt --check Snakefile workflow/
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q $(FAST_WORKERS)
	$(BIN)/python -m pytest -q -m slow $(SLOW_WORKERS)
	$(BIN)/python -m pytest -q -m "workflow or slurm" $(WORKFLOW_WORKERS)

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_simulate.py

lint: $(STAMP)
	$(BIN)/snakemake --lint
	$(BIN)/ruff check src tests benchmarks workflow/scripts
	$(BIN)/snakefmt --check Snakefile workflow/

clean:
	rm -rf results
