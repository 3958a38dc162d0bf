# `make` installs into .venv and builds every figure and report of the default config, then
# Snakemake's own report of that build (results/report.html);
# `make test` installs and runs the fast suite, the slow (stress/convergence) suite, the
# end-to-end workflow and SLURM suites (one session: the test config is built once; the
# SLURM suite installs and starts a one-node cluster, as root), the linter (ruff: the rules
# in pyproject.toml), the import-layer contract and the format of the Snakemake files
# (snakefmt); `make lint` runs Snakemake's linter, ruff and snakefmt.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
CORES  ?= all
# your own config, layered on config/config.yaml: make CONFIG=my_study.yaml
CONFIG ?=
CONFIG_ARGS := $(if $(CONFIG),--configfile $(CONFIG))

.PHONY: all plan report test test-fast test-slow bench lint clean
# checks the config, prints the plan, recovers from a killed run, then runs Snakemake; then
# writes Snakemake's report of the build, whole or not at all
all: $(STAMP)
	$(BIN)/python -m vibroimpact run --cores $(CORES) $(CONFIG_ARGS)
	$(BIN)/python -m vibroimpact report $(CONFIG_ARGS)

report: $(STAMP)
	$(BIN)/python -m vibroimpact report $(CONFIG_ARGS)

plan: $(STAMP)
	$(BIN)/python -m vibroimpact plan --cores $(CORES) $(CONFIG_ARGS)

$(STAMP): environment.txt pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check -r environment.txt
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --no-build-isolation --no-deps -e .
	touch $(STAMP)

test: $(STAMP)
	$(BIN)/python -m pytest -q
	$(BIN)/python -m pytest -q -m slow
	$(BIN)/python -m pytest -q -m "workflow or slurm"
	$(BIN)/ruff check src tests benchmarks workflow/scripts
	$(BIN)/lint-imports
	$(BIN)/snakefmt --check Snakefile workflow/

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_simulate.py

lint: $(STAMP)
	$(BIN)/snakemake --lint
	$(BIN)/ruff check src tests benchmarks workflow/scripts
	$(BIN)/snakefmt --check Snakefile workflow/

clean:
	rm -rf results
