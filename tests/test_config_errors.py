"""Malformed configs, one realistic user mistake each, refused before any job runs.

Each case is built from ``config/test.yaml`` (``paper: false``, ``replace: true``: it stands
alone) with one value changed at a key path, or is a small file of its own layered on the
paper's ``config/config.yaml``. A case names the key path its message must show and a
fragment of the allowed range or of the remedy.

- The fast suite calls :func:`configuration.load` on each case: it must raise
  :class:`ConfigError` with that key path and fragment, one or two lines per problem.
- The ``workflow`` suite gives each case to Snakemake in one copy of the project: its own
  config loader and the Snakefile, in this process through Snakemake's API (what ``snakemake
  --configfile bad.yaml`` runs before any job): it must refuse the file at parse time with the
  same message. One case per kind of check (``COMMAND_CASES``) also runs as the real command
  ``snakemake --cores 1 --configfile bad.yaml`` (no dry run): the message reaches the user's
  terminal, and no job may have run (nothing under ``results``, no incomplete markers).
"""
import copy
from dataclasses import dataclass
import math
import subprocess
import sys
import textwrap

import pytest
import yaml

from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline.config.messages import ConfigError

from helpers import ROOT, SNAKEMAKE, make_workdir

TEST_CONFIG = yaml.safe_load((ROOT / "config" / "test.yaml").read_text())

DELETE = object()       # a value that removes the key instead
APPEND = object()       # marker: the last path part appends to a list


@dataclass(frozen=True)
class Case:
    """A malformed config: ``path``/``value`` changed in test.yaml, or ``text`` of its own."""

    id: str
    key: str                 # key path the message must name
    fragment: str            # fragment of the allowed range / remedy
    path: tuple = ()
    value: object = None
    text: str | None = None  # a user file of its own (layered on the paper's config)
    snakemake: bool = True   # False: plain `snakemake` refuses it first, in words of its own


    def user(self):
        """The user's config as ``--configfile`` would give it (a fresh dict)."""
        if self.text is not None:
            return yaml.safe_load(self.text)
        cfg = copy.deepcopy(TEST_CONFIG)
        node = cfg
        for p in self.path[:-1]:
            node = node[p]
        last = self.path[-1]
        if self.value is DELETE:
            del node[last]
        elif isinstance(last, tuple) and last[0] is APPEND:
            node[last[1]].append(copy.deepcopy(last[2]))
        elif isinstance(last, tuple) and last[0] == "rename":
            node[last[2]] = node.pop(last[1])
        else:
            node[last] = copy.deepcopy(self.value)
        return cfg

    def yaml_text(self):
        if self.text is not None:
            return self.text
        return yaml.safe_dump(self.user(), sort_keys=False)


def _c(id, path, value, key, fragment):
    return Case(id=id, key=key, fragment=fragment, path=tuple(path), value=value)


def _own(id, text, key, fragment, snakemake=True):
    return Case(id=id, key=key, fragment=fragment, text=textwrap.dedent(text),
                snakemake=snakemake)


#: A plane study beside a plain one: the plane cases of `CASES` edit it (issue 44: every check
#: a study gets, a plane study gets, with the same message).
PLANE_STUDY = textwrap.dedent("""
        paper: false
        studies:
          flat:
            noise: harmonic_input
            zeta: 0.05
            eps: 0.5
            amplitude: 1.0
            inv_beta: [1.1]
            delta: [0.0, 1.0]
            transient: 100.0
            figures: [fig13]
          pl:
            noise: harmonic_input
            zeta: 0.05
            amplitude: 1.0
            plane: [eps, delta]
            eps: [0.3, 0.5]
            inv_beta: 1.1
            delta: [0.0, 1.0]
            transient: 100.0
            map: {target_stderr: 0.05, min_time: 200.0, max_periods: 100, min_switches: 5}
            figures: [fig15]
""")


def _plane(id, key, fragment, edits=(), add=""):
    """A case of `PLANE_STUDY` with ``edits`` (old, new) of its text and ``add``, lines of
    the plane study ``pl``."""
    text = PLANE_STUDY
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    return Case(id=id, key=key, fragment=fragment,
                text=text + textwrap.indent(add, "    "), snakemake=True)


def _aliases(levels, width):
    """A YAML file whose `delta` list nests ``levels`` aliases ``width`` wide: a "billion
    laughs" of ``width ** levels`` values, a few lines of text."""
    lines = [f"a0: &a0 [{', '.join(['0.5'] * width)}]"]
    lines += [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * width)}]" for k in range(1, levels)]
    return "\n".join(lines) + textwrap.dedent(f"""
        paper: false
        studies:
          laughs:
            noise: random_input
            zeta: 0.05
            eps: 0.5
            delta: *a{levels - 1}
            figures: [fig09]
        """)


#: A study of one's own, to write a file-level mistake into (line 1 is `paper: false`).
OWN = textwrap.dedent("""\
    paper: false
    studies:
      mine:
        noise: random_input
        zeta: 0.05
        eps: 0.5
        delta: [0.0, 1.0]
        figures: [fig09]
    """)


R = ("studies", "random")
H = ("studies", "harmonic")
M = ("studies", "motion_map")
O = ("orbits", "harmonic")
N = ("noises", "random_input")

CASES = [
    # --- non-finite, out of range, wrong type, unknown keys -----------------------------------
    _c("zeta_nan", R + ("zeta",), math.nan, "studies.random.zeta", "> 0"),
    _c("eps_inf", R + ("eps",), math.inf, "studies.random.eps", "<= 1"),
    _c("zeta_negative", R + ("zeta",), -0.05, "studies.random.zeta", "> 0 and <= 0.9999"),
    _c("zeta_percent", H + ("zeta",), 5.0, "studies.harmonic.zeta", "<= 0.9999"),
    _c("zeta_critical", R + ("zeta",), 0.99999999, "studies.random.zeta", "<= 0.9999"),
    _c("eps_above_one", R + ("eps",), 1.5, "studies.random.eps", ">= 0 and <= 1"),
    _c("unknown_study_key", R + ("colour",), "red", "studies.random.colour",
       "allowed keys here: noise, zeta, eps"),
    _c("unknown_top_key", ("studys",), {}, "studys", "allowed keys here: paper, replace"),
    _c("missing_delta", R + ("delta",), DELETE, "studies.random.delta",
       "missing; allowed: A list of values, or {start, stop, step}"),
    _c("grid_wrong_type", R + ("delta",), "-1 to 3", "studies.random.delta",
       "{start, stop, step}"),
    _c("grid_stop_below_start", R + ("delta",), {"start": 3.0, "stop": -1.0, "step": 0.5},
       "studies.random.delta.stop", "stop >= start"),
    _c("grid_step_zero", R + ("delta",), {"start": -1.0, "stop": 3.0, "step": 0.0},
       "studies.random.delta.step", "> 0"),
    _c("grid_step_tiny", R + ("delta",), {"start": -1.0, "stop": 3.0, "step": 1e-6},
       "studies.random.delta", "limits.max_cells"),
    _c("inv_beta_wrong_type", H + ("inv_beta",), "0.909, 1.1", "studies.harmonic.inv_beta",
       "{start, stop, step}"),
    # --- impact laws -----------------------------------------------------------------------
    _c("law_speed_scale_zero", R + ("law",), {"speed_scale": 0.0},
       "studies.random.law.speed_scale", "> 0"),
    _c("law_without_speed_scale", R + ("law",), {"scale": 0.5}, "studies.random.law",
       "speed_scale"),
    _c("law_lower_one_wall", R + ("law_lower",), {"speed_scale": 1.0},
       "studies.random.law_lower", "give studies.random.gap > 0"),
    _c("law_under_closed_form_orbits", M + ("law",), {"speed_scale": 0.5},
       "studies.motion_map.figures", "the shooting solver takes any law"),
    _c("orbits_law_with_attractors", O + ("law",), {"speed_scale": 0.5},
       "orbits.harmonic.attractors", "leave attractors out"),
    _c("orbits_law_under_fig15_vs_fig16", O + ("law",), {"speed_scale": 0.5},
       "studies.motion_map.figures[1].orbits", "an `orbits` entry without law"),
    # --- noise records ---------------------------------------------------------------------
    _c("n_samples_huge", N + ("n_samples",), 10_000_000_000, "limits.max_disk_gb",
       "raise limits.max_disk_gb"),
    _c("n_samples_exponent_string", N + ("n_samples",), "4e5", "noises.random_input.n_samples",
       "write 400000; allowed: an integer >= 16"),
    _c("noise_kind_typo", N + ("kind",), "bandlimited", "noises.random_input.kind",
       "one of white, band_limited, lowpass2"),
    _c("noise_nperseg_beyond_record", N + ("nperseg",), 500_000, "noises.random_input.nperseg",
       "nperseg <= n_samples = 400001"),
    _c("beta_c_above_nyquist", N + ("beta_c",), 40.0, "noises.random_input.beta_c",
       "0 < beta_c <= 31.4159"),
    _c("band_limited_without_beta_c", N + ("beta_c",), DELETE, "noises.random_input.beta_c",
       "a number > 0"),
    _c("white_with_beta_c", N + ("kind",), "white", "noises.random_input.beta_c",
       "null (or leave it out)"),
    _c("lowpass2_without_zeta_f", N + ("kind",), "lowpass2", "noises.random_input.zeta_f",
       "a number > 0"),
    _c("dt_zero", N + ("dt",), 0.0, "noises.random_input.dt", "> 0"),
    _c("rms_negative", N + ("rms",), -0.5, "noises.random_input.rms", ">= 0"),
    _c("seed_negative", N + ("seed",), -1, "noises.random_input.seed", ">= 0"),
    _c("rms_beyond_float_range", N + ("rms",), 3e120, "noises.random_input.rms", "<= 1e+100"),
    # --- the scale the arithmetic carries (squares summed over the record stay finite) -------
    _c("amplitude_beyond_float_range", H + ("amplitude",), -5e150,
       "studies.harmonic.amplitude", ">= -1e+100 and <= 1e+100"),
    _c("delta_grid_beyond_float_range", R + ("delta",),
       {"start": 0.0, "stop": 1e200, "step": 1e199}, "studies.random.delta.stop", "<= 1e+100"),
    _c("trace_delta_beyond_float_range", R + ("trace", "delta"), 7e222,
       "studies.random.trace.delta", "<= 1e+100"),
    _c("sweep_rms_beyond_float_range", R + ("rms",), [0.5, 1e101],
       "studies.random (noise of combination 1: rms=1e+101): rms",
       "<= 1e+100"),
    # --- records: transient, t_end, spectra, trace ------------------------------------------
    _c("transient_beyond_record", R + ("transient",), 50_000.0, "studies.random.transient",
       "0 <= transient < 40000"),
    _c("t_end_beyond_record", H + ("t_end",), 50_000.0, "studies.harmonic.t_end",
       "<= 40000, or null for the whole record"),
    _c("transient_not_below_t_end", H + ("transient",), 20_000.0, "studies.harmonic.transient",
       "0 <= transient < 20000"),
    _c("spectra_t_end_beyond_record", R + ("spectra", "t_end"), 50_000.0,
       "studies.random.spectra.t_end", "<= 40000"),
    _c("spectra_nperseg_beyond_spectra_record", R + ("spectra", "nperseg"), 500_000,
       "studies.random.spectra.nperseg", "16 <= nperseg <= 199001"),
    _c("spectra_delta_off_grid", R + ("spectra", "delta"), [3.0, 1.0, 0.3],
       "studies.random.spectra.delta[2]", "-1, -0.5, ..., 3"),
    _c("trace_t_end_beyond_record", R + ("trace", "t_end"), 50_000.0,
       "studies.random.trace.t_end", "0 < t_end <= 40000"),
    _c("trace_shorter_than_a_sample_step", R + ("trace", "t_end"), 0.05,
       "studies.random.trace.t_end", "0.1 <= t_end <= 40000"),
    # --- study settings ------------------------------------------------------------------------
    _c("tile_size_zero", R + ("tile_size",), 0, "studies.random.tile_size", ">= 1"),
    _c("n_batches_one", R + ("n_batches",), 1, "studies.random.n_batches", ">= 2"),
    _c("bins_n_zero", R + ("bins", "v_after", "n"), 0, "studies.random.bins.v_after.n", ">= 1"),
    _c("motion_window_too_wide", H + ("motion_window",), 0.75, "studies.harmonic.motion_window",
       "<= 0.5"),
    _c("duplicated_motions", H + ("motions",), [[1, 1], [2, 1], [1, 1]],
       "studies.harmonic.motions", "distinct [m, n] pairs"),
    _c("motion_m_zero", H + ("motions",), [[0, 1], [1, 1]], "studies.harmonic.motions[0][0]",
       ">= 1"),
    _c("study_inv_beta_zero", H + ("inv_beta",), [0.0, 1.1], "studies.harmonic.inv_beta",
       "values > 0"),
    _c("unknown_noise", R + ("noise",), "random_inptu", "studies.random.noise",
       "harmonic_input, random_input"),
    _c("density_delta_off_grid", R + ("density_delta",), [1.0, 0.3],
       "studies.random.density_delta[1]", "-1, -0.5, ..., 3"),
    _c("sweep_repeats_a_value", R + ("zeta",), [0.05, 0.1, 0.05], "studies.random.zeta",
       "0.05 listed more than once"),
    _c("sweep_repeats_a_seed", R + ("seed",), [4, 4], "studies.random.seed", "distinct values"),
    _c("delta_grid_repeats_a_value", R + ("delta",), [1.5, 0.0, 1.5, -0.5],
       "studies.random.delta", "1.5 listed more than once"),
    _c("spectra_delta_repeats_a_value", R + ("spectra", "delta"), [0.0, 0.0],
       "studies.random.spectra.delta", "distinct values"),
    _c("density_delta_repeats_a_value", R + ("density_delta",), [1.0, 0.5, 1.0],
       "studies.random.density_delta", "distinct values"),
    _c("figure_inv_beta_repeats_a_value", H + ("figures",),
       ["fig10", {"name": "fig11", "inv_beta": [0.9090909090909091]},
        {"name": "fig12", "inv_beta": [1.1, 1.1]}, {"name": "fig13", "inv_beta": [1.1]},
        {"name": "fig14", "inv_beta": [1.1]}],
       "studies.harmonic.figures[2].inv_beta", "distinct values"),
    _c("forcing_faster_than_the_samples", M + ("inv_beta",), [0.01, 0.5],
       "studies.motion_map.inv_beta", "1/beta_f >= dt/(2 pi) = 0.0159155"),
    _c("trace_forcing_faster_than_the_samples", H + ("trace", "inv_beta"), 0.002,
       "studies.harmonic.trace.inv_beta", "1/beta_f >= dt/(2 pi)"),
    _c("map_of_one_row", M + ("inv_beta",), [1.1], "studies.motion_map.inv_beta",
       "at least 2 values"),
    _c("orbits_map_of_one_column", O + ("delta",), {"start": 0.5, "stop": 0.5, "step": 0.1},
       "orbits.harmonic.delta", "at least 2 values"),
    _c("seed_beyond_64_bits", N + ("seed",), 2**70, "noises.random_input.seed",
       "<= 9223372036854775807"),
    _c("name_longer_than_a_file_name", ("studies", ("rename", "random", "r" * 130)), None,
       "r" * 130, "at most 120 characters"),
    _c("trace_inv_beta_without_harmonic_force", R + ("trace", "inv_beta"), 2.5,
       "studies.random.trace.inv_beta", "amplitude != 0"),
    _c("inv_beta_grid_without_harmonic_force", R + ("inv_beta",), [0.5, 2.0],
       "studies.random.inv_beta", "amplitude != 0"),
    _c("entry_name_with_hyphen", ("studies", ("rename", "random", "random-fine")), None,
       "random-fine", "letters, digits and _"),
    # --- map ---------------------------------------------------------------------------------
    _c("map_max_periods_beyond_record", M + ("map", "max_periods"), 5000,
       "studies.motion_map.map.max_periods", "max_periods <= 2533"),
    _c("map_target_stderr_zero", M + ("map", "target_stderr"), 0.0,
       "studies.motion_map.map.target_stderr", "> 0"),
    _c("map_min_time_beyond_record", M + ("map", "min_time"), 50_000.0,
       "studies.motion_map.map.min_time", "0 < min_time <= 39800"),
    # --- orbits --------------------------------------------------------------------------------
    _c("orbits_inv_beta_from_zero", O + ("inv_beta",), {"start": 0.0, "stop": 3.0, "step": 0.3},
       "orbits.harmonic.inv_beta.start", "values > 0"),
    _c("orbits_type_m4", O + ("types",), [[1, 1], [2, 1], [1, 2], [4, 1]],
       "orbits.harmonic.types[3]", "1 <= m <= 3"),
    _c("orbits_duplicated_types", O + ("types",), [[1, 1], [2, 1], [1, 2], [1, 1]],
       "orbits.harmonic.types", "distinct [m, n] pairs"),
    _c("attractors_no_starts", O + ("attractors", "n_starts"), 0,
       "orbits.harmonic.attractors.n_starts", "1 <= n_starts <= 65536"),
    _c("attractors_starts_beyond_wall", O + ("attractors", "gap"), [-0.5, 2.0],
       "orbits.harmonic.attractors.gap", "0 <= low < high"),
    _c("attractors_empty_velocity_box", O + ("attractors", "velocity"), [1.0, 1.0],
       "orbits.harmonic.attractors.velocity", "low < high"),
    _c("attractors_cap_too_short", O + ("attractors", "max_time"), 100.0,
       "orbits.harmonic.attractors.max_time", ">= 276.3 (zeta = 0.05)"),
    _c("basins_without_attractors", O + ("attractors",), DELETE,
       "orbits.harmonic.attractors", "an `attractors:` block"),
    _c("orbits_named_like_a_derived_dataset", ("orbits", ("rename", "harmonic", "h_basins")), None,
       "orbits.h_basins", "a name not ending in _boundaries, _basins, _lyapunov"),
    _c("orbits_lists_study_figure", O + ("figures",), ["fig16", "fig07"],
       "orbits.harmonic.figures[1]", "fig16"),
    # --- figures -------------------------------------------------------------------------------
    _c("fig03_without_trace", R + ("trace",), DELETE, "studies.random.trace",
       "a `trace:` block"),
    _c("fig06_without_spectra", R + ("spectra",), DELETE, "studies.random.spectra",
       "a `spectra:` block"),
    _c("figure_inv_beta_off_grid", H + ("figures",),
       ["fig10", {"name": "fig11", "inv_beta": [0.9090909090909091]},
        {"name": "fig12", "inv_beta": [1.2]}, {"name": "fig13", "inv_beta": [1.1]},
        {"name": "fig14", "inv_beta": [1.1]}],
       "studies.harmonic.figures[2].inv_beta[0]", "0.909091, 1.1"),
    _c("figure_option_not_applicable", R + ("figures",),
       ["fig03", "fig04", "fig05", "fig06", "fig07", "fig08",
        {"name": "fig09", "density_delta": [0.0]}],
       "studies.random.figures[6].density_delta",
       "not an option of fig09; allowed: name, envelope"),
    _c("figure_listed_twice", R + ((APPEND, "figures", "fig07"),), None,
       "studies.random.figures[7]", "each figure once"),
    _c("figure_unknown_fig02", R + ("figures",),
       ["fig02", "fig04", "fig05", "fig06", "fig07", "fig08", "fig09"],
       "studies.random.figures[0]", "fig03"),
    _c("study_lists_orbits_figure", R + ("figures",),
       ["fig03", "fig04", "fig05", "fig06", "fig07", "fig08", "fig09", "fig16"],
       "studies.random.figures[7]", "fig15_vs_fig16"),
    _c("harmonic_figure_without_amplitude", R + ((APPEND, "figures", "fig13"),), None,
       "studies.random.amplitude", "amplitude != 0"),
    _c("fig15_vs_fig16_without_orbits", M + ("figures",), ["fig15", "fig15_vs_fig16"],
       "studies.motion_map.figures[1].orbits", "orbits: <name>"),
    _c("fig15_vs_fig16_orbits_other_zeta", O + ("zeta",), 0.1,
       "studies.motion_map.figures[1].orbits", "the same zeta and eps"),
    _c("study_without_figures", R + ("figures",), [], "studies.random.figures",
       "a list of figures from"),
    _c("paper_figure_missing_entry", ("paper_figures", "fig07"), "randon", "paper_figures.fig07",
       "harmonic, motion_map, random"),
    _c("paper_figure_entry_without_it", ("paper_figures", "fig07"), "harmonic",
       "paper_figures.fig07", "add fig07 to studies.harmonic.figures"),
    # --- limits, layering ---------------------------------------------------------------------
    _c("tiny_max_disk_gb", ("limits",), {"max_disk_gb": 0.001}, "limits.max_disk_gb",
       "raise limits.max_disk_gb"),
    _c("tiny_max_cells", ("limits",), {"max_cells": 10}, "limits.max_cells",
       "raise limits.max_cells"),
    _c("tiny_max_cpu_hours", ("limits",), {"max_cpu_hours": 0.01}, "limits.max_cpu_hours",
       "raise limits.max_cpu_hours"),
    # --- the file itself: what YAML reads silently, or as text -----------------------------
    _own("key_given_twice", OWN + "    eps: 0.7\n", "bad.yaml:9:5",
         "the key 'eps' is given twice in one mapping (first on line 6)"),
    _own("section_given_twice", OWN + "studies: {}\n", "bad.yaml:9:1",
         "the key 'studies' is given twice"),
    _own("exponent_without_sign", OWN.replace("zeta: 0.05", "zeta: 5e-2"),
         "studies.mine.zeta", "read as the text '5e-2'"),
    _own("exponent_without_dot_in_noise", OWN + textwrap.dedent("""\
        noises:
          my_noise: {kind: white, rms: 2.5e0, dt: 0.1, n_samples: 20001, seed: 3}
        """).replace("random_input", "my_noise"), "noises.my_noise.rms", "write 2.5e+0"),
    _own("quoted_number", OWN.replace("eps: 0.5", "eps: '0.5'"), "studies.mine.eps",
         "write the number without quotes"),
    _own("spectra_record_shorter_than_a_segment", """
        paper: false
        noises:
          short: {kind: white, rms: 0.5, dt: 0.1, n_samples: 16, nperseg: 16, seed: 2}
        studies:
          mine:
            noise: short
            zeta: 0.05
            eps: 0.5
            delta: [0.0, 1.0]
            transient: 0.5
            spectra: {delta: [0.0], nperseg: 16}
            figures: [fig06]
        """, "studies.mine.spectra: its record holds 11 samples", "n_samples >= 21"),
    _own("empty_file", "", "bad.yaml", "the config file is empty", snakemake=False),
    _own("only_comments", "# my study, to be written\n", "bad.yaml", "the config file is empty",
         snakemake=False),
    _own("nested_aliases", _aliases(9, 9), "bad.yaml", "expand to more than 1,000,000 values"),
    _own("replace_as_a_string", """
        paper: false
        replace: studies.random
        studies:
          random:
            noise: random_input
            zeta: 0.1
            eps: 0.5
            delta: [0.0, 1.0]
            figures: [fig09]
        """, "studies.random", "replace: [studies.random]"),
    _own("collision_without_replace", """
        paper: false
        studies:
          random:
            noise: random_input
            zeta: 0.1
            eps: 0.5
            delta: [0.0, 1.0]
            figures: [fig09]
        """, "studies.random", "replace: [studies.random]"),
    _own("validation_block_without_replace", """
        paper: false
        validation:
          build: true
          work_precision:
            solvers: [RK45]
            repeats: 1
        """, "validation.work_precision", "replace: [validation]"),
    _own("validation_block_differs_with_the_paper_built", """
        validation:
          stress:
            seed: 7
        """, "validation.stress", "would overwrite its results"),
    _own("report_with_the_papers_map_beyond_max_jobs", """
        paper: false
        limits: {max_jobs: 20}
        studies:
          mine:
            noise: harmonic_input
            zeta: 0.05
            eps: 0.5
            amplitude: 1.0
            inv_beta: [1.1]
            delta: [0.0, 1.0]
            transient: 100.0
            figures: [fig13]
            report_with: [motion_map]
        """, "limits.max_jobs", "this build has 26 jobs"),
    # a plane study gets the checks every study gets (issue 44)
    _plane("two_wall_attractors_without_a_plane", "studies.flat.attractors",
           "with the second wall: e.g. plane: [inv_beta, delta] and gap fixed",
           edits=[("  flat:\n", "  flat:\n    gap: 3.0\n    attractors: {n_starts: 8}\n")]),
    _plane("plane_fixed_inv_beta_the_default_list", "studies.pl.inv_beta",
           "the default grid of a study without a plane",
           edits=[("    inv_beta: 1.1", "    inv_beta: [1.0]")]),
    _plane("plane_axis_inv_beta_one_value", "studies.pl.inv_beta", "needs a grid",
           edits=[("plane: [eps, delta]", "plane: [inv_beta, delta]"),
                  ("eps: [0.3, 0.5]", "eps: 0.5"), ("    inv_beta: 1.1", "    inv_beta: [1.0]")]),
    _plane("plane_escape_default_cells", "studies.pl.escape.cells",
           "names its escape cells in its own coordinates",
           edits=[("plane: [eps, delta]", "plane: [gap, delta]"),
                  ("eps: [0.3, 0.5]", "eps: 0.5\n    gap: [2.0, 3.0]")],
           add="escape: {rms: [0.2, 0.25, 0.3]}\n"),
    _plane("plane_report_with_unknown", "studies.pl.report_with", "no other study of this name",
           add="report_with: [no_such_study]\n"),
    _plane("plane_report_with_itself", "studies.pl.report_with", "allowed: flat",
           add="report_with: [pl]\n"),
    _plane("plane_t_end_ignored", "studies.pl.t_end", "draws its map alone",
           add="t_end: 1.0e+9\n"),
    _plane("plane_density_delta_ignored", "studies.pl.density_delta", "draws its map alone",
           add="density_delta: [7.0]\n"),
    _plane("plane_n_batches_beyond_min_time", "studies.pl.n_batches", "map.min_time",
           add="n_batches: 1000\n"),
    _own("replace_names_no_entry", """
        paper: false
        replace: [studies.random]
        studies:
          my_study:
            noise: random_input
            zeta: 0.05
            eps: 0.5
            delta: [0.0, 1.0]
            figures: [fig09]
        """, "replace", "<section>.<name>"),
    _own("paper_false_builds_nothing", """
        paper: false
        noises:
          my_noise:
            kind: white
            rms: 0.5
            dt: 0.1
            n_samples: 100001
            seed: 1
        """, "paper", "at least one study or orbits entry"),
    _own("own_trace_beyond_own_noise", """
        paper: false
        noises:
          short_input:
            kind: white
            rms: 0.5
            dt: 0.1
            n_samples: 10001
            seed: 7
        studies:
          my_trace:
            noise: short_input
            zeta: 0.05
            eps: 0.5
            delta: [0.0]
            trace: {delta: 0.0, t_end: 2000.0}
            figures: [fig03]
        """, "studies.my_trace.trace.t_end", "0 < t_end <= 1000"),
    # --- names YAML reads as something else than text, or that do not match whole ------------
    _own("study_named_yes", OWN.replace("  mine:", "  yes:"), "bad.yaml:3:3",
         "the key 'yes' is read by YAML as the boolean true, not as a name"),
    _own("study_named_123", OWN.replace("  mine:", "  123:"), "bad.yaml:3:3",
         "read by YAML as the integer 123"),
    _own("study_named_tilde", OWN.replace("  mine:", "  ~:"), "bad.yaml:3:3",
         "read by YAML as null"),
    _own("study_named_a_date", OWN.replace("  mine:", "  2024-01-01:"), "bad.yaml:3:3",
         "read by YAML as a date"),
    _own("orbits_named_by_an_integer", OWN + "orbits:\n  5: {}\n", "bad.yaml:10:3",
         "read by YAML as the integer 5"),
    _own("study_name_ending_in_a_newline", OWN.replace("  mine:", '  "s1\\n":'), "studies",
         "the name 's1\\n' is not allowed"),
    _own("figure_name_ending_in_a_newline", OWN.replace("[fig09]", '["fig09\\n"]'),
         "studies.mine.figures[0]", '"fig09\\n": not allowed; allowed: a string matching'),
    _own("paper_figure_name_ending_in_a_newline",
         OWN + 'paper_figures:\n  "fig09\\n": mine\n', "paper_figures",
         "the name 'fig09\\n' is not allowed; allowed: a string matching"),
    # --- YAML 1.1 readings the README does not allow -----------------------------------------
    _own("two_merge_keys", """
        paper: false
        base: &base {noise: random_input, zeta: 0.05}
        more: &more {eps: 0.5}
        studies:
          mine:
            <<: *base
            <<: *more
            delta: [0.0, 1.0]
            figures: [fig09]
        """, "bad.yaml:8:5", "a second `<<:` merge key in one mapping (the first on line 7)"),
    _own("seed_octal", OWN + "    seed: 010\n", "bad.yaml:9:11",
         "010 is read by YAML 1.1 as 8, a number in octal (the leading 0); write 10"),
    _own("n_batches_octal", OWN + "    n_batches: 010\n", "bad.yaml:9:16",
         "read by YAML 1.1 as 8, a number in octal"),
    _own("transient_base_60", OWN + "    transient: 3:20\n", "bad.yaml:9:16",
         "3:20 is read by YAML 1.1 as 200, a number in base 60"),
    _own("leading_zero_not_octal", OWN + "    n_batches: 08\n", "studies.mine.n_batches = 08",
         "YAML 1.1 reads an integer with a leading 0 as octal, and 8, 9 are no octal digits; "
         "write 8"),
    _own("fullwidth_digits", OWN + "    n_batches: １２\n", "studies.mine.n_batches",
         "its digits are not ASCII (U+FF11 FULLWIDTH DIGIT ONE, U+FF12 FULLWIDTH DIGIT TWO); "
         "write 12"),
    _own("zero_width_space_in_a_key", OWN + "    n_\u200bbatches: 10\n",
         'studies.mine."n_\\u200bbatches": unknown key', "U+200B ZERO WIDTH SPACE"),
    _own("no_break_space_in_a_key", OWN + "    n_batches\u00a0: 10\n",
         'studies.mine."n_batches\\xa0": unknown key', "U+00A0 NO-BREAK SPACE"),
    # --- grids, records and motions the README's rules refuse --------------------------------
    _own("grid_step_not_dividing_the_range",
         OWN.replace("delta: [0.0, 1.0]", "delta: {start: 0, stop: 1, step: 0.3}"),
         "studies.mine.delta.stop = 1: not start + a whole number of steps 0.3",
         "a stop on the grid, e.g. 0.9 or 1.2"),
    _own("lowpass2_record_shorter_than_its_correlation", """
        paper: false
        noises:
          slow:
            kind: lowpass2
            rms: 0.5
            dt: 0.1
            beta_c: 2.0
            zeta_f: 1.0e-12
            n_samples: 200001
            seed: 3
        studies:
          mine:
            noise: slow
            zeta: 0.05
            eps: 0.5
            delta: [0.0, 1.0]
            figures: [fig09]
        """, "noises.slow.n_samples", "n_samples dt >= 100 tau_c = 5e+13"),
    _own("thousand_batches_over_ten_samples", """
        paper: false
        noises:
          short:
            kind: white
            rms: 0.5
            dt: 0.1
            n_samples: 16
            nperseg: 16
            seed: 3
        studies:
          mine:
            noise: short
            zeta: 0.05
            eps: 0.5
            delta: [0.0, 1.0]
            transient: 0.5
            n_batches: 1000
            figures: [fig09]
        """, "studies.mine.n_batches = 1000", "n_batches x 6.283 = 6283"),
    _own("record_of_nanoseconds", """
        paper: false
        noises:
          brief:
            kind: white
            rms: 0.5
            dt: 2.5e-10
            n_samples: 16
            nperseg: 16
            seed: 3
        studies:
          mine:
            noise: brief
            zeta: 0.05
            eps: 0.5
            delta: [0.0, 1.0]
            transient: 0.0
            figures: [fig09]
        """, "studies.mine.n_batches = 20", "a record (t_end - transient) of at least"),
    _c("motions_of_one_ratio", H + ("motions",), [[1, 1], [2, 2]], "studies.harmonic.motions",
       "(2/2) has z_j/z = 1 like (1/1)"),
    _c("n_samples_written_as_a_float", N + ("n_samples",), 4.0e5,
       "noises.random_input.n_samples = 400000.0",
       "a number with a dot or an exponent, not an integer; write 400000"),
    _own("tile_size_written_as_a_float", OWN + "    tile_size: 2.0\n", "studies.mine.tile_size",
         "not an integer; write 2; allowed: an integer >= 1"),
    _own("density_play_between_tiny_plays",
         OWN.replace("delta: [0.0, 1.0]", "delta: [1.0e-7, 2.0e-7, 3.0e-7]\n    rms: 1.0e-7\n"
                     "    density_delta: [1.5e-7]"),
         "studies.mine.density_delta[0] = 1.5e-07", "not on the delta grid"),
    _c("delta_list_repeats_a_tiny_value", R + ("delta",), [1e-7, 2e-7, 1.00000000001e-7],
       "studies.random.delta", "1e-07 listed more than once"),
]

assert len({c.id for c in CASES}) == len(CASES), "case ids must be distinct"


def _ids(cases):
    return [c.id for c in cases]


# --- fast suite: configuration.load ------------------------------------------------------------

@pytest.mark.parametrize("case", CASES, ids=_ids(CASES))
def test_load_refuses(case, tmp_path):
    """A case of its own file is read from it, as `make` and `plan` read a --configfile."""
    path = tmp_path / "bad.yaml"
    path.write_text(case.yaml_text())
    with pytest.raises(configuration.ConfigError) as info:
        if case.text is None:
            configuration.load(case.user(), root=ROOT)
        else:
            configuration.load(root=ROOT, user_files=[path])
    err = info.value
    text = "\n".join(err.problems)
    assert case.key in text, f"key path {case.key!r} not named:\n{text}"
    assert case.fragment in text, f"allowed range {case.fragment!r} not given:\n{text}"
    for problem in err.problems:
        assert len(problem.splitlines()) <= 2, f"a problem of more than 2 lines:\n{problem}"


def test_huge_record_is_refused_without_writing(tmp_path):
    """n_samples = 1e10 is costed, not generated: refused at once, nothing written."""
    make_workdir(tmp_path)
    case = next(c for c in CASES if c.id == "n_samples_huge")
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    with pytest.raises(configuration.ConfigError, match="limits.max_disk_gb"):
        configuration.load(case.user(), root=tmp_path)
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before


#: OWN with its `eps` line indented one space too far.
BROKEN = OWN.replace("\n    eps:", "\n     eps:")


def _broken_mark():
    """``line:col`` PyYAML gives for BROKEN (1-based), to compare with the message."""
    try:
        yaml.safe_load(BROKEN)
    except yaml.YAMLError as err:
        return f"{err.problem_mark.line + 1}:{err.problem_mark.column + 1}"
    raise AssertionError("BROKEN must be invalid YAML")


def test_yaml_syntax_error_names_file_line_column(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text(BROKEN)
    with pytest.raises(configuration.ConfigError) as info:
        configuration.read_yaml(path)
    text = str(info.value)
    assert f"{path}:{_broken_mark()}" in text
    assert _broken_mark().startswith("6:")      # the mis-indented `eps` line
    assert "YAML syntax error" in text
    assert len(text.splitlines()) <= 2


def test_a_file_not_in_utf8_is_named_with_its_line(tmp_path):
    """A file saved in Latin-1 (an accented study name): its file and line, not a traceback."""
    path = tmp_path / "latin1.yaml"
    path.write_bytes(OWN.replace("mine:", "mïne:").encode("latin-1"))
    with pytest.raises(configuration.ConfigError) as info:
        configuration.load(root=ROOT, user_files=[path])
    assert str(info.value) == (f"{path}:3: not UTF-8 text (byte 0xef); allowed: a YAML file "
                               f"saved as UTF-8")


# --- workflow suite: the real snakemake command in a copy of the project ----------------------

@pytest.fixture(scope="module")
def copy_dir(tmp_path_factory):
    return make_workdir(tmp_path_factory.mktemp("badconfig"))


def _no_job_ran(work):
    results = work / "results"
    written = [p for p in results.rglob("*")] if results.exists() else []
    assert not written, f"files under results: {written[:5]}"
    incomplete = work / ".snakemake" / "incomplete"
    markers = list(incomplete.rglob("*")) if incomplete.exists() else []
    assert not markers, f"incomplete markers: {markers[:5]}"


#: One case per kind of check, by the code that refuses it and writes its message, through the
#: real `snakemake` command (each ~3-5 s of start-up; every case goes through Snakemake's API
#: in this process): the schema (a non-finite number, an unknown key, a number YAML reads as
#: text), a cross-field check, a figure's block, a sweep's combination, the plan's limits,
#: the strict reading of the file (a key given twice, nested aliases, YAML 1.1 octal, a name
#: YAML reads as a boolean), the layering on the paper's config, and the cases Snakemake's
#: own loader refuses first (the entry point).
COMMAND_CASES = ("zeta_nan", "unknown_study_key", "n_samples_exponent_string",
                 "transient_beyond_record", "fig03_without_trace",
                 "sweep_rms_beyond_float_range", "tiny_max_cells", "key_given_twice",
                 "nested_aliases", "collision_without_replace", "empty_file", "only_comments",
                 "seed_octal", "study_named_yes")
assert {c.id for c in CASES} >= set(COMMAND_CASES)
assert {c.id for c in CASES if not c.snakemake} <= set(COMMAND_CASES)


def _snakemake_parse(work, configfile):
    """What ``snakemake --cores 1 --configfile CONFIGFILE`` does before its first job, in this
    process: Snakemake loads the file and reads the Snakefile (which checks the config)."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.enums import Quietness
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings

    with SnakemakeApi(OutputSettings(quiet={Quietness.ALL})) as api:
        api.workflow(resource_settings=ResourceSettings(cores=1),
                     config_settings=ConfigSettings(configfiles=[configfile]),
                     snakefile=work / "workflow" / "Snakefile", workdir=work).dag()


@pytest.mark.workflow
@pytest.mark.parametrize("case", CASES, ids=_ids(CASES))
def test_snakemake_refuses(copy_dir, case):
    """Snakemake's loader and the Snakefile refuse the file with the message; where
    Snakemake's own loader refuses it first (an empty file), in words of its own."""
    (copy_dir / "bad.yaml").write_text(case.yaml_text())
    with pytest.raises(Exception) as info:
        _snakemake_parse(copy_dir, copy_dir / "bad.yaml")
    text = str(info.value)
    if case.snakemake:
        assert case.key in text, f"key path {case.key!r} not named:\n{text[-3000:]}"
        assert case.fragment in text, f"allowed range {case.fragment!r} not given:\n{text}"
    else:
        assert "Config file must be given as JSON or YAML" in text, text
    _no_job_ran(copy_dir)


@pytest.mark.workflow
@pytest.mark.parametrize("case", [c for c in CASES if c.id in COMMAND_CASES],
                         ids=_ids(c for c in CASES if c.id in COMMAND_CASES))
def test_the_command_refuses(copy_dir, case):
    """Plain `snakemake`, or the entry point `make` calls where Snakemake's own loader
    refuses the file first (an empty file: its message cannot name it)."""
    (copy_dir / "bad.yaml").write_text(case.yaml_text())
    cmd = ([SNAKEMAKE] if case.snakemake else [sys.executable, "-m", "vibroimpact", "run"]) + [
        "--cores", "1", "--configfile", "bad.yaml"]
    out = subprocess.run(cmd, cwd=copy_dir, capture_output=True, text=True, timeout=120)
    text = out.stdout + out.stderr
    assert out.returncode != 0, text[-3000:]
    assert case.key in text, f"key path {case.key!r} not named:\n{text[-3000:]}"
    assert case.fragment in text, f"allowed range {case.fragment!r} not given:\n{text[-3000:]}"
    _no_job_ran(copy_dir)


@pytest.mark.workflow
def test_plan_reports_yaml_syntax_error(copy_dir):
    (copy_dir / "broken.yaml").write_text(BROKEN)
    out = subprocess.run([sys.executable, "-m", "vibroimpact", "plan", "--configfile",
                          "broken.yaml"], cwd=copy_dir, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 2, out.stdout + out.stderr
    assert f"broken.yaml:{_broken_mark()}" in out.stderr
    assert out.stderr.startswith("error: ")
    _no_job_ran(copy_dir)


# --- legitimate studies and readings that must build ------------------------------------------

def _own_study(**keys):
    """OWN as a dict, its study `mine` with ``keys`` set."""
    user = yaml.safe_load(OWN)
    user["studies"]["mine"].update(keys)
    return user


@pytest.mark.parametrize("delta", [{"start": 1.0e-12, "stop": 5.0e-12, "step": 1.0e-12},
                                   [1.0e-12, 2.0e-12, 3.0e-12, 4.0e-12, 5.0e-12]])
def test_a_study_at_a_tiny_scale_keeps_its_plays_distinct(delta):
    """The README's scaling argument (the model is linear between impacts: plays and force
    divided by one factor): plays 1e-12 ... 5e-12 with rms 1e-12 are five distinct cells,
    rounded at 1e-10 of their scale (10 decimals of a grid of scale >= 1), not to 0."""
    from vibroimpact.pipeline.study import grid_values

    config, plan = configuration.load(_own_study(delta=delta, rms=1.0e-12), root=ROOT)
    values = grid_values(config["studies"]["mine"]["delta"])
    assert values.tolist() == pytest.approx([1e-12, 2e-12, 3e-12, 4e-12, 5e-12], rel=1e-9)
    assert plan.cells == 5


def test_a_tiny_forcing_period_is_named_by_its_value():
    """inv_beta from 2e-11 (beyond dt/(2 pi): refused), named 2e-11 and not rounded to 0."""
    user = _own_study(amplitude=1.0e-12, rms=1.0e-12, delta=[0.0, 1.0e-12],
                      inv_beta={"start": 2.0e-11, "stop": 4.0e-11, "step": 1.0e-11})
    with pytest.raises(configuration.ConfigError) as info:
        configuration.load(user, root=ROOT)
    text = str(info.value)
    assert "inv_beta = 2.0e-11" in text and "1/beta_f = 0" not in text, text


@pytest.mark.parametrize("delta", [[1.0e-7, 2.0e-7, 3.0e-7],
                                   {"start": 1.0e-7, "stop": 3.0e-7, "step": 1.0e-7}])
def test_small_values_listed_once_are_not_duplicates(delta):
    """Duplicates are values equal at the grid's rounding relative to their scale (1e-10 of
    it): 1e-7, 2e-7, 3e-7 are three plays in either form, as are density plays on them."""
    config, plan = configuration.load(
        _own_study(delta=delta, rms=1.0e-7, density_delta=[3.0e-7, 2.0e-7]), root=ROOT)
    assert plan.cells == 3


def test_default_grids_are_bit_identical_to_the_ten_decimal_rounding():
    """The grids of config/config.yaml and config/test.yaml (every {start, stop, step}, all of
    scale >= 1) are what the former rounding to 10 decimals gave, bit for bit."""
    import numpy as np

    from vibroimpact.pipeline.study import grid_size, grid_values

    found = []

    def walk(value):
        if isinstance(value, dict):
            if set(value) == {"start", "stop", "step"}:
                old = np.round(float(value["start"])
                               + float(value["step"]) * np.arange(grid_size(value)), 10)
                assert grid_values(value).tobytes() == old.tobytes(), value
                found.append(value)
            for item in value.values():
                walk(item)

    for name in ("config.yaml", "test.yaml"):
        walk(yaml.safe_load((ROOT / "config" / name).read_text()))
    assert len(found) == 14


def test_a_json_config_is_read_as_json(tmp_path):
    """Snakemake reads a config file as JSON first: 5e-2 is a number there, not YAML 1.1
    text; a key given twice in a JSON object is refused like YAML's."""
    import json

    path = tmp_path / "mine.json"
    path.write_text(json.dumps(_own_study(zeta=0.05)).replace("0.05", "5e-2"))
    assert "5e-2" in path.read_text()
    config, _ = configuration.load(root=ROOT, user_files=[path])
    assert config["studies"]["mine"]["zeta"] == 0.05
    path.write_text('{"paper": false, "paper": true}')
    with pytest.raises(configuration.ConfigError, match="JSON: the key 'paper' is given twice"):
        configuration.read_yaml(path)


@pytest.mark.parametrize("text, value", [("0", 0), ("00", 0), ("007", 7), ("0x10", 16),
                                         ("1_000", 1000), ("0.05", 0.05), ("1.0e+6", 1.0e6)])
def test_unambiguous_numbers_read_as_before(tmp_path, text, value):
    """Only a leading 0 that changes the value (octal) and colons (base 60) are refused."""
    path = tmp_path / "n.yaml"
    path.write_text(f"x: {text}\n")
    assert configuration.read_yaml(path) == {"x": value}


def test_a_non_text_key_in_a_given_dict_is_one_line():
    """A config given as a dict (Snakemake's) with an integer orbits key: one line, not a
    traceback from sorting names."""
    user = _own_study()
    user["orbits"] = {5: {}}
    with pytest.raises(configuration.ConfigError) as info:
        configuration.load(user, root=ROOT)
    assert str(info.value) == ("orbits: the key 5 is an integer, not a name (YAML reads yes:, "
                               "123:, ~: so); allowed: text: quote it, or rename it")


def test_several_files_after_one_configfile(tmp_path, capsys):
    """`python -m vibroimpact plan --configfile a.yaml b.yaml` layers both, as Snakemake
    takes them (`make CONFIG="a.yaml b.yaml"` passes this); a target after them is named."""
    from vibroimpact.pipeline import cli

    (tmp_path / "a.yaml").write_text(OWN)
    (tmp_path / "b.yaml").write_text(OWN.replace("paper: false\n", "").replace("mine:", "more:"))
    a, b = str(tmp_path / "a.yaml"), str(tmp_path / "b.yaml")
    assert cli.main(["plan", "--directory", str(ROOT), "--configfile", a, b]) == 0
    out = capsys.readouterr().out
    assert "studies.mine" in out and "studies.more" in out
    code = cli.main(["plan", "--directory", str(ROOT), "--configfile", a,
                     "results/figures/fig09.png"])
    assert code == 2
    assert ("--configfile results/figures/fig09.png: no such config file; every name after "
            "--configfile is one") in capsys.readouterr().err
    code = cli.main(["run", "--directory", str(ROOT), "--configfile", a,
                     "results/figures/fig09.png"])
    assert code == 2
    assert (f"give targets before it, e.g. run results/figures/fig09.png --configfile {a}"
            in capsys.readouterr().err)


#: Two studies on one short record: plastic impact (eps = 0) with Figs. 7, 9 and its report,
#: and the scale 1e-12 of the README's argument beside the same study at scale 0.5.
SCALED = textwrap.dedent("""\
    paper: false
    noises:
      short_input: {kind: band_limited, rms: 0.5, dt: 0.1, beta_c: 4.0, n_samples: 200001,
                    seed: 11}
    studies:
      plastic:
        noise: short_input
        zeta: 0.05
        eps: 0
        delta: [-0.5, 0, 0.5]
        density_delta: [0.5, 0.0, -0.5]
        figures: [fig07, fig09]
      tiny:
        noise: short_input
        zeta: 0.05
        eps: 0.5
        rms: 1.0e-12
        delta: {start: 1.0e-12, stop: 5.0e-12, step: 1.0e-12}
        figures: [fig09]
      scaled:
        noise: short_input
        zeta: 0.05
        eps: 0.5
        delta: {start: 0.5, stop: 2.5, step: 0.5}
        figures: [fig09]
    """)


@pytest.mark.workflow
def test_plastic_and_tiny_studies_build(tmp_path):
    """eps = 0 builds its figures and report (finding 2: n/a, not a division by 0); the study
    at scale 1e-12 is the study at scale 0.5 divided by 5e11 (the model is linear between
    impacts, and the record is the same seed scaled): the same collisions at every play and
    means within 1e-12 relative (measured 2e-15), so its five plays stayed apart."""
    import xarray as xr

    work = make_workdir(tmp_path)
    (work / "mine.yaml").write_text(SCALED)
    out = subprocess.run([SNAKEMAKE, "--cores", "1", "--configfile", "mine.yaml"], cwd=work,
                         capture_output=True, text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    report = (work / "results" / "reports" / "plastic" / "random_force.html").read_text()
    assert "eps = 0: plastic impact" in report
    with (xr.open_dataset(work / "results" / "datasets" / "tiny_events.nc") as tiny,
          xr.open_dataset(work / "results" / "datasets" / "scaled_events.nc") as scaled):
        assert tiny.n_collisions.values.tolist() == scaled.n_collisions.values.tolist()
        for name, factor in (("v_after_mean", 2e-12), ("interval_mean", 1.0)):
            ratio = tiny[name].values / (factor * scaled[name].values)
            assert abs(ratio - 1.0).max() < 1e-12, (name, ratio)


def test_a_long_schema_description_is_cut_in_the_message(tmp_path):
    """A value refused under a key whose description is a paragraph (plane's: ~1 100
    characters) gets a message of one readable line that says where the rest is."""
    path = tmp_path / "bad.yaml"
    path.write_text(textwrap.dedent("""
        paper: false
        studies:
          pl:
            noise: harmonic_input
            zeta: 0.05
            amplitude: 1.0
            plane: "eps, delta"
            eps: 0.5
            inv_beta: 1.1
            delta: [0.0, 1.0]
            transient: 100.0
            figures: [fig15]
        """))
    with pytest.raises(ConfigError) as info:
        configuration.load(root=ROOT, user_files=[path])
    line = next(m for m in str(info.value).splitlines() if "studies.pl.plane" in m)
    assert len(line) < 400, line
    assert line.endswith("(the whole description: workflow/schemas/config.schema.yaml, "
                         "studies.pl.plane)")


def test_the_plane_cases_edit_an_accepted_study(tmp_path):
    """Each plane case is refused for its one edit: the study they edit is accepted."""
    path = tmp_path / "plane.yaml"
    path.write_text(PLANE_STUDY)
    configuration.load(root=ROOT, user_files=[path])
