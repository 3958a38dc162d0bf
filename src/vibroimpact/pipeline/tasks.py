"""The workflow's units of work as plain functions of config blocks and paths.

Each task reads its inputs, calls the numerical modules, records its provenance at run time
(`vibroimpact.pipeline.provenance`) and writes one output atomically. They know nothing of
Snakemake: the scripts under ``workflow/scripts`` only unpack ``snakemake.*`` into these
calls, inside `logged`, and the tests call them directly. ``block`` is the part of a config
entry the task reads (the workflow passes nothing else, so nothing else can rerun it).
"""
import contextlib
import json
import logging
import math
import sys

import numpy as np

from vibroimpact import stats
from vibroimpact._files import DiskFullError
from vibroimpact.pipeline import datasets, io
from vibroimpact.pipeline.provenance import config_text, provenance
from vibroimpact.pipeline.study import (Study, attractor_rows, escape_samples, escape_seed,
                                        grid_size, grid_values, map_cap_steps, orbit_rows,
                                        orbit_tiled_axis, plane_attractor_rows,
                                        laws, shooting, walls)

log = logging.getLogger("vibroimpact")

_NOISE_FIELDS = ("kind", "rms", "dt", "beta_c", "zeta_f")


@contextlib.contextmanager
def logged(path):
    """Send this job's log messages, warnings and, on failure, its traceback to ``path``.

    An unreadable input file (:class:`~vibroimpact.pipeline.io.CorruptFileError`) ends the
    job with its one-line message on stderr (the traceback goes to the log only).
    """
    logging.basicConfig(filename=path, level=logging.INFO, force=True,
                        format="%(asctime)s %(levelname)s %(message)s")
    logging.captureWarnings(True)
    try:
        yield
    except io.CorruptFileError as err:
        log.exception("job failed")
        print(f"error: {err}", file=sys.stderr)
        raise SystemExit(1) from None
    except DiskFullError as err:
        # the console first: the log's own file system is likely the full one, and its
        # handler's failure is not reported over this message
        print(f"error: {err.strerror}", file=sys.stderr)
        logging.raiseExceptions = False
        log.error("job failed: %s", err.strerror)
        raise SystemExit(1) from None
    except BaseException:
        log.exception("job failed")
        raise
    finally:
        logging.shutdown()


#: Seconds between two progress lines of a long job (README, "Progress of a build"): often
#: enough that ``tail -f`` on its log says where it stands, rare enough not to flood it.
PROGRESS_EVERY = 5.0


class Progress:
    """A job's progress over its units (cells, rows, types), logged when it starts, at most
    every ``every`` seconds (default `PROGRESS_EVERY`) and at its end.

    Each line: units done of total, with a simulation's collisions and simulated time
    (``events``), the rate and the time left (README, "Progress of a build"): a long job says
    where it stands without flooding its log. `advance` is the callback the numerical
    modules take as ``progress`` (they know nothing of logging).
    """

    def __init__(self, what, total, unit="cells", every=None, clock=None, events=False):
        import time

        self.what, self.total, self.unit = what, int(total), unit
        self.every = PROGRESS_EVERY if every is None else float(every)
        self.events = events
        self.clock = clock or time.monotonic
        self.start = self.last = self.clock()
        self.done, self.collisions, self.simulated = 0, 0, 0.0
        log.info("progress %s: 0 of %d %s, started", what, self.total, unit)

    def cell_done(self, result):
        """Count one simulated cell (its ``n_collisions`` and ``simulated_time``)."""
        self.collisions += int(result.get("n_collisions", 0))
        self.simulated += float(result.get("simulated_time", 0.0))
        self.advance(1)

    def advance(self, n=1):
        """Count ``n`` more units done; log if ``every`` seconds have passed or all are."""
        self.done += int(n)
        now = self.clock()
        if self.done < self.total and now - self.last < self.every:
            return
        self.last = now
        rate = self.done / max(now - self.start, 1e-9)
        left = (self.total - self.done) / rate if rate > 0 else float("inf")
        counts = (f"{self.collisions} collisions, {self.simulated:.4g} time units simulated, "
                  if self.events else "")
        log.info("progress %s: %d of %d %s, %s%.3g %s/s, ~%.0f s left", self.what, self.done,
                 self.total, self.unit, counts, rate, self.unit, left)


def noise_spec(entry):
    """The :class:`~vibroimpact.noise.NoiseSpec` of a ``noises`` config entry."""
    from vibroimpact.noise import NoiseSpec   # scipy.signal and scipy.fft: not for every job

    return NoiseSpec(**{k: entry[k] for k in _NOISE_FIELDS if entry.get(k) is not None})


def make_noise(entry, out):
    """Rule ``generate_noise``: the record of a ``noises`` entry, into ``out``."""
    spec = noise_spec(entry)
    log.info("generating %d samples of %s", entry["n_samples"], spec)
    io.write_noise(out, spec, int(entry["n_samples"]), int(entry["seed"]),
                   attrs=provenance(entry, entry["seed"]), nperseg=int(entry["nperseg"]))


def _study_attrs(study, block, noise_attrs):
    noise = {k: noise_attrs[k] for k in noise_attrs if k.startswith("noise_")}
    if study.plane is not None:     # the fixed parameters only (the axes are coordinates)
        attrs = dict(provenance(block, int(noise_attrs["seed"])), study=study.name,
                     noise=block["noise"], dt=float(noise_attrs["dt"]))
        attrs.update(noise)
        attrs.update(study.fixed())
        if study.gap is not None:   # the second wall's words (its values: fixed or axes)
            attrs.update({k: v for k, v in _wall_attrs(1.0, 1.0).items()
                          if k not in ("gap", "eps_lower")})
        attrs.update(_law_attrs(study.laws()))
        return attrs
    attrs = dict(provenance(block, int(noise_attrs["seed"])), study=study.name,
                 zeta=study.zeta, eps=study.eps, amplitude=study.amplitude,
                 noise=block["noise"], dt=float(noise_attrs["dt"]))
    attrs.update(noise)
    attrs.update(_wall_attrs(study.gap, study.eps_lower))
    attrs.update(_law_attrs(study.laws()))
    return attrs


def _plane_attrs(study, noise_attrs):
    """A plane study's map attributes: ``axes`` (its two parameters, x first) and ``fixed``
    (JSON text of ``{parameter: value}`` of the others: the model's and, unless it is an
    axis, the noise's ``rms``); none for the default plane (its datasets are those they
    always were)."""
    if study.plane is None:
        return {}
    fixed = study.fixed()
    if "rms" not in study.plane and noise_attrs.get("noise_rms") is not None:
        fixed["rms"] = float(noise_attrs["noise_rms"])
    attrs = dict(axes=list(study.plane), fixed=json.dumps(fixed, sort_keys=True))
    if "rms" in study.plane:
        attrs["rms_axis"] = ("the noise record is generated at unit rms (noise_rms) and "
                             "scaled by each cell's rms: every cell on the same random numbers")
    return attrs


def _wall_attrs(gap, eps_lower):
    """The second wall's attributes of a two-wall dataset (none for one wall: its attributes
    are those it always had)."""
    if gap is None:
        return {}
    return dict(gap=float(gap), eps_lower=float(eps_lower), n_walls=2,
                walls="upper: x = delta (hit from below, eps); lower: x = delta - gap (hit "
                      "from above, eps_lower)")


def _law_attrs(laws):
    """The impact laws' attributes of a study's datasets whose walls do not follow Newton's
    law (``laws``: `Study.laws`; none under Newton's law: its attributes are those it
    always had)."""
    if not laws:
        return {}
    out = dict(impact_law="eps(u) = eps / (1 + u / speed_scale), u the approach speed")
    if laws.get("speed_scale", math.inf) != math.inf:       # (a law at the lower wall alone)
        out["speed_scale"] = float(laws["speed_scale"])
    if laws.get("speed_scale_lower") is not None:
        out["speed_scale_lower"] = float(laws["speed_scale_lower"])
    return out


def _record_attrs(block, t_end, n_samples, dt):
    """The statistical record: ``transient``, ``t_end`` (resolved) and ``record_length``."""
    end = (n_samples - 1) * dt if t_end is None else float(t_end)
    return dict(transient=float(block["transient"]), t_end=end,
                record_length=end - float(block["transient"]))


def _rebound_floor(block):
    """The study's rebound floor (schema default: ``stats.DEFAULT_REBOUND_FLOOR``)."""
    from vibroimpact.stats.collisions import DEFAULT_REBOUND_FLOOR

    return float(block.get("rebound_floor", DEFAULT_REBOUND_FLOOR))


def _tile_job(study, tile, grid, what, run_cell, to_dataset, out):
    """The skeleton of every ``simulate_*`` tile job.

    ``run_cell(cell)`` on each cell of tile ``tile`` of the study's ``grid`` (``"events"``,
    also the map's, or ``"spectra"``) with the progress in the log, then
    ``to_dataset(cells, results)`` written to ``out`` (its provenance collected then).
    """
    tile_cells = study.tile(tile, grid)
    progress = Progress(f"studies.{study.name} {what} tile {tile}", len(tile_cells),
                        events=True)
    results = []
    for cell in tile_cells:
        log.debug("cell %d: inv_beta=%g delta=%g", cell.index, cell.inv_beta, cell.delta)
        results.append(run_cell(cell))
        progress.cell_done(results[-1])
    io.write_dataset(to_dataset(tile_cells, results), out)


def events_tile(name, block, tile, noise_path, out):
    """Rule ``simulate_events``: impact statistics of the cells of one tile."""
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    study = Study.from_config(name, block)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    edges = datasets.bin_edges(block["bins"])

    def run_cell(cell):
        return cells.event_statistics(
            samples, dt, cells.study_model(study, cell), transient=float(block["transient"]),
            t_end=block.get("t_end"), bins=edges, n_batches=int(block["n_batches"]),
            motion_window=float(block["motion_window"]), motions=study.motions,
            rebound_floor=_rebound_floor(block))

    def to_dataset(tile_cells, results):
        attrs = dict(_study_attrs(study, block, noise_attrs),
                     **_record_attrs(block, block.get("t_end"), len(samples), dt),
                     n_batches=int(block["n_batches"]), bins=config_text(block["bins"]),
                     motion_window=float(block["motion_window"]),
                     rebound_floor=_rebound_floor(block))
        return datasets.events_tile(tile_cells, results, edges, attrs, motions=study.motions)

    _tile_job(study, tile, "events", "events", run_cell, to_dataset, out)


def map_tile(name, block, tile, noise_path, out):
    """Rule ``simulate_map``: probabilities of the (m/n) motions on the cells of one tile.

    Every cell runs from rest over the same noise record (common random numbers), so the
    differences between neighbouring cells are not sampling noise of different records.
    A study with a ``plane`` runs each cell at its two axes' values (`Study.parameters`);
    with the rms an axis, the record is the unit-rms one (the sweep expansion gives such a
    study a unit-rms noise entry) scaled by each cell's rms: the same random numbers in
    every cell (docs/datasets.md, "Maps over any two parameters").
    """
    import time

    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    study = Study.from_config(name, block)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    spec = block["map"]
    # the longest forcing period of the whole study: every tile fails alike, before simulating
    map_cap_steps(len(samples), dt, float(block["transient"]), int(spec["max_periods"]),
                  1.0 / study.inv_beta.max(), where=f"studies.{name}.map.max_periods")

    unit = None
    if "rms" in study.axis_names:       # the record at unit rms, scaled per cell
        unit = np.asarray(samples[:], dtype=float)

    def run_cell(cell):
        start = time.process_time()
        record = samples if unit is None else study.parameters(cell)["rms"] * unit
        result = cells.motion_map_cell(
            record, dt, cells.study_model(study, cell), transient=float(block["transient"]),
            motions=study.motions, window=float(block["motion_window"]),
            n_batches=int(block["n_batches"]), target_stderr=float(spec["target_stderr"]),
            min_time=float(spec["min_time"]), max_periods=int(spec["max_periods"]),
            min_switches=int(spec["min_switches"]))
        result["cpu_time"] = time.process_time() - start
        log.debug("cell %d: %.0f time units, %d collisions, %.3f s%s", cell.index,
                  result["simulated_time"], result["n_collisions"], result["cpu_time"],
                  "" if result["reached"] else ", target precision not reached")
        return result

    def to_dataset(tile_cells, results):
        attrs = dict(_study_attrs(study, block, noise_attrs), **_plane_attrs(study, noise_attrs),
                     motion_window=float(block["motion_window"]),
                     n_batches=int(block["n_batches"]),
                     **{k: spec[k] for k in ("target_stderr", "min_time", "max_periods",
                                             "min_switches")},
                     transient=float(block["transient"]))
        return datasets.map_tile(tile_cells, results, study.motions, attrs)

    _tile_job(study, tile, "events", "map", run_cell, to_dataset, out)


def spectra_tile(name, block, tile, noise_path, out):
    """Rule ``simulate_spectra``: Welch spectra of a(tau) for the cells of one tile."""
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    study = Study.from_config(name, block)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    spectra = block["spectra"]

    def run_cell(cell):
        return cells.spectra_statistics(
            samples, dt, cells.study_model(study, cell), transient=float(block["transient"]),
            t_end=spectra.get("t_end"), nperseg=int(spectra["nperseg"]),
            n_batches=None if block.get("n_batches") is None else int(block["n_batches"]))

    def to_dataset(tile_cells, results):
        attrs = dict(_study_attrs(study, block, noise_attrs),
                     **_record_attrs(block, spectra.get("t_end"), len(samples), dt),
                     nperseg=int(spectra["nperseg"]))
        return datasets.spectra_tile(tile_cells, results, attrs)

    _tile_job(study, tile, "spectra", "spectra", run_cell, to_dataset, out)


def trace(name, block, noise_path, out):
    """Rule ``simulate_trace``: a short sampled record from rest (Figs. 3, 10)."""
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    if block.get("plane") is not None:
        return _plane_trace(name, block, noise_path, out, cells)
    study = Study.from_config(name, block)
    samples, dt, noise_attrs = io.read_noise(noise_path)
    spec = block["trace"]
    inv_beta = float(spec.get("inv_beta", study.inv_beta[0]))
    model = cells.cell_model(dict(zeta=study.zeta, eps=study.eps, delta=float(spec["delta"]),
                                  amplitude=study.amplitude, inv_beta=inv_beta, **study.walls()))
    tr = cells.trace(samples, dt, model, t_end=float(spec["t_end"]))
    attrs = dict(_study_attrs(study, block, noise_attrs), delta=float(spec["delta"]),
                 beta_f=1.0 / inv_beta, t_end=float(spec["t_end"]))
    io.write_dataset(datasets.trace_dataset(tr, attrs), out)


def _plane_trace(name, block, noise_path, out, cells):
    """A plane study's trace: at ``trace.cell`` [x, y] of its plane, every other parameter
    fixed; with the rms an axis, the unit-rms record times the cell's rms (as its map)."""
    samples, dt, noise_attrs = io.read_noise(noise_path)
    spec = block["trace"]
    plane = list(block["plane"])
    p = dict(_plane_fixed(block), **{k: float(v) for k, v in zip(plane, spec["cell"])})
    scaled = {}
    if "rms" in p:
        # the record this trace ran on: the unit-rms record times the cell's rms
        rms = p.pop("rms")
        samples = samples * rms
        scaled = dict(noise_rms=float(noise_attrs["noise_rms"]) * rms,
                      noise_unit_rms=float(noise_attrs["noise_rms"]))
    if "gap" in p and p.get("eps_lower") is None:
        p["eps_lower"] = p["eps"]
    p.update(laws(block, f"studies.{name}"))
    tr = cells.trace(samples, dt, cells.cell_model(p), t_end=float(spec["t_end"]))
    beta_f = 1.0 / p.pop("inv_beta")
    fixed = _plane_fixed(block)
    if "rms" not in plane and noise_attrs.get("noise_rms") is not None:
        fixed["rms"] = float(noise_attrs["noise_rms"])
    noise = dict({k: noise_attrs[k] for k in noise_attrs if k.startswith("noise_")}, **scaled)
    attrs = dict(provenance(block, int(noise_attrs["seed"])), study=name, noise=block["noise"],
                 dt=float(noise_attrs["dt"]), **noise, **p, beta_f=beta_f,
                 t_end=float(spec["t_end"]), axes=plane, cell=[float(v) for v in spec["cell"]],
                 fixed=json.dumps(fixed, sort_keys=True))
    if "gap" in p:
        attrs.update({k: v for k, v in _wall_attrs(p["gap"], p["eps_lower"]).items()})
    attrs.update(_law_attrs(laws(block, f"studies.{name}")))
    io.write_dataset(datasets.trace_dataset(tr, attrs), out)


def _escape_attrs(name, block, noise):
    """Global attributes of the escape datasets: the study's system, the noise entry's
    spectrum (its rms is the levels' coordinate) and seed, the record."""
    spec = {f"noise_{k}": noise[k] for k in _NOISE_FIELDS
            if k != "rms" and noise.get(k) is not None}
    escape = block["escape"]
    if block.get("plane") is not None:      # a plane's cells: [x, y], the rest fixed
        fixed = _plane_fixed(block)
        return dict(provenance(dict(block, noise_entry=noise), int(noise["seed"])),
                    study=name, noise=block["noise"], dt=float(noise["dt"]), **spec,
                    **fixed, **_law_attrs(laws(block, f"studies.{name}")),
                    axes=list(block["plane"]),
                    fixed=json.dumps(fixed, sort_keys=True),
                    transient=float(block["transient"]),
                    record_length=float(escape["record_length"]),
                    motion_window=float(block["motion_window"]),
                    seeds="record k: SeedSequence(seed, spawn_key=(k,)), k = spawn_key")
    return dict(provenance(dict(block, noise_entry=noise), int(noise["seed"])), study=name,
                zeta=float(block["zeta"]), eps=float(block["eps"]),
                amplitude=float(block["amplitude"]), noise=block["noise"],
                dt=float(noise["dt"]), **spec, **_wall_attrs(*walls(block, f"studies.{name}")),
                **_law_attrs(laws(block, f"studies.{name}")),
                transient=float(block["transient"]),
                record_length=float(escape["record_length"]),
                motion_window=float(block["motion_window"]),
                seeds="record k: SeedSequence(seed, spawn_key=(k,)), k = spawn_key")


#: The model's parameters a plane study's escape cell is run with (its two axes from the
#: cell, the others fixed).
_ESCAPE_PARAMETERS = ("zeta", "eps", "amplitude", "inv_beta", "delta", "gap", "eps_lower")


def _plane_fixed(block):
    """``{parameter: value}`` of a plane study's fixed model parameters (not its axes; the
    second wall's only with one; an eps_lower not given is not fixed: it follows eps)."""
    plane = block["plane"]
    return {k: float(block[k]) for k in _ESCAPE_PARAMETERS
            if k not in plane and block.get(k) is not None}


def escape_cells(block):
    """``[{zeta, eps, amplitude, inv_beta, delta[, gap, eps_lower][, speed_scale...]}]``:
    the model of each escape cell of a study, as `cells.cell_model` reads it: ``[inv_beta,
    delta]``, or in a plane study ``[x, y]`` in the plane's coordinates with every other
    parameter fixed."""
    plane = block.get("plane") or ("inv_beta", "delta")
    fixed = _plane_fixed(block) if block.get("plane") is not None else {
        k: float(block[k]) for k in ("zeta", "eps", "amplitude")}
    if block.get("plane") is None:
        gap, eps_lower = walls(block, f"studies.{block.get('name', '')}".rstrip("."))
        if gap is not None:
            fixed.update(gap=gap, eps_lower=eps_lower)
    fixed.update(laws(block, f"studies.{block.get('name', '')}".rstrip(".")))
    out = []
    for cell in block["escape"]["cells"]:
        p = dict(fixed, **{k: float(v) for k, v in zip(plane, cell)})
        if "gap" in p and p.get("eps_lower") is None:
            p["eps_lower"] = p["eps"]
        out.append(p)
    return out


def escape_level(name, block, noise, index, out):
    """Rule ``simulate_escape``: the residence times of every escape cell of study ``name``
    on the record of noise level ``index`` (``block["escape"]["rms"][index]``).

    The record is generated here (`vibroimpact.noise.generate_array`, no file): the study's
    noise entry ``noise`` (spectrum, ``dt``, seed) at the level's rms, seeded by
    `study.escape_seed` (seed, index); every cell runs from rest on it.
    """
    from vibroimpact.noise import generate_array
    from vibroimpact.pipeline import cells    # the simulator: only the jobs that simulate load it

    escape = block["escape"]
    rms = float(escape["rms"][index])
    spec = noise_spec(dict(noise, rms=rms))
    transient, length = float(block["transient"]), float(escape["record_length"])
    n = escape_samples(transient, length, spec.dt)
    log.info("level %d: rms %g, %d samples of %s", index, rms, n, spec)
    samples = generate_array(spec, n, escape_seed(noise["seed"], index))
    motions = [tuple(int(k) for k in m) for m in block["motions"]]
    progress = Progress(f"studies.{name} escape level {index}", len(escape["cells"]),
                        events=True)
    results = []
    for p in escape_cells(block):
        results.append(cells.escape_cell(
            samples, spec.dt, cells.cell_model(p), transient=transient, record_length=length,
            motions=motions, window=float(block["motion_window"])))
        progress.cell_done(results[-1])
    io.write_dataset(datasets.escape_part(index, rms, escape["cells"], results, motions,
                                          _escape_attrs(name, block, noise),
                                          axes=block.get("plane") or ("inv_beta", "delta")),
                     out)


def aggregate_escape(name, block, noise, parts, out):
    """Rule ``aggregate_escape``: the escape dataset of study ``name`` from its levels, with
    the fit of ln(residence time) against 1 / rms^2."""
    escape = block["escape"]
    ds = datasets.aggregate_escape([io.load_dataset(p) for p in parts],
                                   _escape_attrs(name, block, noise),
                                   min_stretches=int(escape["min_stretches"]),
                                   fit_max_rms=escape.get("fit_max_rms"))
    io.write_dataset(ds, out)


def aggregate(name, block, kind, tiles, out, noise_path=None):
    """Rules ``aggregate_events`` / ``aggregate_spectra`` / ``aggregate_map``: a study's
    dataset. The grid's axes are the tiles' own (`datasets.tile_axes`: the values their
    cells ran with), not the config's grid expanded once more."""
    # the grid's size (counted, not expanded): a missing tile is an error
    if block.get("plane") is not None:      # a plane's map: its two axes' grids
        x, y = block["plane"]
        n_cells = grid_size(block[x]) * grid_size(block[y])
    else:
        rows = grid_size(block["inv_beta"]) if float(block["amplitude"]) != 0.0 else 1
        n_cells = rows * grid_size((block["spectra"] if kind == "spectra" else block)["delta"])
    parts = [io.load_dataset(p) for p in tiles]
    attrs = dict(parts[0].attrs)
    attrs.update(provenance(block, attrs.get("seed")))
    if kind == "events":
        if float(attrs.get("amplitude", 0.0)) == 0.0:
            # the wall-free response's std's: fig09 draws Rice's large-play asymptotes
            sigma_x, sigma_v = stats.linear_response_std(
                io.noise_spec(attrs).psd_piecewise_linear, float(block["zeta"]))
            attrs.update(linear_sigma_x=sigma_x, linear_sigma_v=sigma_v)
        ds = datasets.aggregate_events(parts, None, attrs, n_cells=n_cells)
    elif kind == "map":
        ds = datasets.aggregate_map(parts, None, attrs, n_cells=n_cells)
    else:
        spec = io.noise_spec(io.read_noise_attrs(noise_path))
        ds = datasets.aggregate_spectra(parts, None, spec, attrs,
                                        input_correlation=io.read_input_correlation(noise_path),
                                        zeta=float(block["zeta"]), n_cells=n_cells)
    io.write_dataset(ds, out)


def figure(target, inputs, out_png, options):
    """Rule ``draw_figure``: the figure's function (its ``draw`` in the figure table) of
    ``*datasets, **options``, saved to ``out_png``.

    ``target`` is ``fig07`` or ``fig13-1`` (`vibroimpact.pipeline.figures`); ``options``
    come from the owner's config entry through the figure table (`figure_options`).
    """
    # here, not at the top: a code digest follows what a module's top level imports, and
    # only the figure jobs reach the drawing functions
    from vibroimpact import plotting
    from vibroimpact.pipeline.figures import drawing_function, figure_variant

    draw = drawing_function(figure_variant(target)[0])
    log.info("drawing %s from %s with %s", target, inputs, options)
    with plotting.style():
        plotting.save(draw(*[io.load_dataset(p) for p in inputs], **options), out_png)


def orbit_tile(entry, tile, out, threads=None, solver=None):
    """Rules ``solve_orbit_tile`` and ``solve_clearance_orbit_tile``: existence and stability
    of the periodic motions of an ``orbits`` entry on some rows of its plane (the paper's
    (1/beta_f, delta) unless it names one; rows strided over the tiles, `orbit_rows`).

    One wall under Newton's law on the paper's plane is Fig. 16's closed form
    (`vibroimpact.orbits.orbit_map`, its rows in ``threads`` numba threads); any other plane,
    a second wall or an impact law (`study.shooting`) is ``solver(x_name, x_values, y_name,
    y_values, fixed, types, progress=...)``: by default `vibroimpact.orbits.plane.orbit_plane`
    (the one-wall closed form); the shooting rule's script gives
    `vibroimpact.attractors.plane.orbit_plane` (any wall layout, any law: the shooting
    solver, seeded by the simulator). The script passes it so that the closed form's tiles'
    code reaches no simulator (their code digest, `pipeline.provenance.code_closure`).
    """
    import numba

    if threads is not None:
        numba.set_num_threads(int(threads))
    if entry.get("plane") or shooting(entry):
        if solver is None:
            if shooting(entry):
                raise ValueError("an orbits entry with a second wall or an impact law is "
                                 "the shooting solver's: rule solve_clearance_orbit_tile "
                                 "gives it (vibroimpact.attractors.plane.orbit_plane)")
            from vibroimpact.orbits.plane import orbit_plane as solver
        io.write_dataset(_plane_tile(entry, tile, solver), out)
        return
    from vibroimpact.orbits import orbit_map

    rows, n_tiles = orbit_rows(entry)
    rows, deltas = rows[tile::n_tiles], grid_values(entry["delta"])
    progress = Progress(f"orbit tile {tile}", rows.size * deltas.size)
    result = orbit_map(rows, deltas, types=[tuple(t) for t in entry["types"]],
                       zeta=float(entry["zeta"]), eps=float(entry["eps"]),
                       progress=progress.advance)
    attrs = dict(provenance(entry), zeta=float(entry["zeta"]), eps=float(entry["eps"]),
                 amplitude=1.0)
    io.write_dataset(datasets.orbit_map_dataset(result, attrs), out)


#: The parameters of an ``orbits`` entry with a plane that its map holds fixed when given.
ORBIT_PLANE_PARAMETERS = ("zeta", "eps", "eps_lower", "delta", "gap", "amplitude", "inv_beta")


def orbit_plane_fixed(entry):
    """``{parameter: value}`` an ``orbits`` entry holds fixed off its plane (the paper's
    (1/beta_f, delta) without one), its amplitude 1 when not given."""
    plane = entry.get("plane") or ("inv_beta", "delta")
    fixed = {k: float(entry[k]) for k in ORBIT_PLANE_PARAMETERS
             if k not in plane and entry.get(k) is not None}
    if "amplitude" not in plane:
        fixed.setdefault("amplitude", 1.0)
    return fixed


def _plane_tile(entry, tile, orbit_plane):
    """One tile of an ``orbits`` entry on its plane (the paper's without one): `orbit_plane`
    (`orbit_tile`'s ``solver``) over its share of the tiled axis (`orbit_tiled_axis`, values
    strided over tiles) by the whole other axis."""
    x_name, y_name = entry.get("plane") or ("inv_beta", "delta")
    rows, n_tiles = orbit_rows(entry)
    values = {k: grid_values(entry[k]) for k in (x_name, y_name)}
    values[orbit_tiled_axis(entry)] = rows[tile::n_tiles]
    progress = Progress(f"orbit tile {tile}", values[x_name].size * values[y_name].size)
    impact_laws = laws(entry, "orbits")         # none under Newton's law
    ds = orbit_plane(x_name, values[x_name], y_name, values[y_name], orbit_plane_fixed(entry),
                     types=[tuple(int(k) for k in t) for t in entry["types"]],
                     progress=progress.advance, **impact_laws)
    ds.attrs.update(provenance(entry), reason_codes="0 stable, 1 no solution, 2 inadmissible, "
                                                    "3 unstable")
    if not entry.get("plane"):      # the paper's plane: named by no attribute, as Fig. 16's
        del ds.attrs["axes"], ds.attrs["fixed"]
    if entry.get("gap") is not None and "gap" not in (x_name, y_name):
        ds.attrs.update(_wall_attrs(*walls(entry, "orbits")))
    ds.attrs.update(_law_attrs(impact_laws))
    return ds


def aggregate_orbits(entry, tiles, out):
    """Rule ``aggregate_orbits``: the orbit map of one entry from its tiles."""
    ds = datasets.concat_orbit_tiles([io.load_dataset(p) for p in tiles],
                                     dim=orbit_tiled_axis(entry))
    ds.attrs.update(provenance(entry))
    io.write_dataset(ds, out)


#: Accuracy asked of every point of a boundary curve (its distance to the exact curve): the
#: issue's 1e-9 in delta; `domain_boundaries` defaults to 1e-10, which a fold next to a doubled
#: orbit can miss by round-off alone (4.8e-10 measured for (2/2) at zeta 0.1, eps 0.8).
BOUNDARY_TOL = 1e-9


def boundaries(entry, orbits_path, out, threads=None):
    """Rule ``trace_boundaries``: the exact edges of every type's stable domain over the box
    of the entry's map (``orbits_path``, whose pixel edges seed them), on its plane (the
    paper's (1/beta_f, delta) unless it names one: `orbits.boundaries.plane_boundaries`,
    over (1/beta_f, delta) `domain_boundaries` bit for bit). A two-wall entry, one under an
    impact law other than Newton's, or one whose eps reaches 0, is written untraced
    (``traced = 0``, ``not_traced`` says why)."""
    fixed = orbit_plane_fixed(entry)
    axes = tuple(entry.get("plane") or ("inv_beta", "delta"))
    if entry.get("plane"):
        attrs = dict(provenance(entry), **fixed, axes=list(axes),
                     fixed=json.dumps(fixed, sort_keys=True), traced=1)
    else:       # the paper's plane: its attributes are those they always were
        attrs = dict(provenance(entry), zeta=fixed["zeta"], eps=fixed["eps"], traced=1)
    seeds = io.load_dataset(orbits_path)
    box = {k: (float(seeds[k].min()), float(seeds[k].max())) for k in axes}
    impact_laws = laws(entry, "orbits")         # none under Newton's law
    why = None
    if entry.get("gap") is not None or "gap" in axes:
        # the boundary tracer continues the closed-form (m/n) solutions: one wall only
        why = "two walls: the edges are the map's cell edges"
        if not entry.get("plane"):
            attrs.update(_wall_attrs(*walls(entry, "orbits")))
    elif impact_laws:
        # the tracer continues the closed-form solutions of Newton's law
        why = "an impact law other than Newton's: the edges are the map's cell edges"
        attrs.update(_law_attrs(impact_laws))
    elif fixed.get("eps", 1.0) == 0.0 or ("eps" in axes and box["eps"][0] <= 0.0):
        # every impact ends at rest on the wall: a flight's maximum is its start, and no
        # boundary condition is regular there (the tracer refuses eps = 0)
        why = "eps = 0 in the plane: the edges are the map's cell edges"
    if why is not None:
        attrs.update(traced=0, not_traced=why)
        io.write_dataset(datasets.boundaries_dataset({}, attrs, axes), out)
        return
    import numba

    from vibroimpact.orbits.boundaries import plane_boundaries

    if threads is not None:
        numba.set_num_threads(int(threads))
    curves = {}
    types = [tuple(int(k) for k in t) for t in entry["types"]]
    progress = Progress("boundaries", len(types), unit="types")
    for m, n in types:
        curves[(m, n)] = plane_boundaries(m, n, axes[0], box[axes[0]], axes[1], box[axes[1]],
                                          fixed, seed_map=seeds, tol=BOUNDARY_TOL)
        log.info("(%d/%d): %d curves", m, n, len(curves[(m, n)]))
        lost = sum(c.ends.count("lost") for c in curves[(m, n)])
        if lost:
            log.warning("(%d/%d): %d curve ends lost: the edge of the stable domain has a gap "
                        "there (the dataset's `ends` says which curves)", m, n, lost)
        progress.advance()
    io.write_dataset(datasets.boundaries_dataset(curves, attrs, axes), out)


def _attractor_attrs(entry, study=None):
    """An attractor tile's attributes: the starts and their box; an ``orbits`` entry's
    oscillator (a study's plane carries its own fixed values) or the study's name."""
    block = entry["attractors"]
    gap, vel = (tuple(float(v) for v in block[k]) for k in ("gap", "velocity"))
    starts = dict(n_starts=int(block["n_starts"]), max_time=float(block["max_time"]),
                  seed=int(block["seed"]), start_gap=list(gap), velocity=list(vel))
    if study is None:
        return dict(zeta=float(entry["zeta"]), eps=float(entry["eps"]), **starts,
                    box=f"forcing phase in [0, 2 pi), x0 = delta - g with g in [{gap[0]:g}, "
                        f"{gap[1]:g}], v0 in [{vel[0]:g}, {vel[1]:g}]")
    return dict(study=study, **starts,
                box=f"forcing phase in [0, 2 pi), x0 = delta - s (s: distance below the "
                    f"wall at delta) with s in [{gap[0]:g}, {gap[1]:g}], v0 in "
                    f"[{vel[0]:g}, {vel[1]:g}]")


def attractor_tile(entry, tile, out, threads=None, study=None):
    """Rules ``solve_attractor_tile`` (an ``orbits`` entry's attractors, on the paper's
    (1/beta_f, delta) plane) and ``solve_plane_attractor_tile`` (study ``study``'s attractors
    on its plane): basins and Lyapunov exponents under the harmonic force alone on some values
    of the plane's first axis (strided over the tiles, as the orbit tiles), every value of
    its second (`vibroimpact.attractors.plane.attractor_plane`; on the paper's plane that is
    one `vibroimpact.attractor_map` call, bit for bit).

    ``threads``: numba threads of the starts (the rule's ``threads``).
    """
    import numba

    from vibroimpact.attractors.plane import attractor_plane

    if threads is not None:
        numba.set_num_threads(int(threads))
    block = entry["attractors"]
    if study is None:       # an orbits entry: the paper's plane, its own grid
        rows, n_tiles = attractor_rows(entry)
        (x, y), ys = ("inv_beta", "delta"), grid_values(block["delta"])
        fixed, types = dict(zeta=float(entry["zeta"]), eps=float(entry["eps"])), entry["types"]
        what = f"attractor tile {tile}"
    else:
        plane = Study.from_config(study, entry)
        rows, n_tiles = plane_attractor_rows(entry)
        (x, y), ys = plane.plane, plane.axes[plane.plane[1]]
        fixed, types = plane.fixed(), block["types"]
        what = f"studies.{study} attractor tile {tile}"
    attrs = _attractor_attrs(entry, study)
    rows = rows[tile::n_tiles]
    progress = Progress(what, rows.size * ys.size)
    types = [tuple(int(k) for k in t) for t in types]
    result = attractor_plane(x, rows, y, ys, fixed, types=types, n_starts=attrs["n_starts"],
                             gap=tuple(attrs["start_gap"]), velocity=tuple(attrs["velocity"]),
                             max_time=attrs["max_time"], seed=attrs["seed"],
                             progress=progress.advance)
    if study is None:       # the paper's plane: its datasets are those they always were
        del result["axes"], result["fixed"]
    io.write_dataset(datasets.attractor_tile_dataset(result, dict(provenance(entry), **attrs)),
                     out)


def aggregate_attractors(entry, tiles, out_basins, out_lyapunov, motions=None):
    """Rule ``aggregate_attractors``: the basins and Lyapunov datasets of one entry (with
    two walls, the basins of ``motions``, the study's own)."""
    joined = datasets.concat_attractor_tiles([io.load_dataset(p) for p in tiles])
    joined.attrs.update(provenance(entry))
    io.write_dataset(datasets.basins_dataset(joined, motions), out_basins)
    io.write_dataset(datasets.lyapunov_dataset(joined), out_lyapunov)


def aggregate_plane_attractors(entry, tiles, out_basins, out_lyapunov):
    """Rule ``aggregate_plane_attractors``: a plane study's basins and Lyapunov datasets;
    with two walls the basins are those of the study's motions."""
    two_walls = [tuple(int(v) for v in m) for m in entry.get("motions", ()) if len(m) == 3]
    aggregate_attractors(entry, tiles, out_basins, out_lyapunov, two_walls or None)


def map_orbits(map_path, orbits_path, out):
    """Rule ``solve_map_orbits``: the periodic orbits of an orbits entry solved at the cells
    of a study's map (`vibroimpact.orbits.cells.orbits_at_cells`): what finding 8, the
    predictors of P and Fig. 15 against Fig. 16 compare P with, cell for cell."""
    from vibroimpact._plane import dataset_axes
    from vibroimpact.orbits.cells import orbits_at_cells

    motion_map = io.load_dataset(map_path)
    axes = dataset_axes(motion_map)
    progress = Progress("orbits at the map's cells",
                        motion_map.sizes[axes[0]] * motion_map.sizes[axes[1]])
    ds = orbits_at_cells(motion_map, io.load_dataset(orbits_path), progress=progress.advance)
    if ds is None:
        raise ValueError(f"no motion of the map {map_path} is a type of the orbit map "
                         f"{orbits_path}")
    ds.attrs.update(provenance({"inputs": {"map": str(map_path), "orbits": str(orbits_path)}}))
    io.write_dataset(ds, out)


def map_predictors(map_path, out, orbits_path=None, basins_path=None, lyapunov_path=None):
    """Rule ``map_predictors``: the rank correlations of each candidate predictor with each
    motion's P over a study's map (`vibroimpact.reports.predictors`), computed once for the
    reports that show the map (the study's, a ``report_with`` study's, the orbits entry's).
    ``orbits_path``: the orbits at the map's own cells (rule ``solve_map_orbits``). An empty
    or None path: that dataset is not provided (its rows say why)."""
    from vibroimpact.reports import predictors

    def read(path):
        return io.load_dataset(path) if path else None

    motion_map = read(map_path)
    found = predictors.predictor_correlations(motion_map, read(orbits_path),
                                              read(basins_path), read(lyapunov_path))
    ds = predictors.correlations_dataset(found)
    block = {"seed": predictors.SEED, "n_resamples": predictors.N_RESAMPLES,
             "inputs": {"map": str(map_path), "orbits": str(orbits_path or ""),
                        "basins": str(basins_path or ""), "lyapunov": str(lyapunov_path or "")}}
    ds.attrs.update(provenance(block))
    io.write_dataset(ds, out)
