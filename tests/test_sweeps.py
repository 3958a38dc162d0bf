"""Sweeps: a study listing values of zeta, eps, amplitude, rms or seed (README, "Sweeps").

The fast tests call `configuration.load` on a user's file layered on the paper's config and
check the expansion: the product's order and names, the derived noise entries, the plan, the
errors (naming the sweep and its combination) and that a study without lists is untouched; then
the attributes the tasks write and the side-by-side figure, on datasets made by the workflow's
own tasks. The ``workflow`` test builds a small sweep and a plain study with `rule all`.
"""
import copy
from pathlib import Path
import textwrap

import numpy as np
import pytest
import xarray as xr
import yaml
from matplotlib.figure import Figure

from vibroimpact.pipeline import config as configuration, provenance, tasks
from vibroimpact.pipeline.config import ConfigError
from vibroimpact.plotting.sweep import sweep_means
from vibroimpact.stats.events import t_quantile

ROOT = Path(__file__).resolve().parents[1]
PAPER = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())

SWEEP = yaml.safe_load(textwrap.dedent("""\
    paper: false
    studies:
      eps_sweep:
        noise: random_input
        zeta: 0.05
        eps: [0.3, 0.5, 0.8]
        rms: [0.3, 0.5]
        delta: {start: -0.5, stop: 3.0, step: 0.5}
        figures: [fig07, fig09]
"""))
NAMES = [f"eps_sweep_{k}" for k in range(6)]
#: (eps, rms) of combinations 0-5: the first listed key (in SWEEP_KEYS order) varies slowest.
PRODUCT = [(0.3, 0.3), (0.3, 0.5), (0.5, 0.3), (0.5, 0.5), (0.8, 0.3), (0.8, 0.5)]


def _user(**study):
    """SWEEP with the study's keys changed (a key given as None is removed)."""
    user = copy.deepcopy(SWEEP)
    entry = user["studies"]["eps_sweep"]
    entry.update(study)
    for key in [k for k, v in entry.items() if v is None]:
        del entry[key]
    return user


def _problems(user):
    with pytest.raises(ConfigError) as info:
        configuration.load(user, root=ROOT)
    problems = info.value.problems
    for problem in problems:
        assert len(problem.splitlines()) <= 2, f"a problem of more than 2 lines:\n{problem}"
    return "\n".join(problems)


# --- expansion --------------------------------------------------------------------------------

def test_one_study_per_combination_in_the_documented_order():
    config, _ = configuration.load(SWEEP, root=ROOT)
    assert "eps_sweep" not in config["studies"]
    assert [config["studies"][n]["sweep"]["index"] for n in NAMES] == list(range(6))
    got = [(config["studies"][n]["eps"], config["studies"][n]["sweep"]["values"]["rms"])
           for n in NAMES]
    assert got == PRODUCT
    for name, (eps, rms) in zip(NAMES, PRODUCT):
        entry = config["studies"][name]
        assert entry["sweep"] == {"name": "eps_sweep", "index": NAMES.index(name),
                                  "values": {"eps": eps, "rms": rms}}
        assert config["noises"][entry["noise"]]["rms"] == rms
        assert "rms" not in entry and "seed" not in entry    # they became its noise
        assert entry["zeta"] == 0.05 and entry["figures"] == ["fig07", "fig09"]
    assert config["sweeps"] == {"eps_sweep": {"studies": NAMES, "keys": ["eps", "rms"],
                                              "values": [list(p) for p in PRODUCT]}}


def test_the_order_follows_the_keys_not_the_file():
    """zeta before eps whatever order the file writes them in."""
    user = copy.deepcopy(SWEEP)
    user["studies"]["eps_sweep"] = {"eps": [0.5, 0.8], "zeta": [0.02, 0.05],
                                    "noise": "random_input", "delta": [0.0], "figures": ["fig09"]}
    config, _ = configuration.load(user, root=ROOT)
    assert config["sweeps"]["eps_sweep"]["keys"] == ["zeta", "eps"]
    assert config["sweeps"]["eps_sweep"]["values"] == [[0.02, 0.5], [0.02, 0.8],
                                                       [0.05, 0.5], [0.05, 0.8]]


def test_derived_noises_are_shared_and_the_entrys_own_values_use_the_entry():
    config, _ = configuration.load(SWEEP, root=ROOT)
    noises = [config["studies"][n]["noise"] for n in NAMES]
    # rms 0.3 differs from random_input's 0.5: one copy, shared; rms 0.5 is random_input itself
    assert noises == ["eps_sweep_noise0", "random_input"] * 3
    derived = config["noises"]["eps_sweep_noise0"]
    assert derived == dict(config["noises"]["random_input"], rms=0.3)   # same seed: scaled record
    assert config["noises"]["random_input"] == dict(PAPER["noises"]["random_input"],
                                                    zeta_f=None, nperseg=2048)


def test_a_seed_list_gives_one_record_per_seed():
    """Combinations of one seed share its record."""
    config, _ = configuration.load(_user(rms=None, eps=[0.5, 0.7], seed=[1, 2]), root=ROOT)
    noises = [config["studies"][f"eps_sweep_{k}"]["noise"] for k in range(4)]
    assert noises == ["eps_sweep_noise0", "eps_sweep_noise1"] * 2
    assert [config["noises"][n]["seed"] for n in noises] == [1, 2, 1, 2]


def test_a_scalar_override_keeps_the_studys_name_and_is_no_sweep():
    config, plan = configuration.load(_user(eps=0.8, rms=0.3), root=ROOT)
    entry = config["studies"]["eps_sweep"]
    assert entry["noise"] == "eps_sweep_noise0" and "sweep" not in entry
    assert config["noises"]["eps_sweep_noise0"]["rms"] == 0.3
    assert config["sweeps"] == {}
    assert plan.drawn["studies"] == {"eps_sweep"}


def test_a_study_without_lists_is_unchanged():
    """The paper's studies, and a user's plain study, are the same with a sweep beside them."""
    plain = {"noise": "harmonic_input", "zeta": 0.1, "eps": 0.8, "delta": [0.0, 0.5, 1.0],
             "figures": ["fig09"]}
    alone, _ = configuration.load({"paper": False, "studies": {"mine": plain}}, root=ROOT)
    user = copy.deepcopy(SWEEP)
    user["studies"]["mine"] = plain
    both, _ = configuration.load(user, root=ROOT)
    for name in [*PAPER["studies"], "mine"]:
        assert both["studies"][name] == alone["studies"][name]
    assert {k: v for k, v in both["noises"].items() if k != "eps_sweep_noise0"} == alone["noises"]
    composed, own = configuration.compose(PAPER, {"paper": False, "studies": {"mine": plain}})
    before = copy.deepcopy(composed)
    sweeps = configuration.expand_sweeps(composed, own)
    assert composed == before and sweeps.record == {}


def test_paper_false_builds_the_expanded_studies_and_their_noises():
    config, plan = configuration.load(SWEEP, root=ROOT)
    assert plan.drawn["studies"] == set(NAMES)
    keys = [r.key for r in plan.rows if r.key.split(".")[0] in ("noises", "studies", "sweeps")]
    assert keys == (["noises.eps_sweep_noise0", "noises.random_input"]
                    + [f"studies.{n}" for n in NAMES] + ["sweeps.eps_sweep"])
    assert configuration.drawn_sweeps(config, plan.drawn) == ["eps_sweep"]
    assert configuration.sweep_labels(config["sweeps"]["eps_sweep"])[4] == "eps = 0.8, rms = 0.3"


def test_the_plan_and_the_limits_count_every_expanded_study():
    _, plan = configuration.load(SWEEP, root=ROOT)
    assert plan.cells == 6 * 8                  # 6 studies x 8 deltas
    jobs = {r.key: r.jobs for r in plan.rows}
    assert [jobs[f"studies.{n}"] for n in NAMES] == [4] * 6    # tile, aggregate, 2 figures
    assert jobs["sweeps.eps_sweep"] == 1
    # 6 x 36 cells, over a limit above every single grid (the paper's largest has 91 values)
    text = _problems(dict(_user(delta={"start": -0.5, "stop": 3.0, "step": 0.1}),
                          limits={"max_cells": 200}))
    assert text.startswith("limits.max_cells = 200: this build has 216 simulation cells")


def test_a_sweep_of_a_study_without_events_figures_still_builds_its_events():
    _, plan = configuration.load(_user(figures=["fig04"]), root=ROOT)
    assert plan.cells == 6 * 8


def test_too_many_combinations_are_refused_before_expanding():
    values = [0.01 * k for k in range(1, 51)]
    text = _problems(_user(eps=values, rms=[10 * v for v in values]))
    assert "studies.eps_sweep: 50 eps x 50 rms = 2,500 combinations" in text
    assert "limits.max_jobs = 2,000" in text


# --- errors -----------------------------------------------------------------------------------

def test_an_error_names_the_sweep_and_its_combination():
    text = _problems(_user(eps=[0.3, 1.5], rms=[0.3]))
    assert ("studies.eps_sweep (combination 1: eps=1.5, rms=0.3): eps = 1.5: not allowed; "
            "allowed: a finite number >= 0 and <= 1") in text
    assert "eps_sweep_1" not in text


def test_a_problem_of_every_combination_is_given_once():
    text = _problems(_user(delta={"start": 3.0, "stop": 0.0, "step": 0.5}))
    assert text.startswith("studies.eps_sweep (all 6 combinations): delta.stop = 0")
    assert len(text.splitlines()) == 1


def test_an_unknown_report_with_is_named_once_without_the_sweeps_own_studies():
    text = _problems(_user(report_with=["motionmap"]))
    assert text.startswith("studies.eps_sweep (all 6 combinations): report_with = motionmap")
    assert len(text.splitlines()) == 1 and "eps_sweep_" not in text


def test_a_bad_noise_override_names_the_combinations_using_it():
    text = _problems(_user(rms=[-0.1, 0.5]))
    assert ("studies.eps_sweep (noise of combinations 0, 2, 4: rms=-0.1): rms = -0.1: "
            "not allowed; allowed: a finite number >= 0") in text
    assert _problems(_user(eps=0.5, rms=None, seed=[1.5])).startswith(
        "studies.eps_sweep (noise of combination 0: seed=1.5): seed = 1.5")


def test_a_non_finite_value_in_a_sweep_is_named_once():
    text = _problems(_user(eps=[0.3, float("nan")], rms=None))
    assert text == ("studies.eps_sweep (combination 1: eps=nan): eps = nan: not a finite "
                    "number; allowed: a finite number >= 0 and <= 1 (restitution coefficient, "
                    "0 <= eps <= 1)")


@pytest.mark.parametrize("value, problem", [([], "an empty list sweeps nothing"),
                                            ([[0.3, 0.5]], "not a number or a list of numbers")])
def test_an_empty_or_nested_list_is_refused(value, problem):
    assert f"studies.eps_sweep.eps = {configuration._short(value)}: {problem}" in _problems(
        _user(eps=value))


def test_a_name_collision_names_both_entries():
    user = copy.deepcopy(SWEEP)
    user["studies"]["eps_sweep_2"] = {"noise": "random_input", "zeta": 0.05, "eps": 0.5,
                                      "delta": [0.0], "figures": ["fig09"]}
    text = _problems(user)
    assert "studies.eps_sweep: its combination 2 (eps=0.5, rms=0.3) would be named " \
           "eps_sweep_2, like the study studies.eps_sweep_2" in text
    user = copy.deepcopy(SWEEP)
    user["noises"] = {"eps_sweep_noise0": dict(PAPER["noises"]["random_input"])}
    assert "like the entry noises.eps_sweep_noise0" in _problems(user)


def test_a_hand_written_sweep_key_is_refused():
    user = _user(eps=0.5, rms=None, sweep={"name": "eps_sweep", "index": 0, "values": {}})
    assert _problems(user).startswith("studies.eps_sweep.sweep: set by the expansion of a "
                                      "sweep, never by hand")


def test_the_error_of_a_plain_study_is_as_before():
    """A scalar keeps the schema's message of the number (README, "Checked and costed")."""
    user = {"paper": False, "studies": {"mine": {"noise": "random_input", "zeta": float("nan"),
                                                 "eps": 0.5, "delta": [0.0],
                                                 "figures": ["fig09"]}}}
    assert _problems(user) == ("studies.mine.zeta = nan: not a finite number; allowed: a finite "
                               "number > 0 and <= 0.9999 (damping ratio, 0 < zeta <= 0.9999)")


# --- attributes and the figure, through the workflow's tasks -----------------------------------

def test_sweep_attrs_of_an_expanded_block_only():
    config, _ = configuration.load(SWEEP, root=ROOT)
    attrs = provenance.provenance(config["studies"]["eps_sweep_4"], 7)
    assert {k: attrs[k] for k in attrs if k.startswith("sweep")} == {
        "sweep": "eps_sweep", "sweep_index": 4, "sweep_eps": 0.8, "sweep_rms": 0.3}
    attrs = provenance.provenance(PAPER["studies"]["random"])
    assert not any(k.startswith("sweep") for k in attrs)


SMALL = yaml.safe_load(textwrap.dedent("""\
    paper: false
    noises:
      short_input: {kind: band_limited, rms: 0.5, dt: 0.1, beta_c: 4.0, n_samples: 40001, seed: 7}
    studies:
      s:
        noise: short_input
        zeta: 0.05
        eps: [0.3, 0.8]
        rms: [0.3, 0.5]
        delta: [-0.5, 0.5, 1.5, 4.0]
        transient: 100.0
        figures: [fig09]
"""))


@pytest.fixture(scope="module")
def sweep_events(tmp_path_factory):
    """The events datasets of a 2 x 2 sweep, made by the workflow's tasks from its blocks."""
    tmp = tmp_path_factory.mktemp("sweep")
    config, _ = configuration.load(SMALL, root=ROOT)
    out = []
    for name in config["sweeps"]["s"]["studies"]:
        block = config["studies"][name]
        noise = tmp / f"{block['noise']}.nc"
        if not noise.exists():
            tasks.make_noise(config["noises"][block["noise"]], noise)
        tasks.events_tile(name, block, 0, noise, tmp / f"{name}_tile.nc")
        tasks.aggregate(name, block, "events", [tmp / f"{name}_tile.nc"], tmp / f"{name}.nc")
        out.append(xr.load_dataset(tmp / f"{name}.nc"))
    return config, out


def test_the_datasets_carry_their_combination(sweep_events):
    config, events = sweep_events
    for k, ds in enumerate(events):
        eps, rms = config["sweeps"]["s"]["values"][k]
        assert (ds.attrs["sweep"], ds.attrs["sweep_index"]) == ("s", k)
        assert (ds.attrs["sweep_eps"], ds.attrs["sweep_rms"]) == (eps, rms)
        assert (ds.attrs["eps"], ds.attrs["noise_rms"]) == (eps, rms)


def test_the_side_by_side_figure_draws_each_combinations_means(sweep_events):
    config, events = sweep_events
    labels = configuration.sweep_labels(config["sweeps"]["s"])
    fig = sweep_means(events, labels)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[:4] == labels == ["eps = 0.3, rms = 0.3", "eps = 0.3, rms = 0.5",
                                    "eps = 0.8, rms = 0.3", "eps = 0.8, rms = 0.5"]
    assert "s" in fig.get_suptitle() and r"$\zeta$ = 0.05" in fig.get_suptitle()
    ax_v, ax_z = fig.axes
    for k, ds in enumerate(events):
        cell = ds.isel(inv_beta=0)
        enough = np.asarray(cell["n_collisions"]) >= 20
        # the k-th errorbar container of each panel: its points and its +-t s.e. bars (1e-9)
        for ax, name in ((ax_v, "v_after"), (ax_z, "interval")):
            line, _, (bars,) = ax.containers[k].lines
            assert np.allclose(line.get_ydata(), cell[f"{name}_mean"].values[enough], rtol=1e-9)
            half = np.array([seg[1, 1] - seg[0, 1] for seg in bars.get_segments()]) / 2
            t = t_quantile(np.asarray(cell["n_batches"])[enough])
            assert np.allclose(half, t * cell[f"{name}_stderr"].values[enough], rtol=1e-9)
    # eps gives the colour, rms the line style
    styles = [(c.lines[0].get_color(), c.lines[0].get_linestyle()) for c in ax_v.containers]
    assert styles[0][0] == styles[1][0] != styles[2][0] and styles[0][1] != styles[1][1]
    with pytest.raises(ValueError, match="one label per dataset"):
        sweep_means(events, labels[:3])


# --- end to end -------------------------------------------------------------------------------

WORKFLOW = textwrap.dedent("""\
    paper: false
    validation: {build: false}
    noises:
      short_input:              # a short record of its own: tau up to 2e4
        kind: band_limited
        rms: 0.5
        dt: 0.1
        beta_c: 4.0
        n_samples: 200001
        seed: 7
    studies:
      stiff:                    # a plain new study
        noise: short_input
        zeta: 0.02
        eps: 0.8
        delta: {start: -0.5, stop: 2.5, step: 0.5}
        transient: 100.0
        tile_size: 7
        figures: [fig07, fig09]
      small_sweep:              # 2 x 2 combinations: small_sweep_0 ... small_sweep_3
        noise: short_input
        zeta: 0.05
        eps: [0.3, 0.8]
        rms: [0.3, 0.5]
        delta: {start: -0.5, stop: 2.5, step: 0.5}
        transient: 100.0
        tile_size: 7
        figures: [fig09]
""")


@pytest.mark.workflow
def test_a_plain_study_and_a_sweep_end_to_end(tmp_path):
    from helpers import assert_figure, make_workdir, snakemake

    workdir = make_workdir(tmp_path / "w")
    (workdir / "mine.yaml").write_text(WORKFLOW)
    snakemake(workdir, config="mine.yaml")
    results = workdir / "results"
    sweep = [f"small_sweep_{k}" for k in range(4)]
    for name, figs in [("stiff", ["fig07", "fig09"])] + [(s, ["fig09"]) for s in sweep]:
        for fig in figs:
            assert_figure(results / "figures" / name / f"{fig}.png")
            assert_figure(results / "figures" / name / f"{fig}.pdf")
        assert list((results / "reports" / name).glob("*.html")), f"no report of {name}"
    assert_figure(results / "figures" / "small_sweep" / "sweep.png")
    assert_figure(results / "figures" / "small_sweep" / "sweep.pdf")
    assert not (results / "figures" / "random").exists()       # paper: false
    plain = xr.open_dataset(results / "datasets" / "stiff_events.nc")
    assert (plain.attrs["eps"], plain.attrs["zeta"]) == (0.8, 0.02)
    assert not any(k.startswith("sweep") for k in plain.attrs)
    for k, (eps, rms) in enumerate([(0.3, 0.3), (0.3, 0.5), (0.8, 0.3), (0.8, 0.5)]):
        ds = xr.open_dataset(results / "datasets" / f"small_sweep_{k}_events.nc")
        assert (ds.attrs["sweep"], ds.attrs["sweep_index"]) == ("small_sweep", k)
        assert (ds.attrs["sweep_eps"], ds.attrs["sweep_rms"], ds.attrs["noise_rms"]) == (
            eps, rms, rms)
        assert ds.attrs["noise"] == ("small_sweep_noise0" if rms == 0.3 else "short_input")
    assert sorted(p.name for p in (results / "noise").glob("*.nc")) == [
        "short_input.nc", "small_sweep_noise0.nc"]
