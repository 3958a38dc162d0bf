"""The workflow's units of work as plain functions of config entries and paths.

Each task reads its inputs, calls the numerical modules and writes one output atomically.
They know nothing of Snakemake: the scripts under ``workflow/scripts`` only unpack
``snakemake.*`` into these calls, and the tests call them directly.
"""
import logging

import xarray as xr

from vibroimpact.pipeline import datasets, io
from vibroimpact.noise import NoiseSpec
from vibroimpact.pipeline.study import Study, grid_values

log = logging.getLogger("vibroimpact")

_NOISE_FIELDS = ("kind", "rms", "dt", "beta_c", "zeta_f")


def noise_spec(entry):
    """The :class:`NoiseSpec` of a ``noises`` config entry."""
    return NoiseSpec(**{k: entry[k] for k in _NOISE_FIELDS if entry.get(k) is not None})


def make_noise(entry, out, provenance):
    """Rule ``noise``: generate the record of a ``noises`` entry into ``out``."""
    spec = noise_spec(entry)
    log.info("generating %d samples of %s", entry["n_samples"], spec)
    io.write_noise(out, spec, int(entry["n_samples"]), int(entry["seed"]),
                   attrs=provenance, nperseg=int(entry.get("nperseg", 2048)))


def _study_attrs(study, entry, noise_attrs, provenance):
    attrs = dict(provenance, study=study.name, zeta=study.zeta, eps=study.eps,
                 amplitude=study.amplitude, noise=entry["noise"],
                 noise_rms=float(noise_attrs["noise_rms"]), noise_kind=str(noise_attrs["noise_kind"]),
                 seed=int(noise_attrs["seed"]), dt=float(noise_attrs["dt"]))
    if noise_attrs.get("noise_beta_c") is not None:
        attrs["noise_beta_c"] = float(noise_attrs["noise_beta_c"])
    return attrs


def _physics(study, cell):
    return dict(zeta=study.zeta, eps=study.eps, delta=cell.delta, amplitude=study.amplitude,
                beta_f=1.0 / cell.inv_beta)


def events_tile(name, entry, tile, noise_path, out, provenance):
    """Rule ``simulate_events``: impact statistics of the cells of one tile."""
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    study = Study.from_config(name, entry)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    edges = datasets.bin_edges(entry["bins"])
    results = []
    for cell in study.tile(tile, "events"):
        log.info("cell %d: inv_beta=%g delta=%g", cell.index, cell.inv_beta, cell.delta)
        results.append(cells.event_statistics(
            samples, dt, **_physics(study, cell), transient=float(entry["transient"]),
            t_end=entry.get("t_end"), bins=edges, n_batches=int(entry["n_batches"]),
            motion_window=float(entry["motion_window"])))
    ds = datasets.events_tile(study.tile(tile, "events"), results, edges,
                              _study_attrs(study, entry, noise_attrs, provenance))
    io.write_dataset(ds, out)


def spectra_tile(name, entry, tile, noise_path, out, provenance):
    """Rule ``simulate_spectra``: Welch spectra of a(tau) for the cells of one tile."""
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    study = Study.from_config(name, entry)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    spectra = entry["spectra"]
    results = [cells.spectra_statistics(samples, dt, **_physics(study, cell),
                                        transient=float(entry["transient"]),
                                        t_end=spectra.get("t_end"), nperseg=int(spectra["nperseg"]))
               for cell in study.tile(tile, "spectra")]
    ds = datasets.spectra_tile(study.tile(tile, "spectra"), results,
                               _study_attrs(study, entry, noise_attrs, provenance))
    io.write_dataset(ds, out)


def trace(name, entry, noise_path, out, provenance):
    """Rule ``simulate_trace``: a short sampled record from rest (Figs. 3, 10)."""
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    study = Study.from_config(name, entry)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    spec = entry["trace"]
    inv_beta = float(spec.get("inv_beta", study.inv_beta[0]))
    tr = cells.trace(samples, dt, zeta=study.zeta, eps=study.eps, delta=float(spec["delta"]),
                     amplitude=study.amplitude, beta_f=1.0 / inv_beta, t_end=float(spec["t_end"]))
    attrs = dict(_study_attrs(study, entry, noise_attrs, provenance), delta=float(spec["delta"]),
                 beta_f=1.0 / inv_beta)
    io.write_dataset(datasets.trace_dataset(tr, attrs), out)


def aggregate(name, entry, kind, tiles, out, provenance, noise_path=None):
    """Rules ``aggregate_events`` / ``aggregate_spectra``: one dataset per study."""
    study = Study.from_config(name, entry)
    parts = [xr.load_dataset(p) for p in tiles]
    attrs = dict(parts[0].attrs, **provenance)
    if kind == "events":
        attrs.update(density_delta=[float(d) for d in (entry.get("density_delta") or study.delta[:7])],
                     motion_window=float(entry["motion_window"]))
        ds = datasets.aggregate_events(parts, study, attrs)
    else:
        spec = io.noise_spec(io.read_noise_attrs(noise_path))
        ds = datasets.aggregate_spectra(parts, study, spec, attrs,
                                        input_correlation=io.read_input_correlation(noise_path))
    io.write_dataset(ds, out)


def log_to(path):
    """Send this job's log messages and warnings to ``path`` (the rule's ``log:`` file)."""
    logging.basicConfig(filename=path, level=logging.INFO, force=True,
                        format="%(asctime)s %(levelname)s %(message)s")
    logging.captureWarnings(True)


def figure(name, inputs, out_png, **options):
    """Figure rules: ``vibroimpact.plotting.<name>(*datasets, **options)`` saved to ``out_png``."""
    from vibroimpact import plotting

    with plotting.style():
        fig = getattr(plotting, name)(*[xr.load_dataset(p) for p in inputs], **options)
        plotting.save(fig, out_png)


def orbit_rows(entry):
    """The ``inv_beta`` values of an ``orbits`` entry and its number of tiles (row groups)."""
    rows = grid_values(entry["inv_beta"])
    return rows, -(-rows.size // int(entry["tile_rows"]))


def orbit_tile(entry, tile, out, provenance):
    """Rule ``orbit_tile``: existence and stability of (m/n) motions on some ``inv_beta`` rows."""
    from vibroimpact.orbits import orbit_map

    rows, n_tiles = orbit_rows(entry)
    result = orbit_map(rows[tile::n_tiles], grid_values(entry["delta"]),
                       types=[tuple(t) for t in entry["types"]], zeta=float(entry["zeta"]),
                       eps=float(entry["eps"]))
    attrs = dict(provenance, zeta=float(entry["zeta"]), eps=float(entry["eps"]), amplitude=1.0)
    io.write_dataset(datasets.orbit_map_dataset(result, attrs), out)


def aggregate_orbits(tiles, out, provenance):
    """Rule ``aggregate_orbits``: the orbit map of one entry from its tiles."""
    ds = datasets.concat_orbit_tiles([xr.load_dataset(p) for p in tiles])
    ds.attrs.update(provenance)
    io.write_dataset(ds, out)
