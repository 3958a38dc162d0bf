"""What each job asks of a scheduler: its memory (MB) and run time (minutes), from its work.

One function, :func:`job_request`, for every rule of the workflow: the rules' ``resources:``
call it (``workflow/rules/common.smk``, `job_mem_mb` and `job_runtime`), and so does the
check of the requests against a build's measured use (``benchmarks/job_requests.py``,
``tests/test_job_requests.py``).
The work of a job (its cells, their sample steps, its record, its map's cells) is read from
the config and the resolved studies as the plan reads it, and costed with the plan's own model
(`vibroimpact.pipeline.config.costs`): the CPU seconds of the plan, and memory as
`costs.BASE_MEM_MB` plus what grows with the work. A job retried after a failure
(``retries`` in workflow/profiles/slurm) asks ``attempt`` times as much of both.
"""
from __future__ import annotations

from dataclasses import dataclass
import math

from vibroimpact.pipeline.config import costs
from vibroimpact.pipeline.study import (attractor_rows, grid_size, grid_values,
                                        orbit_plane_cells, orbit_rows, plane_attractor_rows)

__all__ = ["Request", "job_request", "map_cells", "RULES"]


@dataclass(frozen=True)
class Request:
    """A job's request: ``mem_mb`` and ``runtime`` (minutes), and the ``cpu_s`` it was costed
    at (the plan's model, start-up included)."""

    mem_mb: int
    runtime: int
    cpu_s: float


def job_request(rule, config, studies, wildcards, attempt=1):
    """The :class:`Request` of one job of ``rule`` (its name in the workflow) with
    ``wildcards`` (a mapping), of the checked ``config`` whose studies are resolved in
    ``studies`` (``{name: Study}``, `vibroimpact.pipeline.config.Plan.studies`), at its
    ``attempt`` (1 the first run)."""
    cpu_s, mem_mb = _WORK[rule](config, studies, dict(wildcards))
    attempt = max(1, int(attempt))
    return Request(mem_mb=math.ceil(mem_mb) * attempt,
                   runtime=costs.runtime_min(cpu_s) * attempt,
                   cpu_s=float(cpu_s))


def map_cells(studies, name):
    """Cells of study ``name``'s map (its events grid, the map's too)."""
    return len(studies[name].cells("events"))


# --- the work of each rule: (CPU seconds, memory MB) -------------------------------------------


def _study_noise(config, name):
    return config["noises"][config["studies"][name]["noise"]]


def _simulate_mem(config, studies, name):
    scaled = "rms" in studies[name].axis_names      # the unit record and a cell's, at once
    return costs.simulate_mem_mb(int(_study_noise(config, name)["n_samples"]),
                                 records=2 if scaled else 1)


def _generate_noise(config, studies, w):
    n = int(config["noises"][w["noise"]]["n_samples"])
    return costs.noise_cpu_s(n), costs.NOISE_MEM_MB


def _simulate(kind):
    def work(config, studies, w):
        name = w["study"]
        entry, study = config["studies"][name], studies[name]
        grid = "events" if kind == "map" else kind
        cells = len(study.tile(int(w["tile"]), grid))
        # a map cell costed to its cap at the longest forcing period: the most it runs
        steps = costs.study_steps(kind, entry, _study_noise(config, name),
                                  float(study.inv_beta.max()) if kind == "map" else None)
        cpu = costs.simulate_cpu_s(cells, steps, audit=kind == "events")
        if kind == "spectra":
            cpu += cells * costs.SPECTRA_CELL_S
        mem = _simulate_mem(config, studies, name)
        if kind == "map":
            cpu += cells * costs.MAP_CELL_S
            mem += costs.read_mem_mb(cells)      # the tile's cells, held until written
        return costs.JOB_START_S + cpu, mem
    return work


def _simulate_trace(config, studies, w):
    name = w["study"]
    steps = float(config["studies"][name]["trace"]["t_end"]) / float(
        _study_noise(config, name)["dt"])
    return (costs.JOB_START_S + costs.simulate_cpu_s(1, steps),
            _simulate_mem(config, studies, name))


def _simulate_escape(config, studies, w):
    entry = config["studies"][w["study"]]
    dt = float(_study_noise(config, w["study"])["dt"])
    return (costs.JOB_START_S + costs.escape_cpu_s(entry, dt, levels=1),
            costs.simulate_mem_mb(costs.escape_record_samples(entry, dt)))


def _orbit_tile_cells(entry):
    """Cells of the largest tile of an ``orbits`` entry (``tile_rows`` rows of its tiled
    axis, by every value of the other)."""
    rows, _ = orbit_rows(entry)
    per_row = orbit_plane_cells(entry) // max(rows.size, 1)
    return min(int(entry["tile_rows"]), rows.size) * per_row


def _solve_orbit_tile(config, studies, w):
    entry = config["orbits"][w["orbits"]]
    cells = _orbit_tile_cells(entry)
    if entry.get("plane"):
        cpu = costs.orbit_plane_cpu_s(entry, cells)
    else:
        cpu = costs.orbit_cpu_s(cells, len(entry["types"]))
    return (costs.JOB_START_S + cpu,
            costs.BASE_MEM_MB + costs.orbit_mem_mb(cells, len(entry["types"])))


def _solve_clearance_orbit_tile(config, studies, w):
    entry = config["orbits"][w["orbits"]]
    cells = _orbit_tile_cells(entry)
    return (costs.JOB_START_S + costs.SHOOTING_CELL_S * cells,
            costs.BASE_MEM_MB + costs.orbit_mem_mb(cells, len(entry["types"])))


def _attractor_tile(rows, n_tiles, tile, columns, n_starts):
    cells = len(rows[int(tile)::n_tiles]) * columns
    return (costs.JOB_START_S + costs.attractor_cpu_s(cells, n_starts),
            costs.BASE_MEM_MB + costs.attractor_mem_mb(cells, n_starts))


def _solve_attractor_tile(config, studies, w):
    entry = config["orbits"][w["orbits"]]
    rows, n_tiles = attractor_rows(entry)
    return _attractor_tile(rows, n_tiles, w["tile"], grid_size(entry["attractors"]["delta"]),
                           int(entry["attractors"]["n_starts"]))


def _solve_plane_attractor_tile(config, studies, w):
    entry = config["studies"][w["study"]]
    rows, n_tiles = plane_attractor_rows(entry)
    columns = len(grid_values(entry[entry["plane"][1]]))
    return _attractor_tile(rows, n_tiles, w["tile"], columns,
                           int(entry["attractors"]["n_starts"]))


def _trace_boundaries(config, studies, w):
    entry = config["orbits"][w["orbits"]]
    return (costs.JOB_START_S + costs.boundaries_cpu_s(len(entry["types"])),
            costs.BASE_MEM_MB + costs.orbit_mem_mb(orbit_plane_cells(entry),
                                                   len(entry["types"])))


def _map_job(cpu_of, mem_of):
    def work(config, studies, w):
        name = w["study"]
        cells, motions = map_cells(studies, name), len(config["studies"][name]["motions"])
        return costs.JOB_START_S + cpu_of(cells, motions), costs.BASE_MEM_MB + mem_of(cells)
    return work


def _measure_work_precision(config, studies, w):
    block = config["validation"]["work_precision"]
    return costs.JOB_START_S + costs.work_precision_cpu_s(block), costs.BASE_MEM_MB


def _sample_stress_families(config, studies, w):
    block = config["validation"]["stress"]
    return costs.JOB_START_S + costs.stress_cpu_s(block), costs.BASE_MEM_MB


def _read_mem(config, studies, w):
    """Memory (MB, besides `costs.BASE_MEM_MB`) of the grids a light job (an aggregation, a
    figure, a report) reads: its study's map (and its ``report_with``'s), or an orbits
    entry's orbit map and the largest of its attractor map and the maps drawn over it."""
    if "study" in w:
        names = [w["study"], *config["studies"][w["study"]].get("report_with", [])]
        return costs.read_mem_mb(max(map_cells(studies, n) for n in names))
    if "orbits" in w:
        return _orbits_read_mem(config, studies, w["orbits"])
    if "owner" in w:                # draw_figure: a study's or "orbits/<name>"
        owner = w["owner"]
        if owner.startswith("orbits/"):
            return _orbits_read_mem(config, studies, owner.split("/", 1)[1])
        return costs.read_mem_mb(map_cells(studies, owner))
    return 0.0


def _orbits_read_mem(config, studies, name):
    entry = config["orbits"][name]
    cells = [0]
    if entry.get("attractors"):
        rows, _ = attractor_rows(entry)
        cells.append(rows.size * grid_size(entry["attractors"]["delta"]))
    for study, s_entry in config["studies"].items():
        for item in s_entry.get("figures", []):
            if isinstance(item, dict) and item.get("orbits") == name:
                cells.append(map_cells(studies, study))
    # the orbit map itself (Fig. 16's grid, the largest an orbits entry has), its solutions
    return (costs.read_mem_mb(max(cells))
            + costs.orbit_mem_mb(orbit_plane_cells(entry), len(entry["types"])))


def _light(cpu_s):
    def work(config, studies, w):
        return cpu_s, costs.BASE_MEM_MB + _read_mem(config, studies, w)
    return work


_WORK = {
    "generate_noise": _generate_noise,
    "simulate_events": _simulate("events"),
    "simulate_spectra": _simulate("spectra"),
    "simulate_map": _simulate("map"),
    "simulate_trace": _simulate_trace,
    "simulate_escape": _simulate_escape,
    "solve_orbit_tile": _solve_orbit_tile,
    "solve_clearance_orbit_tile": _solve_clearance_orbit_tile,
    "solve_attractor_tile": _solve_attractor_tile,
    "solve_plane_attractor_tile": _solve_plane_attractor_tile,
    "trace_boundaries": _trace_boundaries,
    "solve_map_orbits": _map_job(costs.map_orbits_cpu_s, costs.read_mem_mb),
    "map_predictors": _map_job(costs.predictors_cpu_s, costs.predictors_mem_mb),
    "measure_work_precision": _measure_work_precision,
    "sample_stress_families": _sample_stress_families,
    "aggregate_events": _light(costs.aggregate_s("aggregate_events")),
    "aggregate_spectra": _light(costs.aggregate_s("aggregate_spectra")),
    "aggregate_map": _light(costs.aggregate_s("aggregate_map")),
    "aggregate_escape": _light(costs.aggregate_s("aggregate_escape")),
    "aggregate_orbits": _light(costs.aggregate_s("aggregate_orbits")),
    "aggregate_attractors": _light(costs.aggregate_s("aggregate_attractors")),
    "aggregate_plane_attractors": _light(costs.aggregate_s("aggregate_plane_attractors")),
    "draw_figure": _light(costs.FIGURE_S + costs.JOB_START_S),
    "draw_validation_figure": _light(costs.VALIDATION_FIGURE_S + costs.JOB_START_S),
    "draw_sweep": _light(costs.FIGURE_S + costs.JOB_START_S),
    "copy_paper_figure": _light(costs.JOB_START_S),
    "study_report": _light(costs.REPORT_S + costs.MAP_REPORT_S + costs.JOB_START_S),
    "orbits_report": _light(costs.REPORT_S + costs.MAP_REPORT_S + costs.JOB_START_S),
    "validation_report": _light(costs.REPORT_S + costs.JOB_START_S),
    "job_costs": _light(costs.JOB_START_S),
}
#: Every rule :func:`job_request` costs (the workflow's rules: tests/test_job_requests.py).
RULES = tuple(_WORK)
