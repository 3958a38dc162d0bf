"""xarray datasets of the workflow: per-tile cell results and their per-study aggregates.

The layouts are documented in ``docs/datasets.md``; every variable carries ``long_name``
and ``units`` (plots take their labels from them).
"""
import json

import numpy as np
import pandas as pd
import xarray as xr

from vibroimpact import stats

#: long_name and units of the other axes a map's plane may have
#: (`pipeline.study.PLANE_PARAMETERS`); given to a plane's map only (an escape dataset's
#: ``rms`` keeps its own words).
PLANE_META = {
    "inv_beta": ("inverse forcing frequency ratio 1/beta_f", "1"),
    "delta": ("play delta", "1"),
    "zeta": ("damping ratio zeta", "1"),
    "eps": ("restitution coefficient eps (of the wall at delta)", "1"),
    "eps_lower": ("restitution coefficient eps_lower of the wall at delta - gap", "1"),
    "gap": ("clearance gap between the walls (the lower wall at x = delta - gap)", "1"),
    "amplitude": ("amplitude of the harmonic force", "1"),
    "rms": ("rms of the random force r(tau)", "1"),
}

#: long_name and units of every variable the datasets hold.
META = {
    "inv_beta": ("inverse forcing frequency ratio 1/beta_f", "1"),
    "delta": ("play delta", "1"),
    "cell": ("cell index", "1"),
    "v_after": ("velocity after impact (a collision's first rebound)", "1"),
    "interval": ("interval between collisions z_j", "1"),
    "ratio": ("interval ratio z_j / z", "1"),
    "motion": ("impact motion (m/n)", "1"),
    "beta": ("frequency ratio beta = omega/omega_0", "1"),
    "n_collisions": ("number of collisions (an impact after a free flight, with its chatter "
                     "and sticking)", "1"),
    "collision_rate": ("collisions per unit time", "1"),
    "n_impacts_resolved": ("impacts the simulator resolved one by one (numerical: set by its "
                           "chatter tolerance; cost models only)", "1"),
    "stuck_fraction": ("fraction of collisions that end sticking on the wall", "1"),
    "stick_time_mean": ("mean time on the wall per collision", "1"),
    "rebounds_mean": ("mean rebounds per collision leaving faster than the rebound floor", "1"),
    "n_rebounds": ("rebounds leaving faster than the rebound floor (per-rebound view)", "1"),
    "rebound_v_after_mean": ("mean velocity after a rebound, rebounds above the floor "
                             "(per-rebound view)", "1"),
    "simulated_time": ("record length after the transient", "1"),
    "v_after_mean": ("mean velocity after impact (per collision)", "1"),
    "v_after_stderr": ("standard error of the mean velocity after impact (ratio estimator over "
                       "B equal stretches of time)", "1"),
    "v_after_mean_lo": ("lower end of the 95 % interval of the mean velocity after impact "
                        "(t of nonempty time batches - 1 dof)", "1"),
    "v_after_mean_hi": ("upper end of the 95 % interval of the mean velocity after impact",
                        "1"),
    "v_after_lag1": ("lag-1 autocorrelation of the batch means of the velocity after impact", "1"),
    "interval_mean": ("mean interval between collisions T/N (record length after the "
                      "transient over the collisions in it: the reciprocal rate)", "1"),
    "interval_stderr": ("standard error of the mean interval T/N (delta method, "
                        "T/N sqrt(max(D, 1)/N), D the count dispersion)", "1"),
    "interval_mean_lo": ("lower end of the 95 % interval of the mean interval T/N (Garwood, "
                         "widened for overdispersed counts)", "1"),
    "interval_mean_hi": ("upper end of the 95 % interval of the mean interval T/N (inf: no "
                         "collision)", "1"),
    "count_dispersion": ("index of dispersion var/mean of the collision counts in B equal "
                         "stretches of time (1: Poisson; > 1: bursts)", "1"),
    "interval_lag1": ("lag-1 autocorrelation of the batch means of the interval", "1"),
    "power_residual": ("residual of the power balance <f v> - 2 zeta <v^2> - "
                       "(1 - eps^2) nu <V^2> / 2 (exact identity: zero within its error)", "1"),
    "power_residual_stderr": ("standard error of the power-balance residual (batch means)",
                              "1"),
    "power_input": ("mean power of the force <f v> (scale of the power-balance residual)", "1"),
    "virial_residual": ("residual of the virial <v^2> - <x^2> + <x f> - delta [(1 + eps) nu <V> "
                        "+ <wall reaction while resting>] (exact identity)", "1"),
    "virial_residual_stderr": ("standard error of the virial residual (batch means)", "1"),
    "virial_scale": ("mean square velocity <v^2> (scale of the virial residual)", "1"),
    "n_batches": ("batches B of the batch-means standard errors (t quantile: B - 1 dof)", "1"),
    "contact_fraction": ("fraction of time resting on the wall", "1"),
    "v_after_density": ("probability density of the velocity after impact", "1"),
    "v_after_density_stderr": ("batch-means standard error of the velocity density", "1"),
    "v_after_beyond": ("fraction of velocities after impact beyond the last bin", "1"),
    "interval_density": ("probability density of the interval between collisions", "1"),
    "interval_density_stderr": ("batch-means standard error of the interval density", "1"),
    "interval_beyond": ("fraction of intervals beyond the last bin", "1"),
    "ratio_density": ("probability density of z_j / z", "1"),
    "ratio_density_stderr": ("batch-means standard error of the density of z_j / z", "1"),
    "ratio_beyond": ("fraction of ratios z_j / z beyond the last bin", "1"),
    "motion_probability": ("probability of the impact motion with free flights "
                           "(fraction of time)", "1"),
    "rule": ("grouping rule of the impacts: physical (today's), impacts (the earlier "
             "impacts-only rule), rebounds (every rebound above the floor)", "1"),
    "rule_n_events": ("collisions (events) under the grouping rule", "1"),
    "rule_collision_rate": ("collisions per unit time under the grouping rule", "1"),
    "rule_v_after_mean": ("mean velocity after impact under the grouping rule", "1"),
    "rule_interval_mean": ("mean interval between collisions under the grouping rule", "1"),
    "rule_motion_probability": ("probability of the impact motion with free flights under "
                                "the grouping rule (fraction of time)", "1"),
    "rule_motion_stick_probability": ("probability of the motion's impact-stick variant "
                                      "under the grouping rule (fraction of time)", "1"),
    "rule_probability": ("probability of the impact motion with free flights under the "
                         "grouping rule, at the cell's stopping point (fraction of time)", "1"),
    "rule_stick_probability": ("probability of the motion's impact-stick variant under the "
                               "grouping rule, at the cell's stopping point", "1"),
    "motion_stick_probability": ("probability of the motion's impact-stick variant "
                                 "(fraction of time)", "1"),
    "probability": ("probability of the impact motion with free flights (fraction of time)", "1"),
    "probability_stderr": ("batch-means standard error of the probability", "1"),
    "stick_probability": ("probability of the motion's impact-stick variant: a collision sticks "
                          "(fraction of time)", "1"),
    "stick_probability_stderr": ("batch-means standard error of the stick probability", "1"),
    "n_switches": ("changes between classified motions in the record", "1"),
    "state": ("impact motion (m/n), free and impact-stick variants together, or none (time in "
              "no listed motion)", "1"),
    "from_motion": ("motion switched from (as state)", "1"),
    "to_motion": ("motion switched to (as state)", "1"),
    "residence_time": ("mean residence time: mean length of the complete stretches of the "
                       "motion, in forcing periods 2 pi / beta_f", "1"),
    "residence_time_stderr": ("standard error of the mean residence time (spread of the "
                              "stretches), in forcing periods", "1"),
    "n_stretches": ("complete stretches of the motion (both ends inside the record)", "1"),
    "n_censored": ("stretches of the motion cut by the record's start or end (not in the "
                   "mean)", "1"),
    "residence_time_none": ("mean residence time in no listed motion (runs of unclassified "
                            "intervals), in forcing periods", "1"),
    "residence_time_stderr_none": ("standard error of residence_time_none, in forcing periods",
                                   "1"),
    "n_stretches_none": ("complete stretches of no listed motion", "1"),
    "n_censored_none": ("stretches of no listed motion cut by the record's start or end", "1"),
    "switch_rate": ("switches from from_motion to to_motion per forcing period spent in "
                    "from_motion (NaN: from_motion never seen)", "1"),
    "switch_count": ("switches from from_motion to to_motion in the record", "1"),
    "few_switches": ("1: between 1 and min_switches - 1 switches (probabilities not "
                     "stationary)", "1"),
    "reached": ("1: every probability reached the target standard error", "1"),
    "record_end": ("last simulated instant (from rest at tau = 0)", "1"),
    "n_checks": ("precision checks made while extending the record", "1"),
    "cpu_time": ("CPU time of the cell (s)", "s"),
    "S_a": ("power spectral density of a(tau) (two-sided, eq. 9)", "1"),
    "S_a_batch": ("power spectral density of a(tau) over one batch (consecutive stretch) of "
                  "the record (two-sided, eq. 9)", "1"),
    "S_f": ("power spectral density of the random input r(tau) (estimate, two-sided)", "1"),
    "S_r_target": ("power spectral density of the random input r(tau) (target, two-sided)", "1"),
    "S_lin": ("linear response |H|^2 S_f (no wall)", "1"),
    "n_segments": ("Welch segments averaged", "1"),
    "lag": ("time lag tau*", "1"),
    "phi_r": ("autocorrelation of the random input (estimate, eq. 8)", "1"),
    "phi_r_target": ("autocorrelation of the random input (target)", "1"),
    "tau": ("dimensionless time tau", "1"),
    "r": ("random force r(tau)", "1"),
    "f": ("input force f(tau)", "1"),
    "a": ("displacement from the wall a(tau)", "1"),
    "x": ("displacement x(tau)", "1"),
    "impact_time": ("impact instant", "1"),
    "impact_velocity": ("approach velocity at impact", "1"),
    "impact_collision": ("collision of the impact (index; its first impact starts it)", "1"),
    # two walls only (a study with a gap): docs/datasets.md, "Two walls"
    "wall": ("wall: upper (x = delta, hit from below) or lower (x = delta - gap, hit from "
             "above)", "1"),
    "impact_wall": ("wall of the impact (0: upper, at delta; 1: lower, at delta - gap)", "1"),
    "wall_n_collisions": ("number of collisions at the wall", "1"),
    "wall_collision_rate_lo": ("lower end of the 95 % interval of the wall's collision rate",
                               "1"),
    "wall_collision_rate_hi": ("upper end of the 95 % interval of the wall's collision rate",
                               "1"),
    "wall_count_dispersion": ("index of dispersion of the wall's collision counts in B equal "
                              "stretches of time", "1"),
    "wall_interval_stderr": ("standard error of the wall's mean interval T/N_w", "1"),
    "wall_v_after_stderr": ("standard error of the wall's mean velocity after impact", "1"),
    "wall_v_after_beyond": ("fraction of the wall's velocities after impact beyond the last "
                            "bin", "1"),
    "wall_interval_beyond": ("fraction of the wall's intervals beyond the last bin", "1"),
    "wall_ratio_density": ("probability density of z_j / z between collisions at the wall",
                           "1"),
    "wall_ratio_density_stderr": ("batch-means standard error of the wall's density of "
                                  "z_j / z", "1"),
    "wall_ratio_beyond": ("fraction of the wall's ratios z_j / z beyond the last bin", "1"),
    "wall_collision_rate": ("collisions at the wall per unit time", "1"),
    "wall_v_after_mean": ("mean velocity after impact at the wall (eps_w u, per collision)",
                          "1"),
    "wall_v_after_mean_lo": ("lower end of the 95 % interval of the wall's mean velocity "
                             "after impact", "1"),
    "wall_v_after_mean_hi": ("upper end of the 95 % interval of the wall's mean velocity "
                             "after impact", "1"),
    "wall_interval_mean": ("mean interval between collisions at the wall T/N_w (the "
                           "reciprocal of its rate)", "1"),
    "wall_interval_mean_lo": ("lower end of the 95 % interval of the wall's mean interval",
                              "1"),
    "wall_interval_mean_hi": ("upper end of the 95 % interval of the wall's mean interval "
                              "(inf: no collision)", "1"),
    "wall_stuck_fraction": ("fraction of the wall's collisions that end sticking on it", "1"),
    "wall_v_after_density": ("probability density of the velocity after impact at the wall",
                             "1"),
    "wall_v_after_density_stderr": ("batch-means standard error of the wall's velocity "
                                    "density", "1"),
    "wall_interval_density": ("probability density of the interval between collisions at "
                              "the wall (one of its collisions to its next)", "1"),
    "wall_interval_density_stderr": ("batch-means standard error of the wall's interval "
                                     "density", "1"),
}

_EVENT_SCALARS = ("n_collisions", "collision_rate", "simulated_time", "n_batches",
                  "v_after_mean", "v_after_stderr", "v_after_mean_lo", "v_after_mean_hi",
                  "v_after_lag1", "interval_mean", "interval_stderr", "interval_mean_lo",
                  "interval_mean_hi", "count_dispersion", "interval_lag1", "contact_fraction",
                  "stuck_fraction",
                  "stick_time_mean", "rebounds_mean", "n_rebounds", "rebound_v_after_mean",
                  "v_after_beyond", "interval_beyond", "power_residual",
                  "power_residual_stderr", "power_input", "virial_residual",
                  "virial_residual_stderr", "virial_scale")
_EVENT_DENSITIES = (("v_after_density", "v_after"), ("v_after_density_stderr", "v_after"),
                    ("interval_density", "interval"), ("interval_density_stderr", "interval"))
#: The statistics under each grouping rule (`stats.RULES`), along dimension ``rule``.
_RULE_SCALARS = ("rule_n_events", "rule_collision_rate", "rule_v_after_mean",
                 "rule_interval_mean")
#: Statistics that need a forcing period: present only for a harmonic study (amplitude != 0).
_HARMONIC_SCALARS = ("ratio_beyond",)
_HARMONIC_DENSITIES = (("ratio_density", "ratio"), ("ratio_density_stderr", "ratio"))


#: Variables that measure the run that made the file (like the attribute ``created``), not
#: results: flagged ``run_measurement = 1``; every other variable is bit-identical between runs.
RUN_MEASUREMENTS = ("cpu_time",)


def annotate(ds):
    """``ds`` with the ``long_name`` and ``units`` of `META` on each variable it names, of
    `PLANE_META` on a plane's other axes and on a tile's cell coordinates ``<x>_cell``; the
    run measurements flagged. Returns ``ds`` (changed in place)."""
    for name in list(ds.variables):
        if name in META:
            ds[name].attrs.update(long_name=META[name][0], units=META[name][1])
        elif name in PLANE_META:
            ds[name].attrs.update(long_name=PLANE_META[name][0], units=PLANE_META[name][1])
        elif name.endswith("_cell") and name.removesuffix("_cell") in PLANE_META:
            long_name, units = PLANE_META[name.removesuffix("_cell")]
            ds[name].attrs.update(long_name=f"{long_name} of the cell", units=units)
        if name in RUN_MEASUREMENTS:
            ds[name].attrs["run_measurement"] = 1
    return ds


def bin_edges(bins_config):
    """Histogram edges ``{"v_after", "interval", "ratio"}`` from ``{name: {max, n}}``."""
    return {name: np.linspace(0.0, float(b["max"]), int(b["n"]) + 1)
            for name, b in bins_config.items()}


def _cell_coords(cells):
    """Coordinates of a tile: the cell indices and each cell's values of its plane's two
    parameters, ``<x>_cell`` and ``<y>_cell`` (the default plane's ``inv_beta_cell``,
    ``delta_cell``)."""
    names = list(cells[0].values) if cells else ["inv_beta", "delta"]
    return dict(cell=[c.index for c in cells],
                **{f"{k}_cell": ("cell", [c.values[k] for c in cells]) for k in names})


def plane_axes(ds):
    """``(x, y)``: the names of a map dataset's (or tile's) two grid parameters: its
    ``axes`` attribute, the default ``("inv_beta", "delta")`` without one."""
    axes = ds.attrs.get("axes")
    if axes is None:
        return ("inv_beta", "delta")
    axes = [axes] if isinstance(axes, str) else list(axes)
    return tuple(str(a) for a in axes)


def _motion_names(motions):
    """``"m/n"``, or ``"(m_upper,m_lower)/n"`` for a two-wall motion: the names
    `stats.motions.motion_key` gives (a test holds them equal), written here so that a job
    writing a dataset does not reach the classification's code (its rebuild scope)."""
    return [f"{m[0]}/{m[1]}" if len(m) == 2 else f"({m[0]},{m[1]})/{m[2]}" for m in motions]


#: The walls of a two-wall dataset's ``wall`` dimension (`stats.WALLS`).
WALLS = ("upper", "lower")
#: The bins of each per-wall density (`stats.wall_statistics`: ``wall_<quantity>_density``).
_WALL_BINS = {"wall_v_after": "v_after", "wall_interval": "interval", "wall_ratio": "ratio"}


def _add_walls(data, coords, results):
    """The per-wall variables of a two-wall tile (the results' ``wall_*`` arrays, wall
    first): scalars over ``(cell, wall)``, densities over ``(cell, wall, <their bins>)``."""
    names = [k for k in results[0] if k.startswith("wall_")]
    if not names:
        return
    for name in names:
        values = np.stack([np.asarray(r[name]) for r in results])
        if values.ndim == 2:
            data[name] = (("cell", "wall"), values)
        else:
            dim = _WALL_BINS[name.removesuffix("_stderr").removesuffix("_density")]
            data[name] = (("cell", "wall", dim), values)
    coords["wall"] = list(WALLS)


def events_tile(cells, results, edges, attrs, motions=stats.DEFAULT_MOTIONS):
    """Dataset of one tile of event statistics, along dimension ``cell``.

    ``results`` are :func:`vibroimpact.pipeline.cells.event_statistics` dicts. The (m/n)
    statistics (``ratio_density(_stderr)``, ``ratio_beyond``, ``motion_probability`` and the
    coordinates ``ratio``, ``motion``) are stored only when the results carry them, that is
    for a harmonic force; all results of a tile must agree.
    """
    harmonic = {"ratio_density" in r for r in results}
    if len(harmonic) != 1:
        raise ValueError("results of one tile mix harmonic and non-harmonic cells")
    harmonic = harmonic.pop()
    scalars = _EVENT_SCALARS + (_HARMONIC_SCALARS if harmonic else ())
    densities = _EVENT_DENSITIES + (_HARMONIC_DENSITIES if harmonic else ())
    data = {name: ("cell", np.array([r[name] for r in results])) for name in scalars}
    for name, dim in densities:
        data[name] = (("cell", dim), np.stack([r[name] for r in results]))
    used = {dim for _, dim in densities}
    centres = {k: 0.5 * (e[1:] + e[:-1]) for k, e in edges.items() if k in used}
    coords = dict(_cell_coords(cells), **centres)
    if harmonic:
        for name in ("motion_probability", "motion_stick_probability"):
            data[name] = (("cell", "motion"), np.stack([r[name] for r in results]))
        coords["motion"] = _motion_names(motions)
    if "rule_collision_rate" in results[0]:         # the grouping rules' sensitivity
        for name in _RULE_SCALARS:
            data[name] = (("cell", "rule"), np.stack([r[name] for r in results]))
        if harmonic:
            for name in ("rule_motion_probability", "rule_motion_stick_probability"):
                data[name] = (("cell", "rule", "motion"), np.stack([r[name] for r in results]))
        coords["rule"] = list(stats.RULES)
    _add_walls(data, coords, results)
    return annotate(xr.Dataset(data, coords=coords, attrs=attrs))


#: The map's residence statistics: over `motion` for the listed motions, and for "none" (time
#: in no listed motion) under the same name with ``_none`` (docs/datasets.md).
RESIDENCE_VARIABLES = ("residence_time", "residence_time_stderr", "n_stretches", "n_censored")
_MAP_SCALARS = ("n_switches", "few_switches", "reached", "n_collisions", "collision_rate",
                "n_impacts_resolved", "v_after_mean", "simulated_time", "record_end", "n_checks",
                "cpu_time")


def map_tile(cells, results, motions, attrs):
    """Dataset of one tile of the probability map (Fig. 15), along dimension ``cell``.

    ``results`` are :func:`vibroimpact.pipeline.cells.motion_map_cell` dicts with a
    ``cpu_time`` entry added by the job.
    """
    data = {name: ("cell", np.array([r[name] for r in results])) for name in _MAP_SCALARS}
    for flag in ("few_switches", "reached"):
        data[flag] = ("cell", data[flag][1].astype("int8"))     # netCDF has no bool
    data["probability"] = (("cell", "motion"), np.stack([r["probability"] for r in results]))
    data["probability_stderr"] = (("cell", "motion"), np.stack([r["stderr"] for r in results]))
    data["stick_probability"] = (("cell", "motion"),
                                 np.stack([r["stick_probability"] for r in results]))
    data["stick_probability_stderr"] = (("cell", "motion"),
                                        np.stack([r["stick_stderr"] for r in results]))
    for name in RESIDENCE_VARIABLES:     # the motions' over `motion`, "none"'s apart
        values = np.stack([r[name] for r in results])
        data[name] = (("cell", "motion"), values[:, :-1])
        data[f"{name}_none"] = ("cell", values[:, -1])
    for name in ("switch_rate", "switch_count"):
        data[name] = (("cell", "from_motion", "to_motion"),
                      np.stack([r[name] for r in results]))
    states = _motion_names(motions) + ["none"]
    coords = dict(_cell_coords(cells), motion=_motion_names(motions), from_motion=states,
                  to_motion=states)
    if "rule_probability" in results[0]:         # the grouping rules' sensitivity
        for name in ("rule_probability", "rule_stick_probability"):
            data[name] = (("cell", "rule", "motion"), np.stack([r[name] for r in results]))
        coords["rule"] = list(stats.RULES)
    _add_walls(data, coords, results)
    return annotate(xr.Dataset(data, coords=coords, attrs=attrs))


def aggregate_map(tiles, study, attrs, n_cells=None):
    """Probability-map dataset of a study (``docs/datasets.md``) from its tiles (the axes
    the study's, or with ``study=None`` the tiles' own, `tile_axes`)."""
    names = plane_axes(tiles[0])
    ds = _to_grid(tiles, *_axes(tiles, study, n_cells=n_cells), names=names).transpose(
        "motion", "from_motion", "to_motion", *names, ..., missing_dims="ignore")
    ds.attrs = dict(attrs)
    ds = annotate(ds)
    if "axes" in attrs:             # a plane's map: its axes named in words
        for name in names:
            ds[name].attrs.update(long_name=PLANE_META[name][0], units=PLANE_META[name][1])
    return ds


def spectra_tile(cells, results, attrs):
    """Dataset of one tile of spectra, along dimension ``cell``."""
    data = dict(S_a=(("cell", "beta"), np.stack([r["S_a"] for r in results])),
                S_f=(("cell", "beta"), np.stack([r["S_f"] for r in results])),
                n_segments=("cell", np.array([r["n_segments"] for r in results])))
    if "S_a_batch" in results[0]:
        data["S_a_batch"] = (("cell", "batch", "beta"),
                             np.stack([r["S_a_batch"] for r in results]))
    coords = dict(_cell_coords(cells), beta=results[0]["beta"])
    return annotate(xr.Dataset(data, coords=coords, attrs=attrs))


def tile_axes(tiles, n_cells=None):
    """``(inv_beta, delta)``: the axes of a study's grid, read from its tiles' cells.

    A tile stores each cell's index (``cell = i * n_delta + j``, inv_beta-major,
    `pipeline.study.Study.cells`) with its values ``inv_beta_cell`` and ``delta_cell``, so
    the aggregate needs no config to rebuild the axes (they are the values the cells ran
    with, bit for bit).

    ``n_cells``: the grid's number of cells, when known (a missing tile is then an error).

    Raises
    ------
    ValueError
        If the cells are not ``0 .. n_cells - 1`` or do not form an ``inv_beta x delta``
        grid in that order.
    """
    cell = np.concatenate([np.asarray(t["cell"]) for t in tiles])
    order = np.argsort(cell, kind="stable")
    n = cell.size if n_cells is None else int(n_cells)
    if not np.array_equal(cell[order], np.arange(n)):
        raise ValueError(f"tiles cover cells {cell[order].tolist()}, expected 0..{n - 1}")
    x, y = plane_axes(tiles[0])
    ib = np.concatenate([np.asarray(t[f"{x}_cell"], dtype=float) for t in tiles])[order]
    d = np.concatenate([np.asarray(t[f"{y}_cell"], dtype=float) for t in tiles])[order]
    other = np.flatnonzero(ib != ib[0])
    n_delta = int(other[0]) if other.size else ib.size
    inv_beta, delta = ib[::n_delta], d[:n_delta]
    if (ib.size % n_delta or not np.array_equal(ib, np.repeat(inv_beta, n_delta))
            or not np.array_equal(d, np.tile(delta, inv_beta.size))):
        raise ValueError(f"the tiles' cells do not form an {x} x {y} grid "
                         f"(cell = i * n_{y} + j)")
    return inv_beta, delta


def _axes(tiles, study, kind="events", n_cells=None):
    """The grid's axes: the study's when given, else the tiles' (`tile_axes`)."""
    if study is None:
        return tile_axes(tiles, n_cells)
    if study.plane is not None:
        return tuple(study.axes[k] for k in study.plane)
    return study.inv_beta, study.spectra_delta if kind == "spectra" else study.delta


def _to_grid(tiles, inv_beta, delta, names=("inv_beta", "delta")):
    """Concatenate tiles along ``cell`` and reshape to ``(x, y, ...)``: the plane's two
    parameters ``names`` (default (inv_beta, delta)) with values ``inv_beta``, ``delta``."""
    x, y = names
    ds = xr.concat(tiles, dim="cell").sortby("cell")
    n = len(inv_beta) * len(delta)
    if ds.sizes["cell"] != n or not np.array_equal(ds["cell"].values, np.arange(n)):
        raise ValueError(f"tiles cover cells {ds['cell'].values.tolist()}, expected 0..{n - 1}")
    index = xr.Coordinates.from_pandas_multiindex(
        pd.MultiIndex.from_product([inv_beta, delta], names=[x, y]), "cell")
    ds = ds.drop_vars(["cell", f"{x}_cell", f"{y}_cell"]).assign_coords(index).unstack("cell")
    return ds.transpose(x, y, ...)


def aggregate_events(tiles, study, attrs, n_cells=None):
    """Events dataset of a study (``docs/datasets.md``) from its tiles (the axes the
    study's, or with ``study=None`` the tiles' own, `tile_axes`)."""
    ds = _to_grid(tiles, *_axes(tiles, study, n_cells=n_cells))
    ds.attrs = dict(attrs)
    return annotate(ds)


def aggregate_spectra(tiles, study, spec, attrs, input_correlation, zeta=None, n_cells=None):
    """Spectra dataset of a study, with the linear reference ``S_lin = |H|^2 S_f``.

    ``study`` gives the axes and ``zeta``; with ``study=None`` the axes are the tiles' own
    (`tile_axes`) and ``zeta`` is given.

    ``spec`` is the :class:`~vibroimpact.noise.NoiseSpec` of the random force; the reference
    uses the spectrum of the piecewise-linear force the simulator integrates.
    ``input_correlation`` is ``(lag, estimate, target)`` of the random input (eq. 8).
    """
    ds = _to_grid(tiles, *_axes(tiles, study, "spectra", n_cells))
    zeta = study.zeta if study is not None else zeta
    # every cell of a row estimates S_f from the same stretch of the same input: keep one
    S_f = ds["S_f"]
    if not (S_f == S_f.isel(delta=0)).all():
        raise ValueError("S_f differs between the deltas of one inv_beta: the cells did not "
                         "see the same input record")
    ds["S_f"] = S_f.isel(delta=0, drop=True)
    beta = ds["beta"].values
    S_r = spec.psd_piecewise_linear(beta)
    ds["S_lin"] = ("beta", stats.linear_psd_response(beta, S_r, zeta))
    ds["S_r_target"] = ("beta", S_r)
    lag, phi, phi_target = input_correlation
    ds = ds.assign_coords(lag=lag)
    ds["phi_r"] = ("lag", phi)
    ds["phi_r_target"] = ("lag", phi_target)
    ds.attrs = dict(attrs)
    return annotate(ds)


def trace_dataset(tr, attrs):
    """Dataset of a short sampled trace (Figs. 3 and 10)."""
    ds = xr.Dataset(
        dict(r=("tau", tr["r"]), f=("tau", tr["f"]), a=("tau", tr["a"]), x=("tau", tr["x"]),
             impact_time=("impact", tr["impact_time"]),
             impact_velocity=("impact", tr["impact_velocity"]),
             impact_collision=("impact", tr["impact_collision"])),
        coords=dict(tau=tr["tau"]), attrs=attrs)
    if "impact_wall" in tr:         # two walls
        ds["impact_wall"] = ("impact", np.asarray(tr["impact_wall"], dtype=np.int8))
    return annotate(ds)


ORBIT_META = {
    "type": ("impact motion (m/n)", "1"),
    "exists": ("an admissible periodic motion exists", "1"),
    "n_solutions": ("number of admissible periodic motions", "1"),
    "n_stable": ("number of stable admissible periodic motions", "1"),
    "lam": ("|lambda| = max|mu|^(1/m) of the most stable admissible motion (eq. 20)", "1"),
    "S": ("degree of stability S = 100 (1 - |lambda|) of the most stable motion (eq. 24)", "%"),
    "reason": ("0 stable / 1 no solution / 2 only inadmissible / 3 only unstable", "1"),
}


def orbit_map_dataset(result, attrs):
    """Dataset of :func:`vibroimpact.orbits.orbit_map` output over ``(type, inv_beta, delta)``."""
    types = _motion_names(result["types"])
    dims = ("type", "inv_beta", "delta")
    ds = xr.Dataset({name: (dims, result[name]) for name in ORBIT_META if name != "type"},
                    coords=dict(type=types, inv_beta=result["inv_beta"], delta=result["delta"]),
                    attrs=dict(attrs, reason_codes="0 stable, 1 no solution, 2 inadmissible, "
                                                   "3 unstable"))
    ds["exists"] = ds["exists"].astype("int8")    # netCDF has no bool
    for name, (long_name, units) in {**META, **ORBIT_META}.items():
        if name in ds.variables:
            ds[name].attrs.update(long_name=long_name, units=units)
    return ds


def concat_orbit_tiles(tiles, dim="inv_beta"):
    """Join orbit-map tiles (disjoint sets of ``dim`` rows: ``inv_beta``, or the tiled axis
    of a plane) into one dataset sorted along ``dim``."""
    return xr.concat(tiles, dim=dim).sortby(dim)


def orbit_map_result(ds):
    """The :func:`vibroimpact.orbits.orbit_map` dict of an orbits dataset (its seeds for
    :func:`vibroimpact.orbits.domain_boundaries`)."""
    out = {name: ds[name].values for name in ("n_solutions", "n_stable", "lam", "S", "reason")}
    out["exists"] = ds["exists"].values.astype(bool)
    out.update(inv_beta=ds["inv_beta"].values, delta=ds["delta"].values,
               types=np.array([[int(k) for k in str(t).split("/")]
                               for t in ds["type"].values], dtype=np.int64).reshape(-1, 2))
    return out


BOUNDARY_META = {
    "inv_beta": ("1/beta_f of a point on a boundary curve", "1"),
    "delta": ("play delta of a point on a boundary curve", "1"),
    "curve": ("index of the curve the point lies on (points of a curve are consecutive, in "
              "order along it)", "1"),
    "kind": ("what happens on the curve: grazing, fold (multiplier +1), period_doubling "
             "(multiplier -1), existence (another end of the stable solution)", "1"),
    "type": ("impact motion (m/n) whose stable domain the curve bounds", "1"),
    "ends": ("why the curve stops at its two ends (box, codim2, coexist, closed, lost), "
             "joined by +", "1"),
    "codim2_inv_beta": ("1/beta_f of a codimension-two point (two kinds meet)", "1"),
    "codim2_delta": ("play delta of a codimension-two point", "1"),
    "codim2_type": ("impact motion (m/n) of the codimension-two point", "1"),
    "codim2_kinds": ("the two kinds that meet there, in alphabetical order, joined by +", "1"),
}


def boundaries_dataset(curves_by_type, attrs, axes=("inv_beta", "delta")):
    """Dataset of the boundary curves of :func:`vibroimpact.orbits.domain_boundaries`, one
    call per type: ``curves_by_type`` is ``{(m, n): result}``; or of
    :func:`vibroimpact.orbits.boundaries.plane_boundaries` over the plane ``axes`` (its
    curves' ``x``, ``y``).

    Dimensions ``point`` (every curve's points, curve after curve), ``curve`` and ``codim2``;
    the points' coordinates are named after the axes (``inv_beta``, ``delta``; over a plane
    ``eps``, ``delta`` ..., and ``codim2_<axis>``).
    """
    x_name, y_name = axes

    def xy(point):      # a plane's curve or point has x, y; domain_boundaries' its own names
        return (point.x, point.y) if hasattr(point, "x") else (point.inv_beta, point.delta)

    xs, ys, index, kinds, types, ends = [], [], [], [], [], []
    c_x, c_y, c_type, c_kinds = [], [], [], []
    for (m, n), result in curves_by_type.items():
        for curve in result:
            x, y = xy(curve)
            xs.append(np.asarray(x, dtype=float))
            ys.append(np.asarray(y, dtype=float))
            index.append(np.full(xs[-1].size, len(kinds), dtype=np.int32))
            kinds.append(str(curve.kind))
            types.append(f"{m}/{n}")
            ends.append("+".join(str(e) for e in getattr(curve, "ends", ())))
        for point in result.codimension_two:
            x, y = xy(point)
            c_x.append(float(x))
            c_y.append(float(y))
            c_type.append(f"{m}/{n}")
            c_kinds.append("+".join(sorted(point.kinds)))

    def cat(parts, dtype):
        return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype)

    ds = xr.Dataset(
        {x_name: ("point", cat(xs, float)), y_name: ("point", cat(ys, float)),
         "curve": ("point", cat(index, np.int32)),
         "kind": ("curve", np.array(kinds, dtype=str)),
         "type": ("curve", np.array(types, dtype=str)),
         "ends": ("curve", np.array(ends, dtype=str)),
         f"codim2_{x_name}": ("codim2", np.array(c_x, dtype=float)),
         f"codim2_{y_name}": ("codim2", np.array(c_y, dtype=float)),
         "codim2_type": ("codim2", np.array(c_type, dtype=str)),
         "codim2_kinds": ("codim2", np.array(c_kinds, dtype=str))},
        attrs=dict(attrs))
    meta = dict(BOUNDARY_META)
    if tuple(axes) != ("inv_beta", "delta"):
        for name in ("inv_beta", "delta", "codim2_inv_beta", "codim2_delta"):
            del meta[name]
        for name in axes:
            meta[name] = (f"{name} of a point on a boundary curve", "1")
            meta[f"codim2_{name}"] = (f"{name} of a codimension-two point (two kinds meet)",
                                      "1")
    for name, (long_name, units) in meta.items():
        ds[name].attrs.update(long_name=long_name, units=units)
    return ds


#: Classes of a start of the attractor map (`vibroimpact.attractor_map`).
ATTRACTOR_CLASSES = ("listed", "periodic_other", "sticking", "chaotic", "undecided",
                     "wall_free")

ATTRACTOR_META = {
    "fraction": ("share of the starts that settle on a stable periodic motion of this type "
                 "(other: every other start)", "1"),
    "fraction_lo": ("lower end of the 95 % Clopper-Pearson interval of fraction", "1"),
    "fraction_hi": ("upper end of the 95 % Clopper-Pearson interval of fraction", "1"),
    "count": ("starts that settle on a stable periodic motion of this type", "1"),
    "n_stable": ("stable admissible periodic motions of this type the solver finds", "1"),
    "stick_fraction": ("share of the starts that settle on this type's impact-stick variant "
                       "(counted in other)", "1"),
    "class_fraction": ("share of the starts in each class", "1"),
    "other_class_fraction": ("share of the starts in each class that settle on none of the "
                             "motions (counted in other)", "1"),
    "lyapunov": ("largest Lyapunov exponent over the cell's starts, per unit of "
                 "non-dimensional time tau (-inf: every start sticks)", "1"),
    "lyapunov_stderr": ("standard error of the exponent of the starts that do not settle, "
                        "per unit of non-dimensional time tau", "1"),
    "cell_class": ("the most frequent class of the cell's starts", "1"),
    "lyapunov_class": ("class of the start whose exponent is the cell's largest", "1"),
    "class_start": ("class of each start (flag_meanings)", "1"),
    "impact_rate": ("collisions per unit of non-dimensional time tau, mean over the cell's "
                    "starts", "1"),
    "lyapunov_start": ("largest Lyapunov exponent of each start, per unit of non-dimensional "
                       "time tau", "1"),
    "motion_start": ("what each start settles on: index into motion", "1"),
    "lyapunov_second_start": ("second Lyapunov exponent of each start, per unit of "
                              "non-dimensional time tau", "1"),
    "settle_time": ("time a start takes to settle on a periodic motion (NaN: not settled)",
                    "1"),
    "period_impacts_start": ("impacts per period of the periodic motion a start settles on "
                             "(collisions of an impact-stick motion; 0: none)", "1"),
    "period_periods_start": ("forcing periods of that period (0: none)", "1"),
    "impacts_lower_start": ("of those impacts, the ones at the wall below", "1"),
    "stick_count": ("starts that settle on this type's impact-stick variant", "1"),
    "class_count": ("starts in each class", "1"),
    "motion": ("what a start settles on: a stable periodic motion of a listed type (m/n), or "
               "other", "1"),
    "type": ("impact motion (m/n)", "1"),
    "class": ("class of what a start settles on: listed, periodic_other, sticking, chaotic, "
              "undecided, wall_free (codes 0-5)", "1"),
    "start": ("starting state of the cell (index)", "1"),
}


def attractor_tile_dataset(result, attrs):
    """Dataset of one :func:`vibroimpact.attractor_map` call over
    ``(inv_beta, delta)``: what the basins and Lyapunov datasets are cut from."""
    motions = list(result["motions"])
    types = motions[:-1]
    plane = tuple(result.get("axes", ("inv_beta", "delta")))
    coords = dict(motion=motions, type=types, **{k: result[k] for k in plane},
                  start=np.arange(result["lyapunov_start"].shape[0]),
                  **{"class": list(ATTRACTOR_CLASSES)})
    data = {name: (("motion", *plane), result[name])
            for name in ("fraction", "fraction_lo", "fraction_hi", "count")}
    data["n_stable"] = (("type", *plane), result["n_stable"])
    data["stick_count"] = (("type", *plane), result["stick_count"])
    data["class_count"] = (("class", *plane), result["class_count"])
    for name in ("lyapunov", "lyapunov_stderr", "impact_rate"):
        data[name] = (plane, result[name])
    data["cell_class"] = (plane, result["cell_class"].astype(np.int8))
    data["lyapunov_class"] = (plane, result["lyapunov_class"].astype(np.int8))
    for name in ("lyapunov_start", "lyapunov_second_start", "settle_time", "motion_start"):
        data[name] = (("start", *plane), result[name])
    data["class_start"] = (("start", *plane), result["class_start"].astype(np.int8))
    two_walls = "gap" in plane or "gap" in result.get("fixed", {})
    if two_walls:
        # two walls: what each settled start's motion is in the study's own names
        data["period_impacts_start"] = (("start", *plane), result["period_start"][0])
        data["period_periods_start"] = (("start", *plane), result["period_start"][1])
        data["impacts_lower_start"] = (("start", *plane), result["impacts_lower_start"])
    ds = _described(xr.Dataset(data, coords=coords, attrs=dict(attrs)))
    if "axes" in result:        # a named plane (attractors.plane.attractor_plane)
        ds.attrs.update(axes=list(plane), fixed=json.dumps(result["fixed"], sort_keys=True),
                        **{k: float(v) for k, v in result["fixed"].items()})
    if two_walls:       # `gap` is the clearance (a fixed value or an axis), as every dataset's
        ds.attrs["n_walls"] = 2             # of a two-wall study; the starts' box: start_gap
        for name in plane:
            ds[name].attrs.update(long_name=PLANE_META[name][0], units=PLANE_META[name][1])
    return ds


def concat_attractor_tiles(tiles):
    """Join attractor-map tiles (disjoint sets of rows of the plane's first axis,
    ``inv_beta`` on the paper's plane) into one sorted dataset."""
    dim = tiles[0]["lyapunov"].dims[0]
    return xr.concat(tiles, dim=dim, data_vars="minimal", coords="minimal",
                     compat="override").sortby(dim)


def _described(ds):
    """An attractor dataset's variables described (`ATTRACTOR_META`), and its plane's axes
    (`META`, `PLANE_META`) where they have no words yet."""
    for name, (long_name, units) in ATTRACTOR_META.items():
        if name in ds.variables:
            ds[name].attrs.update(long_name=long_name, units=units)
    for name in ds.dims:
        words = META.get(name) or PLANE_META.get(name)
        if name in ds.variables and words and "long_name" not in ds[name].attrs:
            ds[name].attrs.update(long_name=words[0], units=words[1])
    return ds


def basins_dataset(tiles, motions=None):
    """The basins dataset (``results/orbits/<name>_basins.nc``) of the joined attractor tiles:
    ``fraction``, its interval, ``count`` over ``(motion, inv_beta, delta)``; ``n_stable`` and
    ``stick_fraction`` over the same (the ``other`` row 0 and NaN); ``class_fraction`` over
    ``(class, inv_beta, delta)``. With two walls (tiles holding ``impacts_lower_start``) and
    the study's ``motions`` ``(m_upper, m_lower, n)``, the basins of those motions instead
    (:func:`two_wall_basins`)."""
    if motions and "impacts_lower_start" in tiles:
        return two_wall_basins(tiles, motions)
    n_starts = int(tiles.attrs["n_starts"])
    other = xr.zeros_like(tiles["n_stable"].isel(type=0)).expand_dims(type=["other"])
    n_stable = xr.concat([tiles["n_stable"], other], dim="type").rename(type="motion")
    stick = (tiles["stick_count"] / n_starts)
    stick = xr.concat([stick, xr.full_like(stick.isel(type=0), np.nan).expand_dims(
        type=["other"])], dim="type").rename(type="motion")
    ds = xr.Dataset(
        {"fraction": tiles["fraction"], "fraction_lo": tiles["fraction_lo"],
         "fraction_hi": tiles["fraction_hi"], "count": tiles["count"],
         "n_stable": n_stable.assign_coords(motion=tiles["motion"].values),
         "stick_fraction": stick.assign_coords(motion=tiles["motion"].values),
         "class_fraction": tiles["class_count"] / n_starts,
         "motion_start": tiles["motion_start"]},
        attrs=dict(tiles.attrs))
    return _described(ds)


def two_wall_basins(tiles, motions):
    """The basins of a two-wall plane over the study's own motions ``(m_upper, m_lower, n)``
    (named ``"(m_upper,m_lower)/n"``, as its Fig. 15): a start counts for a motion when it
    settles on a periodic impact motion (a listed one-wall orbit at either wall, or another
    periodic motion) of ``m_upper + m_lower`` impacts per ``n`` forcing periods, its least
    period, ``m_lower`` of them at the wall below; ``other`` is every other start. No
    ``n_stable`` (the closed-form solver knows one wall) nor ``stick_fraction``;
    ``motion_start`` indexes these motions (``len(motions)``: other)."""
    n_starts = int(tiles.attrs["n_starts"])
    cls = tiles["class_start"].values
    m = tiles["period_impacts_start"].values
    k = tiles["period_periods_start"].values
    low = tiles["impacts_lower_start"].values
    periodic = np.isin(cls, [ATTRACTOR_CLASSES.index("listed"),
                             ATTRACTOR_CLASSES.index("periodic_other")])
    index = np.full(cls.shape, len(motions), np.int64)
    for t, (m_up, m_lo, n) in enumerate(motions):
        index[periodic & (m - low == int(m_up)) & (low == int(m_lo)) & (k == int(n))] = t
    count = np.stack([(index == t).sum(axis=0) for t in range(len(motions) + 1)])
    lo, hi = stats.clopper_pearson(count, n_starts)
    dims = ("motion",) + tiles["class_start"].dims[1:]
    names = _motion_names(motions) + ["other"]
    ds = xr.Dataset(
        {"fraction": (dims, count / n_starts), "fraction_lo": (dims, lo),
         "fraction_hi": (dims, hi), "count": (dims, count),
         "class_fraction": tiles["class_count"] / n_starts,
         "other_class_fraction": (("class",) + dims[1:], np.stack(
             [((index == len(motions)) & (cls == c)).sum(axis=0)
              for c in range(len(ATTRACTOR_CLASSES))]) / n_starts),
         "motion_start": (tiles["class_start"].dims, index)},
        coords={"motion": names, "class": list(ATTRACTOR_CLASSES),
                **{d: tiles[d] for d in dims[1:]}},
        attrs=dict(tiles.attrs))
    return _described(ds)


def lyapunov_dataset(tiles):
    """The Lyapunov dataset (``results/orbits/<name>_lyapunov.nc``) of the joined attractor
    tiles: ``lyapunov``, ``lyapunov_stderr``, ``cell_class`` and ``lyapunov_class`` (CF
    flags), ``impact_rate`` over ``(inv_beta, delta)``, ``class_fraction`` and each start's
    exponents and class (``class_start``, CF flags)."""
    n_starts = int(tiles.attrs["n_starts"])
    ds = xr.Dataset(
        {name: tiles[name] for name in ("lyapunov", "lyapunov_stderr", "cell_class",
                                        "lyapunov_class", "impact_rate", "lyapunov_start",
                                        "lyapunov_second_start", "settle_time", "class_start")},
        attrs=dict(tiles.attrs))
    ds["class_fraction"] = tiles["class_count"] / n_starts
    for name in ("cell_class", "lyapunov_class", "class_start"):
        ds[name].attrs.update(flag_values=np.arange(len(ATTRACTOR_CLASSES), dtype=np.int8),
                              flag_meanings=" ".join(ATTRACTOR_CLASSES))
    return _described(ds)


#: The escape dataset's own variables (``results/datasets/{study}_escape.nc``); the residence
#: variables keep their `META` entries, ``probability`` and the cells' coordinates get these.
ESCAPE_META = {
    "rms": ("rms of the random force r(tau) (samples)", "1"),
    "inv_rms2": ("1 / rms^2 of the random force", "1"),
    "spawn_key": ("SeedSequence spawn key of the level's record: SeedSequence(seed, "
                  "spawn_key=(k,))", "1"),
    "cell": ("escape cell (index into the config's escape.cells)", "1"),
    "inv_beta": ("inverse forcing frequency ratio 1/beta_f of the cell", "1"),
    "delta": ("play delta of the cell", "1"),
    "probability": ("fraction of the record after the transient in the state (a motion with "
                    "its impact-stick variant; none: the rest)", "1"),
    "slope": ("Delta: slope of ln(residence_time) against 1 / rms^2 (weighted least squares "
              "over the levels with fit_used = 1)", "1"),
    "slope_stderr": ("standard error of the slope (scaled by sqrt(chi2_red) when > 1)", "1"),
    "slope_lo": ("lower end of the slope's 95 % interval (Student's t at n_fit - 2 degrees "
                 "of freedom)", "1"),
    "slope_hi": ("upper end of the slope's 95 % interval (Student's t at n_fit - 2 degrees "
                 "of freedom)", "1"),
    "intercept": ("ln C of the fit ln(residence_time) = ln C + slope / rms^2 (C in forcing "
                  "periods)", "1"),
    "chi2_red": ("chi^2 per degree of freedom of the fit (about 1: ln(residence_time) is "
                 "linear in 1 / rms^2 within the errors; NaN: no fit)", "1"),
    "n_fit": ("noise levels in the fit (0: no fit, fewer than 3 usable levels)", "1"),
    "censored_time": ("total length of the state's stretches cut by the record's start or "
                      "end (forcing periods); where a state holding at least half the record "
                      "has n_stretches = 0 (never left), censored_time / n_censored is a lower "
                      "bound of residence_time", "1"),
    "fit_used": ("1: the level enters the fit (enough complete stretches, rms <= "
                 "fit_max_rms)", "1"),
}
_ESCAPE_STATES = ("residence_time", "residence_time_stderr", "n_stretches", "n_censored",
                  "censored_time", "probability")


def escape_part(index, rms, cells, results, motions, attrs, axes=("inv_beta", "delta")):
    """Dataset of one escape job (one noise level, every cell) along ``rms`` (length 1).

    ``cells`` are ``(inv_beta, delta)`` pairs (a plane study's: pairs of its ``axes``, each a
    coordinate along ``cell`` named after its parameter), ``results`` their
    :func:`vibroimpact.pipeline.cells.escape_cell` dicts.
    """
    data = {name: (("rms", "cell", "state"), np.stack([r[name] for r in results])[None])
            for name in _ESCAPE_STATES}
    for name in ("n_collisions", "simulated_time"):
        data[name] = (("rms", "cell"), np.array([[r[name] for r in results]]))
    data["spawn_key"] = ("rms", np.array([int(index)]))
    pairs = np.asarray(cells, dtype=float).reshape(-1, 2)
    x, y = axes
    coords = {"rms": [float(rms)], "cell": np.arange(len(results)),
              "state": _motion_names(motions) + ["none"], x: ("cell", pairs[:, 0]),
              y: ("cell", pairs[:, 1])}
    ds = _escape_described(annotate(xr.Dataset(data, coords=coords, attrs=attrs)))
    if tuple(axes) != ("inv_beta", "delta"):      # a plane's cells: named in its words
        for name in axes:
            ds[name].attrs.update(long_name=f"{PLANE_META[name][0]} of the cell",
                                  units=PLANE_META[name][1])
    return ds


def aggregate_escape(parts, attrs, min_stretches, fit_max_rms=None):
    """The escape dataset (``docs/datasets.md``): the levels joined along ``rms`` (ascending)
    and the fit of ``ln(residence_time)`` against ``1 / rms^2`` of every (cell, state)
    (`stats.escape_fit`: levels with at least ``min_stretches`` complete stretches and, unless
    None, ``rms <= fit_max_rms``)."""
    ds = xr.concat(parts, dim="rms").sortby("rms")
    ds = ds.assign_coords(inv_rms2=("rms", 1.0 / ds["rms"].values ** 2))
    allowed = (np.ones(ds.sizes["rms"], dtype=bool) if fit_max_rms is None
               else ds["rms"].values <= float(fit_max_rms) * (1 + 1e-12))
    shape = (ds.sizes["cell"], ds.sizes["state"])
    fits = {name: np.full(shape, np.nan) for name in ("slope", "slope_stderr", "slope_lo",
                                                      "slope_hi", "intercept", "chi2_red")}
    fits["n_fit"] = np.zeros(shape, dtype=np.int64)
    used = np.zeros((ds.sizes["rms"],) + shape, dtype=np.int8)
    t = ds["residence_time"].transpose("rms", "cell", "state").values
    e = ds["residence_time_stderr"].transpose("rms", "cell", "state").values
    n = ds["n_stretches"].transpose("rms", "cell", "state").values
    for c in range(shape[0]):
        for s in range(shape[1]):
            fit = stats.escape_fit(ds["inv_rms2"].values, t[:, c, s], e[:, c, s], n[:, c, s],
                                   min_stretches=min_stretches, allowed=allowed)
            for name in fits:
                fits[name][c, s] = getattr(fit, "n_used" if name == "n_fit" else name)
            used[:, c, s] = fit.used
    for name, values in fits.items():
        ds[name] = (("cell", "state"), values)
    ds["fit_used"] = (("rms", "cell", "state"), used)
    ds.attrs = dict(attrs, min_stretches=int(min_stretches),
                    fit_max_rms=float("nan") if fit_max_rms is None else float(fit_max_rms))
    return _escape_described(annotate(ds.transpose("rms", "cell", "state")))


def _escape_described(ds):
    for name, (long_name, units) in ESCAPE_META.items():
        if name in ds.variables:
            ds[name].attrs.update(long_name=long_name, units=units)
    return ds
