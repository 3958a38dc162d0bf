"""Rebuild scope: after a build, an edit reruns exactly the jobs it touches
(README, "What reruns").

The session's build of the test config (``built``) is copied, with Snakemake's records, into a
temporary git repository holding the working tree; each case edits one thing there and reads
the job list of ``snakemake -n``. The package is imported from
that copy (PYTHONPATH), so an edit of its sources is an edit of the code the workflow runs. A
code edit is a statement appended to a module: comments and docstrings rerun nothing.
"""
import os
from pathlib import Path
import re
import shutil
import socket
import subprocess
import sys

import pytest
import yaml

from helpers import RUN_STATE, copy_kernel_cache, copy_tree

#: on the worker of the session's build (`make test` runs it with --dist loadgroup): `repo`
#: starts from a copy of it
pytestmark = [pytest.mark.workflow, pytest.mark.xdist_group("built")]

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
# a figure reruns the report that shows it
FIGURE_RULES = {"draw_figure", "copy_paper_figure", "study_report", "all"}
REPORT_RULES = {"orbits_report", "validation_report"}
STRESS_RULES = {"sample_stress_families", "draw_validation_figure", "validation_report"}
VALIDATION_RULES = STRESS_RULES | {"measure_work_precision"}
STUDY_RULES = {"simulate_events", "simulate_spectra", "simulate_trace", "aggregate_events",
               "aggregate_spectra"}
ORBIT_RULES = {"solve_orbit_tile", "aggregate_orbits", "trace_boundaries"}
# the basins and Lyapunov exponents run the simulator's kernel against the orbit solver's
ATTRACTOR_RULES = {"solve_attractor_tile", "aggregate_attractors"}
# the predictors of the map's P (rule map_predictors) read the map, Fig. 16 and the attractors
PREDICTOR_RULES = {"map_predictors"}
# Fig. 16's orbits solved at the map's cells read the map and the orbit map
MAP_ORBIT_RULES = {"solve_map_orbits"}
MAP_RULES = {"simulate_map", "aggregate_map"} | PREDICTOR_RULES | MAP_ORBIT_RULES
ESCAPE_RULES = {"simulate_escape", "aggregate_escape"}


def _git(repo, *args):
    subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True,
                   env={**os.environ, "GIT_AUTHOR_NAME": "t", "GIT_AUTHOR_EMAIL": "t@t",
                        "GIT_COMMITTER_NAME": "t", "GIT_COMMITTER_EMAIL": "t@t"})


def _snakemake(repo, *args):
    env = {**os.environ, "PYTHONPATH": str(repo / "src")}
    out = subprocess.run([SNAKEMAKE, *args, "--cores", "2", "--configfile", "config/test.yaml"],
                         cwd=repo, capture_output=True, text=True, timeout=900, env=env)
    if out.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{out.stdout[-3000:]}\n"
                             f"{out.stderr[-3000:]}")
    return out.stdout + out.stderr


def scheduled(repo):
    """``{rule: {outputs}}`` of the jobs a dry run would execute."""
    jobs = {}
    rule = None
    for line in _snakemake(repo, "-n").splitlines():
        match = re.match(r"^(?:local)?rule (\w+):$", line.strip())
        if match:
            rule = match[1]
            jobs.setdefault(rule, set())
        elif rule and line.strip().startswith("output:"):
            jobs[rule].update(p.strip() for p in line.split(":", 1)[1].split(","))
    return jobs


@pytest.fixture(scope="module")
def repo(tmp_path_factory, built):
    """A git repository holding the working tree, with the session's build of the test config
    and Snakemake's records of it (the code, params and inputs of every output: the package
    in the copy is the same, so nothing is scheduled), and the kernels the session has
    compiled (numba's cache is not in git, and no case runs a kernel edited)."""
    repo = copy_tree(tmp_path_factory.mktemp("rebuild"))
    copy_kernel_cache(repo)
    shutil.copytree(built / "results", repo / "results")
    shutil.copytree(built / ".snakemake", repo / ".snakemake", symlinks=True,
                    ignore=shutil.ignore_patterns(*RUN_STATE))
    _git(repo, "init", "-q")
    _git(repo, "add", "-A")
    _git(repo, "commit", "-qm", "base")
    assert scheduled(repo) == {}
    return repo


@pytest.fixture()
def edit(repo):
    """Edit files of ``repo`` for one case; restore them (and the git history) afterwards."""
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True,
                          text=True, check=True).stdout.strip()
    saved = {}

    def change(path, func):
        """Write ``func(text)`` to ``path``; a new file when ``path`` does not exist."""
        path = repo / path
        saved.setdefault(path, path.read_text() if path.exists() else None)
        path.write_text(func(path.read_text() if path.exists() else ""))

    yield change
    for path, text in saved.items():
        if text is None:
            path.unlink()
        else:
            path.write_text(text)
    _git(repo, "reset", "-q", "--hard", head)


def _set(key_path, value):
    def func(text):
        cfg = yaml.safe_load(text)
        node = cfg
        for key in key_path[:-1]:
            node = node[key]
        node[key_path[-1]] = value
        return yaml.safe_dump(cfg, sort_keys=False)
    return func


def _append_comment(text):
    return text + "\n# an edit\n"


def _append_code(text):
    return text + "\n_EDITED = True\n"


def _reword_docstring(text):
    assert text.lstrip().startswith('"""')
    return text.replace('"""', '"""Reworded. ', 1)


def test_commits_of_nothing_docs_readme_tests_rerun_nothing(repo, edit):
    _git(repo, "commit", "-q", "--allow-empty", "-m", "empty")
    assert scheduled(repo) == {}
    for path in ("README.md", "docs/model.md", "tests/test_stats.py"):
        edit(path, _append_comment)
    _git(repo, "commit", "-qam", "docs, readme, tests")
    assert scheduled(repo) == {}


def test_plan_and_lint_change_nothing_on_disk(repo):
    """A plain dry run leaves a stale temporary of a killed writer (`python -m vibroimpact
    run` removes it before it hands over), and `--lint` passes."""
    name = f".x.nc.999999999.0123456789ab@{socket.gethostname()}.tmp"    # pid: none alive
    stale = repo / "results" / "datasets" / name
    stale.write_bytes(b"x")
    try:
        assert scheduled(repo) == {}
        assert stale.exists()
        _snakemake(repo, "--lint")
        assert stale.exists()
    finally:
        stale.unlink()


def test_docstring_or_comment_edits_rerun_nothing(repo, edit):
    for module in ("pipeline/tasks.py", "stats/events.py", "_checks.py"):
        edit(f"src/vibroimpact/{module}", _reword_docstring)
    edit("src/vibroimpact/impact/kernels.py", _append_comment)
    assert scheduled(repo) == {}


def test_a_new_module_reruns_exactly_the_jobs_that_import_it(repo, edit):
    edit("src/vibroimpact/validation/_timing.py", lambda text: "REPEATS = 3\n")
    edit("src/vibroimpact/validation/work_precision.py",
         lambda text: text + "\nfrom vibroimpact.validation import _timing  # noqa: E402\n")
    jobs = scheduled(repo)
    assert jobs == {"measure_work_precision": {"results/validation/work_precision.nc"},
                    "draw_validation_figure": {"results/figures/work_precision.png",
                                               "results/figures/work_precision.pdf"},
                    "validation_report": {f"results/reports/validation/performance.{ext}"
                                          for ext in ("ipynb", "html", "summary.html")},
                    "all": set()}
    edit("src/vibroimpact/validation/_timing.py", _append_comment)
    assert scheduled(repo) == jobs
    # a module no job imports reruns nothing
    edit("src/vibroimpact/validation/work_precision.py", lambda text: text.rsplit("from", 1)[0])
    assert scheduled(repo) == {}


def test_plotting_edit_reruns_only_figures(repo, edit):
    edit("src/vibroimpact/plotting/_common.py", _append_code)
    jobs = scheduled(repo)
    drawn = FIGURE_RULES | REPORT_RULES | {"draw_validation_figure"}
    assert set(jobs) == drawn
    _git(repo, "commit", "-qam", "plotting")          # committed or not: the same jobs
    assert set(scheduled(repo)) == drawn


def test_figure_only_key_reruns_only_that_figure(repo, edit):
    edit("config/test.yaml", _set(("studies", "random", "density_delta"), [0.5, 0.0]))
    jobs = scheduled(repo)
    assert set(jobs) == FIGURE_RULES
    drawn = {Path(p).name for p in jobs["draw_figure"] if p.endswith(".png")}
    assert drawn == {"fig07.png", "fig08.png"}
    edit("config/test.yaml", _set(("studies", "random", "figures"),
                                  ["fig03", "fig04", "fig05", "fig06", "fig07", "fig08",
                                   "fig09"][::-1]))
    assert set(scheduled(repo)) == FIGURE_RULES


def test_simulator_edit_reruns_the_studies_and_downstream(repo, edit):
    edit("src/vibroimpact/impact/kernels.py", _append_code)    # uncommitted
    jobs = scheduled(repo)
    assert set(jobs) == (STUDY_RULES | MAP_RULES | ESCAPE_RULES | ATTRACTOR_RULES | FIGURE_RULES
                         | REPORT_RULES | VALIDATION_RULES)
    assert "fig16.png" not in {Path(p).name for p in jobs["draw_figure"]}
    assert {"basins.png", "lyapunov.png"} <= {Path(p).name for p in jobs["draw_figure"]}


def test_statistics_edit_reruns_the_studies_that_use_it(repo, edit):
    edit("src/vibroimpact/stats/events.py", _append_code)
    jobs = scheduled(repo)
    assert {"simulate_events", "aggregate_events", "simulate_map", "aggregate_map"} <= set(jobs)
    # no event statistics in a trace, a spectrum or a noise record
    assert not {"simulate_trace", "simulate_spectra", "generate_noise"} & set(jobs)


def test_physical_value_reruns_that_study(repo, edit):
    edit("config/test.yaml", _set(("studies", "random", "eps"), 0.6))
    jobs = scheduled(repo)
    assert set(jobs) == STUDY_RULES | FIGURE_RULES
    assert "generate_noise" not in jobs


def test_noise_edit_reruns_everything_it_feeds(repo, edit):
    edit("config/test.yaml", _set(("noises", "random_input", "rms"), 0.4))
    assert set(scheduled(repo)) == {"generate_noise"} | STUDY_RULES | FIGURE_RULES


def test_orbit_entry_or_solver_edit_reruns_only_the_orbit_figures(repo, edit):
    edit("config/test.yaml", _set(("orbits", "harmonic", "delta"),
                                  {"start": -1.5, "stop": 3.0, "step": 0.5}))
    jobs = scheduled(repo)
    assert set(jobs) == (ORBIT_RULES | MAP_ORBIT_RULES | PREDICTOR_RULES | FIGURE_RULES
                         | {"orbits_report"})
    # the basins figure draws the map's stable domains; the attractors do not read its grid
    assert {Path(p).name for p in jobs["draw_figure"] if p.endswith(".png")} == {
        "fig16.png", "fig15_vs_fig16.png", "basins.png"}
    (repo / "config/test.yaml").write_text((ROOT / "config/test.yaml").read_text())
    edit("config/test.yaml", _set(("orbits", "harmonic", "attractors", "n_starts"), 4))
    jobs = scheduled(repo)
    # (the test config copies neither to a paper target; the study reports that show the
    # map over this entry read the basins and exponents as predictors of the probabilities)
    assert set(jobs) == ATTRACTOR_RULES | PREDICTOR_RULES | {"draw_figure", "orbits_report",
                                                             "study_report", "all"}
    assert {Path(p).name for p in jobs["draw_figure"] if p.endswith(".png")} == {
        "basins.png", "lyapunov.png"}
    (repo / "config/test.yaml").write_text((ROOT / "config/test.yaml").read_text())
    edit("src/vibroimpact/orbits/kernels.py", _append_code)     # the stress sample too
    assert set(scheduled(repo)) == (ORBIT_RULES | MAP_ORBIT_RULES | ATTRACTOR_RULES
                                    | PREDICTOR_RULES
                                    | FIGURE_RULES | {"orbits_report"} | STRESS_RULES)


def test_a_predictors_edit_reruns_their_job_and_the_reports_showing_the_map(repo, edit):
    """The predictors of P are computed once (rule map_predictors) and read by the reports
    that show the map (the two harmonic studies' and the orbits entry's): an edit of their
    code reruns those, nothing else (no figure, no other report)."""
    edit("src/vibroimpact/reports/predictors.py", _append_code)
    jobs = scheduled(repo)
    assert jobs == {"map_predictors": {"results/datasets/motion_map_predictors.nc"},
                    "study_report": {f"results/reports/{study}/harmonic_random.{ext}"
                                     for study in ("harmonic", "motion_map")
                                     for ext in ("ipynb", "html", "summary.html")},
                    "orbits_report": {f"results/reports/orbits/harmonic/periodic_motions.{ext}"
                                      for ext in ("ipynb", "html", "summary.html")},
                    "all": set()}


def test_outputs_record_the_dirty_flag(repo, edit):
    """A job run in the repository records its commit, clean; run again after an edit that
    reruns nothing (a README line), the same commit, dirty. (The copied build records the
    commit of the tree the session built it from.)"""
    import xarray as xr

    path = repo / "results/datasets/random_events.nc"
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=repo, capture_output=True,
                            text=True, check=True).stdout.strip()
    for dirty in (0, 1):
        if dirty:
            edit("README.md", _append_comment)
        _snakemake(repo, "--force", "results/datasets/random_events.nc")
        with xr.open_dataset(path) as ds:
            assert (ds.attrs["git_commit"], ds.attrs["git_dirty"]) == (commit, dirty)
