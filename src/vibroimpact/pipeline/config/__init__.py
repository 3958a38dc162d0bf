"""The workflow's config: read, layered, checked and costed before any job runs.

One place for everything that can be known about a config before a simulation starts, so
that a bad value stops the build at once with a message of one or two lines naming the key
path, the value and the allowed range, instead of failing minutes into a build. One module
per step, in the order :func:`load` takes them:

- `layering`: :func:`read_yaml` reads a config file strictly; :func:`compose` layers a
  user's file on the paper's config (``config/config.yaml``).
- `sweeps`: :func:`expand_sweeps` turns a study that lists values (a sweep) into one
  ordinary study per combination.
- `messages`: :func:`validate` checks against the schema
  (``workflow/schemas/config.schema.yaml``), filling its
  defaults (the one place a default is written), and words every problem.
- `checks`: :func:`check`, the cross-field relations (records, grids, figures).
- `plan` and `costs`: the :class:`Plan` of the build (cells, jobs, disk, CPU), refused
  beyond ``limits``, from the one cost model that the rule resources use too.

The Snakefile and the ``python -m vibroimpact`` entry point both call :func:`load`, so a
dry run, a build and the plan see the same config and the same errors. Importing this
package loads no numba, no scipy and no kernel.
"""
from pathlib import Path

from vibroimpact.pipeline import layout
from vibroimpact.pipeline.config.checks import check
from vibroimpact.pipeline.config.layering import (SECTIONS, check_size, compose, deep_merge,
                                                  read_yaml)
from vibroimpact.pipeline.config.messages import (VERBOSE_ENV, ConfigError, non_text_keys,
                                                  validate)
from vibroimpact.pipeline.config.messages import _short  # noqa: F401 (how a value is shown)
from vibroimpact.pipeline.config.plan import Plan, make_plan
from vibroimpact.pipeline.study import Study
from vibroimpact.pipeline.config.sweeps import (SWEEP_KEYS, Sweeps, drawn_sweeps,
                                                expand_sweeps, sweep_label, sweep_labels)

__all__ = ["ConfigError", "Plan", "Sweeps", "read_yaml", "compose", "expand_sweeps", "validate",
           "check", "make_plan", "load", "drawn_sweeps", "sweep_label",
           "sweep_labels", "SECTIONS", "SWEEP_KEYS", "VERBOSE_ENV"]


def load(user=None, *, root=".", user_files=(), schema=None, paper=None):
    """Read the paper's config, layer ``user`` on it, expand its sweeps, validate and check.

    Returns ``(config, plan)``; ``config["sweeps"]`` records each sweep's studies and values
    (:func:`expand_sweeps`).

    Parameters
    ----------
    user : dict, optional
        The user's config (what ``--configfile`` files gave Snakemake, or a host workflow's
        ``module ...: config:``), or None.
    root : path
        The working directory: the build's ``results/`` is there.
    user_files : sequence of paths
        Files to read as the user's config (deep-merged in order) when ``user`` is None.
    schema, paper : path, optional
        The workflow's schema and the paper's config; by default those of the workflow a
        build in ``root`` runs (`vibroimpact.pipeline.layout.workflow_dir`). The Snakefile
        passes its own.
    """
    root = Path(root)
    workflow = layout.workflow_dir(root)
    schema = Path(schema) if schema is not None else workflow / layout.SCHEMA
    paper = Path(paper) if paper is not None else workflow / layout.PAPER_CONFIG
    if user is None and user_files:
        user = {}
        for path in user_files:
            user = deep_merge(user, read_yaml(path))
    else:
        check_size(user or {}, "the config given with --configfile")
    keys = non_text_keys(user or {})
    if keys:        # before anything sorts or looks up the names
        raise ConfigError(keys)
    schema = read_yaml(schema, user=False)
    paper = read_yaml(paper, user=False)
    config, own = compose(paper, user or {})
    if own is not None and "build" not in ((user or {}).get("validation") or {}):
        # paper: false builds the file's own entries; the validation runs are the paper's
        config["validation"] = {**(config.get("validation") or {}), "build": False}
    sweeps = expand_sweeps(config, own, max_studies=_max_jobs(config, schema))
    try:
        validate(config, schema)
        config["sweeps"] = sweeps.record    # after the schema, which knows only the user's keys
        grids = check(config, schema, own)
        # each study resolved once, from the grids the checks expanded (the plan and the
        # workflow's rules read these: `plan.studies`)
        studies = {name: Study.from_config(name, entry, grids=grids.get(name))
                   for name, entry in config["studies"].items()}
        plan = make_plan(config, own, results=root / "results", studies=studies)
        plan.refuse_beyond_limits()
    except ConfigError as err:
        raise sweeps.relabel(err) from None
    return config, plan


def _max_jobs(config, schema):
    """``limits.max_jobs`` of a config not yet validated (the schema's default if unusable)."""
    limits = config.get("limits")
    value = limits.get("max_jobs") if isinstance(limits, dict) else None
    if isinstance(value, int) and not isinstance(value, bool) and value >= 1:
        return value
    return schema["properties"]["limits"]["properties"]["max_jobs"]["default"]
