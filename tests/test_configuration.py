"""Config layering, the plan and its limits, and the fault-recovery helpers (fast)."""
import os
from pathlib import Path
import signal
import socket
import subprocess
import sys
import textwrap
import time

import pytest
import yaml

from vibroimpact import _files
from vibroimpact.pipeline import config as configuration, figures

ROOT = Path(__file__).resolve().parents[1]
PAPER = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())

MINE = yaml.safe_load(textwrap.dedent("""\
    paper: false
    studies:
      mine:
        noise: harmonic_input      # the paper's record, used by name
        zeta: 0.1
        eps: 0.8
        delta: [0.0, 0.5, 1.0]
        figures: [fig09]
"""))


# --- layering ---------------------------------------------------------------------------------

def test_no_user_file_is_the_paper_config():
    config, plan = configuration.load(root=ROOT)
    assert set(config["studies"]) == set(PAPER["studies"])
    assert plan.drawn["paper_figures"] == set(PAPER["paper_figures"])


def test_paper_false_builds_only_the_users_entries_with_the_papers_noise():
    config, plan = configuration.load(MINE, root=ROOT)
    assert set(config["studies"]) == set(PAPER["studies"]) | {"mine"}   # still defined
    assert plan.drawn == {"studies": {"mine"}, "orbits": set(), "paper_figures": set()}
    assert [r.key for r in plan.rows] == ["noises.harmonic_input", "studies.mine", "reports"]
    assert config["validation"]["build"] is False       # the paper's validation runs: not built
    assert plan.cells == 3


def test_paper_true_builds_both():
    config, plan = configuration.load(dict(MINE, paper=True), root=ROOT)
    assert plan.drawn["studies"] == set(PAPER["studies"]) | {"mine"}
    _, paper_plan = configuration.load(root=ROOT)
    assert plan.cells == paper_plan.cells + 3


def test_a_colliding_entry_is_refused_unless_replaced():
    user = {"paper": False, "studies": {"random": dict(PAPER["studies"]["random"], zeta=0.1)}}
    with pytest.raises(configuration.ConfigError, match=r"replace: \[studies\.random\]"):
        configuration.load(user, root=ROOT)
    config, plan = configuration.load(dict(user, replace=["studies.random"]), root=ROOT)
    assert config["studies"]["random"]["zeta"] == 0.1
    assert plan.drawn["studies"] == {"random"}


def test_a_replaced_entry_is_replaced_whole_not_merged_key_by_key():
    mine = {k: v for k, v in PAPER["studies"]["random"].items() if k != "spectra"}
    mine["figures"] = ["fig07"]
    config, _ = configuration.load({"paper": False, "replace": True,
                                    "studies": {"random": mine}}, root=ROOT)
    assert "spectra" not in config["studies"]["random"]


def test_an_identical_entry_needs_no_replace():
    user = {"paper": False, "studies": {"random": PAPER["studies"]["random"]}}
    _, plan = configuration.load(user, root=ROOT)
    assert plan.drawn["studies"] == {"random"}


def test_a_users_validation_block_is_the_papers_unless_replaced():
    """`validation` follows the rule of `studies`: a block that differs from the paper's
    would overwrite results/validation/work_precision.nc, its figure and report; refused
    unless replaced. `validation.build` is the user's own (whether rule all builds it)."""
    one_run = {"solvers": ["RK45"], "repeats": 1}
    user = dict(MINE, validation={"build": True, "work_precision": one_run})
    with pytest.raises(configuration.ConfigError, match=r"validation\.work_precision: .* "
                       r"would overwrite its results"):
        configuration.load(user, root=ROOT)
    config, _ = configuration.load(dict(user, validation={"build": True}), root=ROOT)
    assert config["validation"]["build"] is True               # the paper's runs, unchanged
    paper = configuration.load(root=ROOT)[0]["validation"]
    assert {k: v for k, v in config["validation"].items() if k != "build"} == {
        k: v for k, v in paper.items() if k != "build"}
    same = dict(MINE, validation={"work_precision": PAPER["validation"]["work_precision"]})
    configuration.load(same, root=ROOT)                        # identical: no replace needed
    config, _ = configuration.load(dict(user, replace=["validation"]), root=ROOT)
    assert config["validation"]["work_precision"]["solvers"] == ["RK45"]
    assert config["validation"]["work_precision"]["delta"] == (   # replaced whole: defaults
        [1.0, 0.0, -0.5])


def test_stale_lists_only_the_drawn_entries_outputs_the_config_no_longer_builds(tmp_path):
    """`make stale`: an earlier config's figure of the same study (fig13-9), a dataset the
    study no longer needs, are listed and removed; the current outputs (their PDF and
    notebook twins), another study of a similar name and, with `paper: false`, the paper's
    outputs are not."""
    from vibroimpact.pipeline import stale, targets

    config, plan = configuration.load(root=ROOT)
    current = targets.needed_files(config, plan.drawn)
    twins = {p[:-4] + ".pdf" for p in current if p.endswith(".png")}
    twins |= {p[:-5] + ext for p in current if p.endswith(".html")
              for ext in (".ipynb", ".summary.html")}
    old = ["results/figures/harmonic/fig13-9.png", "results/figures/harmonic/fig13-9.pdf",
           "results/datasets/harmonic_map.nc", "results/reports/random/harmonic_random.html",
           "results/datasets/harmonic_basins.nc", "results/datasets/random_predictors.nc"]
    other = ["results/datasets/harmonic_two_events.nc", "results/figures/elsewhere/fig09.png"]
    for rel in [*current, *twins, *old, *other]:
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).touch()
    assert stale.stale_files(config, plan.drawn, tmp_path) == sorted(old)
    mine, mine_plan = configuration.load(MINE, root=ROOT)
    assert stale.stale_files(mine, mine_plan.drawn, tmp_path) == []    # the paper's: not its
    line = stale.summary(stale.stale_files(config, plan.drawn, tmp_path))
    assert line.startswith(f"vibroimpact: {len(old)} file(s) beside this config's outputs")
    assert "and 3 more" in line and "vibroimpact stale --delete" in line
    assert stale.main(["--directory", str(tmp_path), "--delete"]) == 0
    assert not any((tmp_path / rel).exists() for rel in old)
    assert all((tmp_path / rel).exists() for rel in [*current, *twins, *other])


@pytest.mark.parametrize("files", [[], ["config/test.yaml"], ["config/examples/clearance.yaml"],
                                   ["config/examples/planes.yaml"],
                                   ["config/examples/impact_law.yaml"]])
def test_every_dataset_a_build_needs_is_a_kind_of_the_one_table(files):
    """Every dataset the plan counts (`targets.needed_files`: the default config, the test
    config, each shipped example) is of one kind of `targets.DATASETS`, and `make stale`
    (`stale.owned_datasets`) scans that kind's place for its owner: a kind added to the
    table is listed by both, and a dataset written outside the table fails here."""
    import fnmatch
    from vibroimpact.pipeline import stale, targets

    config, plan = configuration.load(root=ROOT, user_files=[ROOT / f for f in files])
    kinds = {k: p.replace("{name}", "*").replace("{noise}", "*")
             for k, p in targets.DATASETS.items()}
    owned = {section: set(stale.owned_datasets(section)) for section in ("studies", "orbits")}
    seen = set()
    for path in sorted(targets.needed_files(config, plan.drawn)):
        if not path.startswith(("results/datasets/", "results/orbits/", "results/traces/",
                                "results/noise/")):
            continue
        # the table's most specific pattern that matches (``{name}.nc`` also matches
        # ``{name}_boundaries.nc``; an owner's name never holds the kinds' suffixes here)
        match = [k for k, pattern in kinds.items() if fnmatch.fnmatch(path, pattern)]
        assert match, f"{path}: of no kind of targets.DATASETS"
        kind = max(match, key=lambda k: len(targets.DATASETS[k]))
        seen.add(kind)
        if kind != "noise":
            section = "orbits" if path.startswith("results/orbits/") else "studies"
            assert targets.DATASETS[kind] in owned[section], (path, kind)
    assert seen, "no dataset needed"


def test_the_readme_quotes_the_current_plan_and_figure_table():
    """The README's generated blocks (benchmarks/readme_numbers.py --write README.md) are
    those of this tree: the plans of the default config and of the shipped examples, and the
    table of which figure an entry may list and what it needs, and the jobs' requests against
    their recorded use (tests/data/job_requests.json). A change to any fails here
    until the script is re-run; the build's own numbers name their build's commit and are
    not checked."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("readme_numbers",
                                                  ROOT / "benchmarks" / "readme_numbers.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    readme = (ROOT / "README.md").read_text()

    def block(name):
        marker = f"<!-- readme_numbers:{name} -->"
        start = readme.index(marker) + len(marker)
        return readme[start:readme.index(f"<!-- /readme_numbers:{name} -->")]

    _, plan = configuration.load(root=ROOT)
    assert block("plan").endswith(f"`benchmarks/readme_numbers.py`): {plan.summary(2)}")
    assert block("figures") == module.figures_text()
    for name in module.EXAMPLES:        # the shipped examples' plans, e.g. their job counts
        assert block(name) == module.example_plan_text(name)
    assert block("plan_finer") == module.finer_plan_text()
    assert block("requests") == module.requests_text()   # the recorded use, today's requests
    for fig in figures.FIGURES:
        assert f"| `{fig}` |" in block("figures")


# --- the plan ---------------------------------------------------------------------------------

def test_plan_of_the_paper_config():
    """Cells from the grids of config.yaml; disk and time within a factor of the default
    build measured at 61270b2 (120 MB on disk; 190 CPU-s in results/benchmarks), plus the
    escape study (~15 CPU-s estimated: 6 jobs and a figure; ~25 CPU-s measured on a shared
    node, benchmarks/bench_escape.py)."""
    _, plan = configuration.load(root=ROOT)
    assert plan.cells == 71 + 8 + 16 + 10 + 57 * 91 + 3 * 5   # 8 spectra plays; escape 3 x 5
    assert plan.orbit_cells == 141 * 226 + 57 * 91     # Fig. 16's map, the attractors' grid
    assert 60e6 < plan.bytes < 250e6
    assert 90 < plan.cpu_s < 650
    text = plan.format()
    for key in ("limits.max_cells", "limits.max_disk_gb", "studies.motion_map", "total"):
        assert key in text


def test_a_build_beyond_a_limit_is_refused_with_the_estimate_and_the_key():
    user = {"limits": {"max_cells": 1000}}
    with pytest.raises(configuration.ConfigError) as info:
        configuration.load(user, root=ROOT)
    text = str(info.value)
    assert "limits.max_cells = 1,000" in text and "5,307 simulation cells" in text
    assert "raise limits.max_cells" in text


def test_verbose_adds_the_validator_output(monkeypatch):
    user = {"paper": False, "studies": {"mine": dict(MINE["studies"]["mine"], zeta=-1.0)}}
    with pytest.raises(configuration.ConfigError) as short:
        configuration.load(user, root=ROOT)
    monkeypatch.setenv(configuration.VERBOSE_ENV, "1")
    with pytest.raises(configuration.ConfigError) as full:
        configuration.load(user, root=ROOT)
    assert len(str(short.value).splitlines()) == 1
    assert "Failed validating" in str(full.value)


# --- temporaries of interrupted writes --------------------------------------------------------

def _dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_sweep_removes_only_the_temporaries_of_dead_writers(tmp_path):
    host = socket.gethostname()
    dead = tmp_path / f".a.nc.{_dead_pid()}.0123456789ab@{host}.tmp"
    live = tmp_path / f".b.nc.{os.getpid()}.0123456789ab@{host}.tmp"
    elsewhere = tmp_path / ".c.nc.1.0123456789ab@another-node.tmp"
    old_elsewhere = tmp_path / ".d.nc.1.0123456789ab@another-node.tmp"
    unrelated = tmp_path / ".e.tmp"
    for p in (dead, live, elsewhere, old_elsewhere, unrelated):
        p.write_bytes(b"x")
    two_days_ago = time.time() - 3 * 24 * 3600
    os.utime(old_elsewhere, (two_days_ago, two_days_ago))
    removed = _files.sweep_stale_temporaries(tmp_path)
    assert sorted(removed) == sorted([dead, old_elsewhere])
    assert live.exists() and elsewhere.exists() and unrelated.exists()


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_while_writing_removes_the_temporary(tmp_path, sig):
    target = tmp_path / "out.nc"
    # Ctrl-C as at a terminal: a shell without job control starts background commands with
    # SIGINT ignored, which Python then keeps (the writer would never see the signal)
    code = textwrap.dedent(f"""
        import signal, sys, time
        from vibroimpact._files import atomic_path
        signal.signal(signal.SIGINT, signal.default_int_handler)
        with atomic_path({str(target)!r}) as tmp:
            open(tmp, "w").write("half")
            print(tmp, flush=True)
            time.sleep(60)
    """)
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    tmp = Path(proc.stdout.readline().strip())
    assert tmp.exists() and _files.TEMP_PATTERN.match(tmp.name)
    proc.send_signal(sig)
    assert proc.wait(timeout=30) != 0
    assert not tmp.exists() and not target.exists()


# --- progress of a job ------------------------------------------------------------------------

def test_progress_is_logged_at_its_start_at_a_bounded_rate_and_at_the_end(caplog):
    from vibroimpact.pipeline.tasks import Progress

    now = [0.0]
    with caplog.at_level("INFO", logger="vibroimpact"):
        progress = Progress("tile 0", 1000, every=20.0, clock=lambda: now[0], events=True)
        for _ in range(1000):
            now[0] += 0.1                    # 100 s of cells, one every 0.1 s
            progress.cell_done({"n_collisions": 3, "simulated_time": 2.0})
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 6                   # the start; every 20 s of 100 s; the last cell
    assert lines[0] == "progress tile 0: 0 of 1000 cells, started"
    assert lines[1].startswith("progress tile 0: 200 of 1000 cells, 600 collisions, 400 time")
    assert "~80 s left" in lines[1]
    assert lines[-1].startswith("progress tile 0: 1000 of 1000 cells, 3000 collisions")
    assert "~0 s left" in lines[-1]


def test_progress_of_other_units_has_no_simulation_counts(caplog):
    """A job that simulates nothing (orbits, boundaries) counts its units alone."""
    from vibroimpact.pipeline.tasks import Progress

    now = [0.0]
    with caplog.at_level("INFO", logger="vibroimpact"):
        progress = Progress("boundaries", 5, unit="types", every=1.0, clock=lambda: now[0])
        for _ in range(5):
            now[0] += 2.0
            progress.advance()
    lines = [r.getMessage() for r in caplog.records]
    assert lines[0] == "progress boundaries: 0 of 5 types, started"
    assert lines[1] == "progress boundaries: 1 of 5 types, 0.5 types/s, ~8 s left"
    assert len(lines) == 6 and lines[-1].endswith("5 of 5 types, 0.5 types/s, ~0 s left")


def test_a_per_figure_listed_by_name_alone_is_drawn_at_every_grid_value():
    """``fig14`` alone in a study with ``inv_beta: [0.5, 1.1]``: ``fig14-0`` at 0.5 and
    ``fig14-1`` at 1.1 (it crashed in the figure job, missing inv_beta); with one grid value
    the plain name."""
    entry = {"inv_beta": [0.5, 1.1], "figures": ["fig14", {"name": "fig13", "inv_beta": [1.1]}]}
    assert figures.figure_targets(entry) == ["fig14-0", "fig14-1", "fig13"]
    assert [figures.figure_options(entry, t)["inv_beta"] for t in ("fig14-0", "fig14-1")] == [
        0.5, 1.1]
    one = {"inv_beta": {"start": 1.1, "stop": 1.1, "step": 0.1}, "figures": ["fig12"]}
    assert figures.figure_targets(one) == ["fig12"]
    assert figures.figure_options(one, "fig12")["inv_beta"] == 1.1


def test_every_study_key_reaches_the_jobs_that_read_it():
    # a key that no job's params carry is silently ignored by the jobs (rebound_floor was)
    from vibroimpact.pipeline.study import JOB_KEYS

    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / "config.schema.yaml").read_text())
    keys = set(schema["$defs"]["study"]["properties"])
    by_jobs = set().union(*JOB_KEYS.values())
    by_figures = {key for fig in figures.FIGURES.values() for key in fig.get("options", ())}
    before_jobs = {"rms", "seed"}           # the sweep expansion makes them a noise record
    by_reports = {"figures", "report_with"}
    assert keys == by_jobs | by_figures | before_jobs | by_reports
    assert not by_jobs & by_figures         # a figure option reruns no simulation


def test_an_orbits_entry_writing_the_default_eps_lower_is_the_same_system(tmp_path):
    """The clearance example's orbits entry with ``eps_lower`` written as the default it
    takes (its eps) still draws the study's fig15_vs_fig16; a different one is refused."""
    from vibroimpact.pipeline.config.messages import ConfigError

    text = yaml.safe_load((ROOT / "config/examples/clearance.yaml").read_text())
    for value, refused in ((0.5, False), (0.6, True)):
        text["orbits"]["clearance"]["eps_lower"] = value
        path = tmp_path / "c.yaml"
        path.write_text(yaml.safe_dump(text))
        if refused:
            with pytest.raises(ConfigError, match=r"has eps_lower = 0\.6, the study "
                                                  r"eps_lower = 0\.5"):
                configuration.load(root=ROOT, user_files=[path])
        else:
            configuration.load(root=ROOT, user_files=[path])


def test_values_that_differ_past_six_digits_are_printed_apart():
    from vibroimpact.pipeline.config.checks import _told_apart

    assert _told_apart(1 / 1.1, 0.90909090909091) == ("0.909090909090909", "0.90909090909091")
    assert _told_apart(0.5, None) == ("0.5", "none")


def test_the_checks_know_the_schemas_default_escape_cells():
    from vibroimpact.pipeline.config.checks import DEFAULT_ESCAPE_CELLS

    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / "config.schema.yaml").read_text())
    escape = schema["$defs"]["study"]["properties"]["escape"]["properties"]
    assert escape["cells"]["default"] == DEFAULT_ESCAPE_CELLS


@pytest.mark.workflow
@pytest.mark.parametrize("files", [[], ["config/examples/clearance.yaml"],
                                   ["config/examples/planes.yaml"],
                                   ["config/examples/impact_law.yaml"]])
def test_every_file_a_build_writes_is_a_product_the_plan_and_make_stale_know(tmp_path, files):
    """Every file a build of the config writes (a dry run of every job, forced) is a product
    of the one table (`targets.PRODUCTS`, `targets.product_of`), a file made beside one
    (`targets.TWINS`) or an intermediate another job of the build reads (a tile, a level);
    the plan's files (`targets.needed_files`) are exactly its products; `make stale` lists
    none of them on a finished tree, and lists an earlier figure and report of each drawn
    entry beside them."""
    from helpers import make_workdir, scheduled_jobs
    from vibroimpact.pipeline import stale, targets

    work = make_workdir(tmp_path / "work")
    config_file = files[0] if files else "config/config.yaml"
    jobs = scheduled_jobs(work, "-F", config=config_file)
    written = {p for job in jobs for p in job["output"]}
    read = {p for job in jobs for p in job["input"]}

    def main(path):                 # a twin's product, or the path itself
        suffix = next((s for s in targets.TWINS if path.endswith(s)), None)
        return path if suffix is None else path[:-len(suffix)] + targets.TWINS[suffix]

    products = {p for p in written if targets.product_of(main(p))[0] is not None}
    orphans = sorted(p for p in written - products if p not in read)
    assert not orphans, f"written, of no kind of targets.PRODUCTS, read by no job: {orphans}"
    config, plan = configuration.load(root=ROOT, user_files=[ROOT / f for f in files])
    needed = targets.needed_files(config, plan.drawn)
    assert {main(p) for p in products} == needed
    assert {targets.product_of(p)[0] for p in needed} >= {"figure", "report"}
    for rel in written:
        (work / rel).parent.mkdir(parents=True, exist_ok=True)
        (work / rel).touch()
    assert stale.stale_files(config, plan.drawn, work) == []
    old = [targets.product("figure", owner=name, figure="fig99") for name in plan.drawn["studies"]]
    old += [targets.product("report", owner=f"orbits/{name}", report="earlier")
            for name in plan.drawn["orbits"]]
    for rel in old:
        (work / rel).parent.mkdir(parents=True, exist_ok=True)
        (work / rel).touch()
    assert stale.stale_files(config, plan.drawn, work) == sorted(old)
