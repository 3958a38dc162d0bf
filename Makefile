# `make` installs into .venv (and compiles the numba kernels into their cache: python -m
# vibroimpact.warm, so that no job of a build compiles one; and keeps the workflow's code
# digests, python -m vibroimpact.pipeline.digest_cache, so that no Snakemake start parses the
# package) and builds every figure and report
# of the default config, then Snakemake's own report of that build (results/report.html);
# `make test` installs and runs the linter (ruff: the rules in pyproject.toml), the format
# of the Snakemake files (snakefmt), the import-layer contracts, then the fast suite and
# the slow (stress/convergence), end-to-end workflow and SLURM suites in one session on three
# workers (the test config is built once, on one worker, while the others run the suites that
# build their own copies, the slow tests and the fast ones; whichever worker is free takes the
# next test, so none waits for the others at the end of a suite; the SLURM suite installs
# and starts a one-node cluster, as root); `make test-fast` runs the fast suite alone,
# `make test-slow` the others; `make lint` runs Snakemake's linter, ruff and snakefmt.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
CORES  ?= all
# the fast suite's tests on both cores (pytest-xdist; the kernels come compiled from the
# installation, vibroimpact.warm, and every build and suite loads them from numba's cache)
FAST_WORKERS ?= -n 2
# the slow, workflow and SLURM suites in one session on three workers: every test of the
# built test config on one worker (xdist group `built`, tests/conftest.py: the rebuild-scope
# cases start from a copy of that build), every other test on whichever worker is free. xdist
# hands out the largest group first, so the build starts at once. Three workers on two
# cores: a worker often waits (on a build's Snakemake scheduling its jobs, on SLURM, on
# disk), and the third keeps both cores busy meanwhile (README, "Tests": measured times)
LONG_WORKERS ?= -n 3 --dist loadgroup
LONG_MARKERS := slow or workflow or slurm
# `make test`: the fast suite and the long ones in that one session (one start of the workers,
# and no worker idle at the end of the fast suite while the other finishes its last test)
ALL_MARKERS := $(LONG_MARKERS) or not ($(LONG_MARKERS))
# The exact environment: requirements.lock (every distribution, its version and hashes,
# written by uv from pyproject.toml's direct requirements: `make lock`) installed by uv alone,
# `uv pip sync --require-hashes`: .venv then holds the lock's distributions and nothing else,
# each file checked against its hash (tests/test_release.py checks the venv against the
# lock). uv itself comes from the lock too, installed by pip with its hashes checked.
# --compile-bytecode: uv leaves the packages without their .pyc files (pip writes them), and
# every job then compiled matplotlib, xarray and scipy from source at import: +2.3 CPU-s a
# figure job, +100 CPU-s a default build (a fresh clone of 5101ed1: 365 CPU-s against 262)
LOCK := requirements.lock
# your own config, layered on config/config.yaml: make CONFIG=my_study.yaml
CONFIG ?=
CONFIG_ARGS := $(if $(CONFIG),--configfile $(CONFIG))

.PHONY: all plan report stale clean-stale test test-fast test-slow docs bench lint lock clean
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
	$(BIN)/vibroimpact stale $(CONFIG_ARGS)

clean-stale: $(STAMP)
	$(BIN)/vibroimpact stale --delete $(CONFIG_ARGS)

$(STAMP): $(LOCK) pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python tools/environment.py entry uv > $(VENV)/uv.lock
	$(BIN)/python -m pip install --quiet --disable-pip-version-check --require-hashes \
	  --no-deps -r $(VENV)/uv.lock
	$(BIN)/uv pip sync --quiet --compile-bytecode --require-hashes --python $(BIN)/python $(LOCK)
	$(BIN)/uv pip install --quiet --compile-bytecode --python $(BIN)/python --no-deps \
	  --no-build-isolation -e .
	$(BIN)/vibroimpact warm --jobs 2
	$(BIN)/python -m vibroimpact.pipeline.digest_cache
	touch $(STAMP)

# the seconds-long checks first: a lint failure stops the build before the half-hour suites
test: $(STAMP)
	$(BIN)/ruff check src tests benchmarks tools workflow/scripts docs
	$(BIN)/snakefmt --check workflow/
	$(BIN)/lint-imports
	$(BIN)/python -m pytest -q -m "$(ALL_MARKERS)" $(LONG_WORKERS)

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q $(FAST_WORKERS)

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m "$(LONG_MARKERS)" $(LONG_WORKERS)

# requirements.lock again from pyproject.toml's direct requirements (the package's, the slurm
# extra, the dev and docs groups), keeping every pin that still satisfies them; `make lock UPGRADE=1`
# moves every distribution to its newest allowed version. Then the conda environment of the
# rules, from the lock. Python 3.11.5: the oldest 3.11 the locked distributions support.
lock: $(STAMP)
	$(BIN)/uv pip compile pyproject.toml --extra slurm --group dev --group docs --universal \
	  --python-version 3.11.5 --generate-hashes --quiet $(if $(UPGRADE),--upgrade) \
	  --custom-compile-command "make lock" -o $(LOCK)
	$(BIN)/python tools/environment.py conda

# the documentation site, docs/_build/html/index.html: the pages, the config reference from the
# schema, the API reference from the docstrings and the tutorials, executed as it builds
# (offline; any warning fails it)
docs: $(STAMP)
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html
	@echo "the site: docs/_build/html/index.html"

bench: $(STAMP)
	$(BIN)/python benchmarks/bench_simulate.py

lint: $(STAMP)
	$(BIN)/snakemake --lint
	$(BIN)/ruff check src tests benchmarks tools workflow/scripts docs
	$(BIN)/snakefmt --check workflow/

clean:
	rm -rf results
