"""Every check a study gets, on each kind of study: plain, with a second wall, over a plane.

A plane study, a two-wall study and a sweep are studies (issue 44): a mistake in one is
refused before any job, naming the same key with the same allowed range as in a plain study.
Each `CHECKS` row is one user mistake, written into one study of ``config/test.yaml``
(``harmonic``, an events study, or ``motion_map``, a map) in three forms of that config:

- ``plain``: as it is;
- ``two_walls``: the study with a second wall (``gap``, ``eps_lower``; its motions and the
  orbits entry its figures read counted per wall);
- ``plane``: ``motion_map`` over the plane (eps, delta), 1/beta_f fixed. A plane study is a
  map: a mistake in an events study's key is written into it, and the row says what it is
  told instead (an events key in a map is refused, as in a plain map study).

Where a row's expectation differs by kind, it says why; otherwise all three give one message.
The three forms, without a mistake, are accepted (`test_each_kind_is_accepted`), so each
refusal comes from the mistake alone.
"""
import copy
from dataclasses import dataclass, field
import math

import pytest
import yaml

from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline.config.messages import ConfigError

from helpers import ROOT

TEST_CONFIG = yaml.safe_load((ROOT / "config" / "test.yaml").read_text())
KINDS = ("plain", "two_walls", "plane")
DELETE = object()
#: Two-wall motions (collisions at the wall above, at the wall below, forcing periods).
WALL_MOTIONS = [[1, 1, 1], [1, 0, 1], [0, 1, 1]]


def _form(kind, study):
    """``(config, study under test)``: test.yaml in ``kind``'s form around ``study``."""
    cfg = copy.deepcopy(TEST_CONFIG)
    if kind == "two_walls":
        entry = cfg["studies"][study]
        entry.update(gap=6.0, eps_lower=0.5)      # the wall below at delta - 6: below -1
        entry["motions"] = copy.deepcopy(WALL_MOTIONS)
        if study == "motion_map":                # its fig15_vs_fig16 reads the orbits entry
            orbits = cfg["orbits"]["harmonic"]
            orbits.update(gap=6.0, types=copy.deepcopy(WALL_MOTIONS), figures=["fig16"],
                          inv_beta=copy.deepcopy(entry["inv_beta"]),   # its motions are read
                          delta=copy.deepcopy(entry["delta"]))         # at the map's cells
            orbits.pop("attractors")             # one-wall (a plane study has its own)
        return cfg, study
    if kind == "plane":
        entry = cfg["studies"]["motion_map"]
        entry.update(plane=["eps", "delta"], eps=[0.3, 0.5], inv_beta=1.1,
                     figures=["fig15", "residence", "escape_vs_noise"])
        entry["escape"]["cells"] = [[0.5, 1.0], [0.5, 0.0]]      # (eps, delta)
        del cfg["paper_figures"]["fig15_vs_fig16"]   # its orbits entry is over (1/beta_f, delta)
        return cfg, "motion_map"
    return cfg, study


@dataclass(frozen=True)
class Check:
    """One mistake: ``path`` (inside the study) set to ``value``; the message names
    ``studies.<study><key>`` and ``fragment``. ``kinds`` overrides, per kind, any of
    ``path``, ``value``, ``key``, ``fragment`` (a value another kind writes differently, a
    message that says something else there, and why)."""

    id: str
    study: str               # "harmonic" (events) or "motion_map" (map)
    path: tuple
    value: object
    key: str
    fragment: str
    kinds: dict = field(default_factory=dict)

    def of(self, kind):
        """``(path, value, key, fragment)`` for ``kind``."""
        over = self.kinds.get(kind, {})
        return (over.get("path", self.path), over.get("value", self.value),
                over.get("key", self.key), over.get("fragment", self.fragment))


def _ck(id, study, path, value, key, fragment, **kinds):
    return Check(id, study, tuple(path) if isinstance(path, (tuple, list)) else (path,),
                 value, key, fragment, kinds)


E, M = "harmonic", "motion_map"
#: What a plane study (a map) says of a key only an events study reads.
MAP_ALONE = "draws its map alone"
#: An eps value in the plane form: a bad value among the axis's grid.
def _eps_grid(v):
    return {"value": [0.3, v], "key": ".eps"}


CHECKS = [
    # --- numbers: non-finite, out of range, type ----------------------------------------
    _ck("zeta_nan", M, "zeta", math.nan, ".zeta", "> 0"),
    _ck("zeta_negative", E, "zeta", -0.05, ".zeta", "> 0 and <= 0.9999"),
    _ck("zeta_percent", M, "zeta", 5.0, ".zeta", "<= 0.9999"),
    _ck("eps_above_one", M, "eps", 1.5, ".eps", ">= 0 and <= 1", plane=_eps_grid(1.5)),
    _ck("eps_inf", E, "eps", math.inf, ".eps", "<= 1", plane=_eps_grid(math.inf)),
    _ck("eps_lower_above_one", M, "eps_lower", 1.5, ".eps_lower", ">= 0 and <= 1"),
    _ck("amplitude_beyond_float_range", M, "amplitude", -5e150, ".amplitude",
        ">= -1e+100 and <= 1e+100"),
    _ck("unknown_key", M, "colour", "red", ".colour", "allowed keys here: noise, zeta, eps"),
    _ck("unknown_noise", E, "noise", "harmonic_inptu", ".noise",
        "harmonic_input, random_input"),
    # --- the grid of plays -----------------------------------------------------------------
    _ck("missing_delta", M, "delta", DELETE, ".delta",
        "missing; allowed: A list of values, or {start, stop, step}"),
    _ck("grid_wrong_type", M, "delta", "-1 to 3", ".delta", "{start, stop, step}"),
    _ck("grid_stop_below_start", M, "delta", {"start": 3.0, "stop": -1.0, "step": 0.5},
        ".delta.stop", "stop >= start"),
    _ck("grid_step_zero", M, "delta", {"start": -1.0, "stop": 3.0, "step": 0.0},
        ".delta.step", "> 0"),
    _ck("grid_step_tiny", M, "delta", {"start": -1.0, "stop": 3.0, "step": 1e-6},
        "", "limits.max_cells"),
    _ck("grid_repeats_a_value", M, "delta", [1.5, 0.0, 1.5, -0.5], ".delta",
        "1.5 listed more than once"),
    _ck("map_of_one_column", M, "delta", [1.0], ".delta", "at least 2 values"),
    # --- the forcing -------------------------------------------------------------------------
    _ck("forcing_faster_than_the_samples", M, "inv_beta", [0.01, 0.5], ".inv_beta",
        "1/beta_f >= dt/(2 pi) = 0.0159155",
        plane={"value": 0.01}),       # fixed in a plane: one value
    _ck("inv_beta_zero", E, "inv_beta", [0.0, 1.1], ".inv_beta", "values > 0",
        plane={"value": 0.0, "fragment": "> 0"}),
    # --- the record --------------------------------------------------------------------------
    _ck("transient_beyond_record", M, "transient", 50_000.0, ".transient",
        "0 <= transient < 40000"),
    _ck("t_end_beyond_record", E, "t_end", 50_000.0, ".t_end",
        "<= 40000, or null for the whole record",
        plane={"fragment": MAP_ALONE}),
    # --- settings --------------------------------------------------------------------------
    _ck("tile_size_zero", M, "tile_size", 0, ".tile_size", ">= 1"),
    _ck("n_batches_one", E, "n_batches", 1, ".n_batches", ">= 2"),
    _ck("motion_window_too_wide", E, "motion_window", 0.75, ".motion_window", "<= 0.5"),
    _ck("duplicated_motions", M, "motions", [[1, 1], [2, 1], [1, 1]], ".motions",
        "distinct", two_walls={"value": [[1, 1, 1], [1, 0, 1], [1, 1, 1]]}),
    _ck("motion_of_no_period", M, "motions", [[1, 0], [1, 1]], ".motions[0][1]", ">= 1",
        two_walls={"value": [[1, 1, 0], [1, 0, 1]], "key": ".motions[0][2]"}),
    _ck("motion_without_a_collision", M, "motions", [[0, 1], [1, 1]], ".motions[0][0]", ">= 1",
        two_walls={"value": [[0, 0, 1], [1, 0, 1]], "key": ".motions[0]",
                   "fragment": "m_upper + m_lower >= 1"}),
    _ck("density_delta_off_grid", E, "density_delta", [1.0, 0.3], ".density_delta[1]",
        "-0.5, 0, 0.25, 1, 2.5", plane={"key": ".density_delta", "fragment": MAP_ALONE}),
    _ck("bins_n_zero", E, ("bins", "v_after", "n"), 0, ".bins.v_after.n", ">= 1"),
    # --- sweeps ----------------------------------------------------------------------------
    _ck("sweep_repeats_a_value", M, "zeta", [0.05, 0.1, 0.05], ".zeta",
        "0.05 listed more than once"),
    _ck("sweep_repeats_a_seed", E, "seed", [4, 4], ".seed", "distinct values"),
    _ck("sweep_rms_beyond_float_range", M, "rms", [0.29, 1e101],
        " (noise of combination 1: rms=1e+101): rms", "<= 1e+100"),
    # --- the map ---------------------------------------------------------------------------
    _ck("map_max_periods_beyond_record", M, ("map", "max_periods"), 9000,
        ".map.max_periods", "max_periods <= "),
    _ck("map_target_stderr_zero", M, ("map", "target_stderr"), 0.0,
        ".map.target_stderr", "> 0"),
    _ck("map_min_time_beyond_record", M, ("map", "min_time"), 50_000.0,
        ".map.min_time", "0 < min_time <= 39800"),
    _ck("escape_one_level", M, ("escape", "rms"), [0.2, 0.3], ".escape.rms", "at least 3"),
    _ck("escape_cell_off_the_map", M, ("escape", "cells"), [[1.0, 7.0]], ".escape.cells[0]",
        "delta in [-1, 3]", plane={"value": [[0.5, 7.0]]}),
    _ck("escape_without_its_figure", M, "escape", DELETE, ".escape",
        "escape_vs_noise draws it"),
    # --- figures, the trace, the report --------------------------------------------------
    _ck("figures_empty", M, "figures", [], ".figures", "a list of figures from"),
    _ck("figure_unknown", M, "figures", ["fig15", "fig02"], ".figures[1]", "fig15"),
    _ck("figure_listed_twice", M, "figures", ["fig15", "residence", "fig15"], ".figures[2]",
        "each figure once"),
    _ck("orbits_figure_in_a_study", M, "figures", ["fig15", "fig16"], ".figures[1]",
        "fig15_vs_fig16"),
    _ck("trace_t_end_beyond_record", E, ("trace", "t_end"), 50_000.0, ".trace.t_end",
        "0 < t_end <= 40000",
        plane={"value": {"cell": [0.5, 1.0], "t_end": 50_000.0}, "path": ("trace",)}),
    _ck("report_with_unknown", E, "report_with", ["no_such_study"], ".report_with",
        "no other study of this name"),
    _ck("report_with_itself", E, "report_with", ["harmonic"], ".report_with", "allowed:",
        plane={"value": ["motion_map"]}),
]


def _write(cfg, study, path, value):
    node = cfg["studies"][study]
    for p in path[:-1]:
        node = node.setdefault(p, {})
    if value is DELETE:
        node.pop(path[-1], None)
    else:
        node[path[-1]] = copy.deepcopy(value)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("study", [E, M])
def test_each_kind_is_accepted(kind, study):
    cfg, _ = _form(kind, study)
    configuration.load(cfg, root=ROOT)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("check", CHECKS, ids=[c.id for c in CHECKS])
def test_each_check_on_each_kind(check, kind):
    cfg, study = _form(kind, check.study)
    path, value, key, fragment = check.of(kind)
    _write(cfg, study, path, value)
    with pytest.raises(ConfigError) as info:
        configuration.load(cfg, root=ROOT)
    text = str(info.value)
    assert f"studies.{study}{key}" in text or (not key and fragment in text), text
    assert fragment in text, text
    # one readable message: no line of it runs past a paragraph
    assert max(map(len, text.splitlines())) < 600, text


# --- the second newcomer pass (issue 44): refusals that misled, and a build that failed late --

def _refusal(cfg):
    with pytest.raises(ConfigError) as info:
        configuration.load(cfg, root=ROOT)
    return str(info.value)


def _two_wall_map_and_orbits():
    cfg, study = _form("two_walls", M)
    return cfg, cfg["studies"][study], cfg["orbits"]["harmonic"]


def test_a_two_wall_orbit_map_must_hold_the_maps_cells():
    """Its motions are read at the map's cells, not solved there: a cell off its grid was
    accepted, then failed in solve_map_orbits with a message naming one grid twice."""
    cfg, study, orbits = _two_wall_map_and_orbits()
    orbits["delta"] = {"start": -1.0, "stop": 3.0, "step": 1.0}     # the map's step is 0.5
    text = _refusal(cfg)
    assert "orbits.harmonic.delta lacks -0.5, 0.5, 1.5, 2.5 of the study's delta grid" in text
    assert "inv_beta lacks" not in text


def test_walls_that_differ_are_said_once_and_no_eps_lower_is_invented():
    """A two-wall plane study over (eps, delta) beside a one-wall orbits entry of the same
    plane: the gap differs; eps_lower (which follows the eps axis) was said to differ from
    itself, '[0.3, 0.5] against [0.3, 0.5]'."""
    cfg, _ = _form("plane", M)
    study = cfg["studies"]["motion_map"]
    study.update(gap=6.0, motions=copy.deepcopy(WALL_MOTIONS),
                 figures=["fig15", {"name": "fig15_vs_fig16", "orbits": "pl"}])
    cfg["orbits"]["pl"] = {"plane": ["eps", "delta"], "zeta": 0.05, "eps": [0.3, 0.5],
                           "inv_beta": 1.1, "delta": copy.deepcopy(study["delta"]),
                           "types": [[1, 1], [2, 1], [1, 2]], "figures": ["fig16"]}
    text = _refusal(cfg)
    assert "orbits.pl has gap = none, the study gap = 6" in text
    assert "eps_lower" not in text


def test_an_orbits_entry_with_a_gap_and_attractors_is_sent_to_a_plane_study():
    """The hint named an orbits entry over (inv_beta, delta), which is refused with a gap."""
    cfg, _ = _form("plain", M)
    orbits = cfg["orbits"]["harmonic"]
    orbits.update(plane=["eps", "delta"], eps=[0.3, 0.5], inv_beta=1.1, gap=6.0,
                  types=copy.deepcopy(WALL_MOTIONS), figures=["fig16"])
    text = _refusal(cfg)
    assert "orbits.harmonic.attractors: basins and Lyapunov exponents over the plane" in text
    assert "a study with plane: ['eps', 'delta'] and this gap has them" in text


def test_a_misspelt_axis_is_no_sweep():
    """plane: [Eps, delta] with eps a grid: one line on the axis, not '(all 2
    combinations)' as though eps were swept."""
    cfg, _ = _form("plane", M)
    cfg["studies"]["motion_map"]["plane"] = ["Eps", "delta"]
    text = _refusal(cfg)
    assert "studies.motion_map.plane[0] = Eps: not allowed" in text
    assert "combination" not in text
