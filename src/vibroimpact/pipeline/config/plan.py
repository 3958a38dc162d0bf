"""The plan of a build: cells, jobs, output bytes and CPU time per config entry.

:func:`make_plan` costs every job that ``rule all`` runs (its targets and every file they
need, `vibroimpact.pipeline.targets.needed_files`: the jobs a dry run on a fresh copy
schedules) with the one cost model
(`vibroimpact.pipeline.config.costs`) before anything runs; :meth:`Plan.format` is what
``python -m vibroimpact plan`` prints and :meth:`Plan.refuse_beyond_limits` refuses a build
beyond the config's ``limits``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
import shutil

from vibroimpact.pipeline import figures, targets
from vibroimpact.pipeline.config import costs
from vibroimpact.pipeline.config.costs import (COMPILE_S, FIGURE_BYTES, FIGURE_JOB_START_S,
                                               FIGURE_S, FILE_OVERHEAD, JOB_START_S,
                                               MAP_REPORT_S, REPORT_BYTES, REPORT_S,
                                               VALIDATION_FIGURE_S, VALIDATION_RULES)
from vibroimpact.pipeline.config.messages import ConfigError, _num
from vibroimpact.pipeline.study import (Study, attractor_rows, grid_size, orbit_plane_cells,
                                        orbit_rows, plane_attractor_rows, shooting)

__all__ = ["Plan", "Row", "make_plan", "built_entries", "WHOLE_MACHINE_RULES"]

#: The kinds of job that hold every core while they run (their cost is wall time).
WHOLE_MACHINE_RULES = ("measure_work_precision", "sample_stress_families")


@dataclass
class Row:
    """One line of the plan: a config entry and what building it costs."""

    key: str
    detail: str
    cells: int = 0
    orbit_cells: int = 0
    jobs: int = 0
    bytes: float = 0.0
    cpu_s: float = 0.0
    #: ``{kind of job: [jobs, CPU seconds]}``, the kind named as its benchmark files' folder
    #: (``results/benchmarks/<kind>/``; the three report rules are ``report``)
    rules: dict = field(default_factory=dict)


@dataclass
class Plan:
    """What a build will make, before anything runs (``str()`` is the printed plan)."""

    rows: list = field(default_factory=list)
    limits: dict = field(default_factory=dict)
    free_bytes: float | None = None
    results: str = "results"
    drawn: dict = field(default_factory=dict)    # built_entries(...)[0]: what `rule all` draws
    #: every study of the config resolved once (`pipeline.study.Study`, its grids expanded
    #: by the checks): the workflow's rules read these (common.smk, ``STUDIES``)
    studies: dict = field(default_factory=dict, repr=False)

    @property
    def cells(self):
        return sum(r.cells for r in self.rows)

    @property
    def orbit_cells(self):
        return sum(r.orbit_cells for r in self.rows)

    @property
    def jobs(self):
        return sum(r.jobs for r in self.rows)

    @property
    def bytes(self):
        return sum(r.bytes for r in self.rows)

    @property
    def cpu_s(self):
        return sum(r.cpu_s for r in self.rows)

    def rule_costs(self, cold_cache=False):
        """``{kind of job: (jobs, CPU seconds)}`` over every entry, the kind named as its
        benchmark files' folder (``results/benchmarks/<kind>/``): what
        ``benchmarks/job_costs.py --plan`` compares with a build's benchmark files. The jobs
        and seconds sum to the plan's. ``cold_cache``: plus numba's compilation in the
        jobs (`costs.COMPILE_S`), as in a build whose installation compiled nothing."""
        out = {}
        for row in self.rows:
            for rule, (jobs, cpu) in row.rules.items():
                n, c = out.get(rule, (0, 0.0))
                out[rule] = (n + jobs, c + cpu)
        if cold_cache:
            for rule, cpu in COMPILE_S.items():
                if rule in out:
                    out[rule] = (out[rule][0], out[rule][1] + cpu)
        return out

    def summary(self, cores=2):
        return (f"{_n(self.cells, 'simulation cell')}, {_n(self.orbit_cells, 'orbit cell')}, "
                f"{_n(self.jobs, 'job')} (Snakemake counts {self.jobs + 1}, with its target "
                f"`all`), ~{_bytes(self.bytes)} of outputs, ~{_time(self.cpu_s)} of CPU "
                f"(~{_time(self.cpu_s / max(cores, 1))} on {_n(cores, 'core')})")

    def format(self, cores=2):
        lines = ["vibroimpact plan (every job of `rule all` and of what it needs, whether or "
                 "not already built):"]
        width = max([len(r.key) for r in self.rows] + [10])
        lines.append(f"  {'entry':<{width}}  {'jobs':>4}  {'outputs':>8}  {'CPU':>8}  what")
        for r in self.rows:
            lines.append(f"  {r.key:<{width}}  {r.jobs:>4}  {_bytes(r.bytes):>8}  "
                         f"~{_time(r.cpu_s):>7}  {r.detail}")
        lines.append(f"  total: {self.summary(cores)}")
        lim = self.limits
        lines.append(f"  limits: {self.cells:,} of {lim['max_cells']:,} cells (limits.max_cells), "
                     f"{self.orbit_cells:,} of {lim['max_orbit_cells']:,} orbit cells "
                     f"(limits.max_orbit_cells),")
        lines.append(f"          {self.jobs} of {lim['max_jobs']} jobs (limits.max_jobs), "
                     f"{_bytes(self.bytes)} of {_num(lim['max_disk_gb'])} GB (limits.max_disk_gb)"
                     + (f"; {_bytes(self.free_bytes)} free under {self.results}"
                        if self.free_bytes is not None else "") + ",")
        lines.append(f"          ~{_time(self.cpu_s)} of {_num(lim['max_cpu_hours'])} h of CPU "
                     f"(limits.max_cpu_hours)")
        return "\n".join(lines)

    __str__ = format

    def refuse_beyond_limits(self):
        lim, problems = self.limits, []
        for value, key, what in ((self.cells, "max_cells", "simulation cells"),
                                 (self.orbit_cells, "max_orbit_cells", "orbit cells"),
                                 (self.jobs, "max_jobs", "jobs")):
            if value > lim[key]:
                problems.append(f"limits.{key} = {lim[key]:,}: this build has {value:,} "
                                f"{what}; raise limits.{key} to build it, or shrink the grids"
                                f"\n  ({self.summary()})")
        if self.cpu_s > lim["max_cpu_hours"] * 3600:
            problems.append(f"limits.max_cpu_hours = {_num(lim['max_cpu_hours'])}: this build "
                            f"needs ~{_time(self.cpu_s)} of CPU; raise limits.max_cpu_hours to "
                            f"build it (a cluster: README, \"On a SLURM cluster\"), or shrink "
                            f"the grids or records\n  ({self.summary()})")
        gb = self.bytes / 1e9
        if gb > lim["max_disk_gb"]:
            problems.append(f"limits.max_disk_gb = {_num(lim['max_disk_gb'])}: this build "
                            f"writes ~{_bytes(self.bytes)}; raise limits.max_disk_gb to build "
                            f"it, or shorten the records\n  ({self.summary()})")
        elif self.free_bytes is not None and self.bytes > self.free_bytes:
            # what a finished or partial earlier build holds is not written again
            built = _built_bytes(self.results)
            if self.bytes - built > self.free_bytes:
                problems.append(f"disk: this build writes ~{_bytes(self.bytes - built)} "
                                f"(~{_bytes(self.bytes)} in all, {_bytes(built)} of it already "
                                f"under {self.results}), only {_bytes(self.free_bytes)} free "
                                f"there; free some space or shorten the records")
        if problems:
            raise ConfigError(problems)


def _built_bytes(results):
    """Bytes of the files under ``results`` (an earlier build's outputs, logs and benchmarks
    aside: they are small and written anew), 0 when there is none."""
    total = 0
    for path in Path(results).rglob("*"):
        if path.parts[len(Path(results).parts):][:1] in (("logs",), ("benchmarks",)):
            continue
        try:
            if path.is_file():
                total += path.stat().st_size
        except OSError:
            continue
    return total


def _n(count, word):
    """``"1 figure"``, ``"3 figures"``, ``"2 studies"``."""
    if count == 1:
        return f"1 {word}"
    return f"{count:,} " + (word[:-1] + "ies" if word.endswith(("dy", "py")) else word + "s")


def _bytes(n):
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} B"


def _time(s):
    if s >= 3600:
        return f"{s / 3600:.2g} h"
    if s >= 60:
        return f"{s / 60:.2g} min"
    return f"{s:.2g} s"


_STUDY_KINDS = ("events", "map", "spectra", "escape", "trace", "plane_basins", "predictors",
                "map_orbits")
_ORBIT_KINDS = ("orbits", "boundaries", "basins", "lyapunov")


def built_entries(config, own=None):
    """``(drawn, build)`` of ``rule all``: ``drawn`` the entries whose figures it draws
    (``{section: names}``, paper figures included); ``build`` what the build makes, from the
    files it needs (`vibroimpact.pipeline.targets.needed_files`, the closure of ``rule
    all``'s targets through the rules' own input functions): ``{"noises": names, "studies":
    {name: kinds}, "orbits": {name: kinds}, "figures": {owner: count}, "sweeps": names,
    "copies": count, "reports": count, "map_reports": count, "validation": files}``
    (``map_reports``: the reports that read a map dataset, with its predictors' dataset)."""
    sections = ("studies", "orbits", "paper_figures")
    drawn = {s: set(config.get(s, {})) if own is None else set(own[s]) for s in sections}
    for fig in drawn["paper_figures"]:
        section = "orbits" if figures.FIGURES[fig]["owner"] == "orbits" else "studies"
        drawn[section].add(config["paper_figures"][fig])
    needed = targets.needed_files(config, drawn)
    build = {"noises": set(), "studies": {}, "orbits": {}, "figures": {}, "sweeps": set(),
             "copies": 0, "reports": 0, "map_reports": 0, "validation": set()}
    for name in config.get("studies", {}):
        kinds = {k for k in _STUDY_KINDS if targets.DATASETS[k].format(name=name) in needed}
        if kinds:
            build["studies"][name] = kinds
            # escape, attractors, predictors, orbits at the map's cells: no record file
            if kinds - {"escape", "plane_basins", "predictors", "map_orbits"}:
                build["noises"].add(config["studies"][name]["noise"])
    for name in config.get("orbits", {}):
        kinds = {k for k in _ORBIT_KINDS if targets.DATASETS[k].format(name=name) in needed}
        if kinds:
            build["orbits"][name] = kinds
    for path in needed:
        kind, fields = targets.product_of(path)
        if kind == "noise":
            build["noises"].add(fields["noise"])
        elif kind == "validation":
            build["validation"].add(path)
        elif kind == "top_figure":      # a validation figure, or a paper figure's copy
            if fields["figure"] in targets.VALIDATION_FIGURES:
                build["validation"].add(path)
            else:
                build["copies"] += 1
        elif kind == "sweep_figure":
            build["sweeps"].add(fields["name"])
        elif kind == "figure":
            owner = fields["owner"]
            build["figures"][owner] = build["figures"].get(owner, 0) + 1
        elif kind == "report" and fields["owner"] == "validation":
            build["validation"].add(path)
        elif kind == "report":
            build["reports"] += 1
            if path.endswith(".html") and any(p.endswith("_map.nc") for p in
                                              targets.rule_inputs(config, drawn, path)):
                build["map_reports"] += 1
    return drawn, build


def make_plan(config, own=None, *, results="results", studies=None):
    """The :class:`Plan` of ``rule all``: cells, jobs, bytes and CPU seconds per entry, of
    every job the build runs (:func:`built_entries`). ``studies``: the config's studies
    already resolved (``{name: Study}``); the others are resolved here."""
    drawn, build = built_entries(config, own)
    studies = dict(studies or {})
    for name, entry in config["studies"].items():
        if name not in studies:
            studies[name] = Study.from_config(name, entry)
    plan = Plan(limits=dict(config["limits"]), results=str(results), drawn=drawn,
                studies=studies)
    for name in sorted(build["noises"]):
        entry = config["noises"][name]
        n = int(entry["n_samples"])
        row = Row(f"noises.{name}", f"{n:,} samples", bytes=8 * n + FILE_OVERHEAD)
        _charge(row, "generate_noise", 1, costs.noise_cpu_s(n))
        plan.rows.append(row)
    owners = sorted(set(build["studies"]) | {o for o in build["figures"]
                                             if not o.startswith("orbits/")})
    for name in owners:
        entry = config["studies"][name]
        study = studies[name]
        noise = config["noises"][entry["noise"]]
        needs = build["studies"].get(name, set())
        row = Row(f"studies.{name}", "")
        parts = []
        if "events" in needs:
            cells = len(study.cells("events"))
            steps = costs.study_steps("events", entry, noise)
            bins = sum(int(b["n"]) for b in entry["bins"].values())
            per_cell = 12 * (bins + 100)
            tiles = study.n_tiles("events")
            _add(row, cells, 0, 2 * cells * per_cell, 0.0)
            _charge(row, "simulate_events", tiles,
                    costs.simulate_cpu_s(cells, steps, audit=True) + tiles * JOB_START_S)
            _charge(row, "aggregate_events", 1, costs.aggregate_s("aggregate_events"))
            row.bytes += (tiles + 1) * FILE_OVERHEAD
            parts.append(f"events {_n(cells, 'cell')}")
        if "map" in needs:
            cells = len(study.cells("events"))
            tiles = study.n_tiles("events")
            if study.plane is None:
                cap = sum(len(study.delta) * costs.study_steps("map", entry, noise, float(ib))
                          for ib in study.inv_beta)
                cpu = costs.map_cpu_s(cap * costs.MAP_CAP_FRACTION)
            else:       # any plane: each cell's cap at its own forcing period
                cpu = costs.plane_map_cpu_s(study, entry, noise)
            _add(row, cells, 0, 2 * cells * 200 + (tiles + 1) * FILE_OVERHEAD, 0.0)
            _charge(row, "simulate_map", tiles, cpu + tiles * JOB_START_S)
            _charge(row, "aggregate_map", 1, costs.aggregate_s("aggregate_map"))
            if study.plane is None:
                parts.append(f"map {_n(cells, 'cell')} (CPU at {costs.MAP_CAP_FRACTION:g} of "
                             f"the caps, the paper map's mean; <= "
                             f"x{1 / costs.MAP_CAP_FRACTION:.1f})"
                             + _hours(cpu, tiles))
            else:
                parts.append(f"map over ({', '.join(study.plane)}) {_n(cells, 'cell')}, "
                             f"~{_time(cpu)} of cell CPU (at {costs.MAP_CAP_FRACTION:g} of the "
                             f"caps and {costs.MAP_CELL_S * 1e3:g} ms a cell)"
                             + _hours(cpu, tiles))
        if "spectra" in needs:
            cells = len(study.cells("spectra"))
            spec = entry["spectra"]
            steps = costs.study_steps("spectra", entry, noise)
            tiles = study.n_tiles("spectra")
            _add(row, cells, 0, 2 * cells * 16 * (int(spec["nperseg"]) // 2 + 1)
                 + (tiles + 1) * FILE_OVERHEAD, 0.0)
            _charge(row, "simulate_spectra", tiles,
                    costs.simulate_cpu_s(cells, steps) + cells * costs.SPECTRA_CELL_S
                    + tiles * JOB_START_S)
            _charge(row, "aggregate_spectra", 1, costs.aggregate_s("aggregate_spectra"))
            parts.append(f"spectra {_n(cells, 'cell')}")
        if "escape" in needs:
            block = entry["escape"]
            levels, cells = len(block["rms"]), len(block["cells"])
            states = len(entry["motions"]) + 1
            cpu = costs.escape_cpu_s(entry, float(noise["dt"]))
            _add(row, levels * cells, 0, 2 * levels * cells * states * 40 + cells * states * 60
                 + (levels + 1) * FILE_OVERHEAD, 0.0)
            _charge(row, "simulate_escape", levels, cpu + levels * JOB_START_S)
            _charge(row, "aggregate_escape", 1, costs.aggregate_s("aggregate_escape"))
            cpu += (levels + 1) * JOB_START_S + FIGURE_S     # its jobs' start-up, its figure
            parts.append(f"escape {_n(cells, 'cell')} x {_n(levels, 'noise level')} "
                         f"(~{cpu:.0f} CPU-s with its figure)")
        if "plane_basins" in needs:        # its attractors block, over the plane
            a_rows, a_tiles = plane_attractor_rows(entry)
            a_cells = len(a_rows) * len(study.axes[study.plane[1]])
            n_starts = int(entry["attractors"]["n_starts"])
            _add(row, a_cells, a_tiles + 1, a_cells * (8 * 5 * n_starts + 400)
                 + 2 * FILE_OVERHEAD, costs.attractor_cpu_s(a_cells, n_starts))
            parts.append(f"attractors over ({', '.join(study.plane)}) {_n(a_cells, 'cell')} x "
                         f"{_n(n_starts, 'start')}")
        if "predictors" in needs:          # rule map_predictors: the map's bootstrap, once
            cells, motions = len(study.cells("events")), len(entry["motions"])
            row.bytes += FILE_OVERHEAD
            _charge(row, "map_predictors", 1,
                    costs.predictors_cpu_s(cells, motions) + JOB_START_S)
            parts.append("predictors of P")
        if "map_orbits" in needs:          # rule solve_map_orbits: Fig. 16 at the map's cells
            cells, motions = len(study.cells("events")), len(entry["motions"])
            row.bytes += FILE_OVERHEAD + cells * motions * 17
            _charge(row, "solve_map_orbits", 1,
                    costs.map_orbits_cpu_s(cells, motions) + JOB_START_S)
            parts.append("orbits at the map's cells")
        if "trace" in needs:
            steps = float(entry["trace"]["t_end"]) / float(noise["dt"])
            _add(row, 0, 0, 40 * steps + FILE_OVERHEAD, 0.0)
            _charge(row, "simulate_trace", 1, costs.simulate_cpu_s(1, steps) + JOB_START_S)
            parts.append("trace")
        n_figs = build["figures"].get(name, 0)
        row.bytes += n_figs * FIGURE_BYTES
        _charge(row, "draw_figure", n_figs, n_figs * (FIGURE_S + FIGURE_JOB_START_S))
        row.detail = ", ".join(parts + [_n(n_figs, "figure")])
        plan.rows.append(row)
    for name in sorted(set(build["orbits"]) | {o.split("/", 1)[1] for o in build["figures"]
                                               if o.startswith("orbits/")}):
        entry = config["orbits"][name]
        needs = build["orbits"].get(name, set())
        n_figs = build["figures"].get(f"orbits/{name}", 0)
        row = Row(f"orbits.{name}", "", bytes=n_figs * FIGURE_BYTES)
        _charge(row, "draw_figure", n_figs, n_figs * (FIGURE_S + FIGURE_JOB_START_S))
        parts = []
        if "orbits" in needs:
            rows, n_tiles = orbit_rows(entry)
            cells = orbit_plane_cells(entry)
            row.orbit_cells += cells
            row.bytes += 2 * cells * len(entry["types"]) * 34
            # two walls or an impact law: the shooting solver's rule (common.smk)
            tile_rule = ("solve_clearance_orbit_tile" if shooting(entry)
                         else "solve_orbit_tile")
            if entry.get("plane"):
                work = costs.orbit_plane_cpu_s(entry, cells)
            elif tile_rule == "solve_clearance_orbit_tile":
                work = costs.SHOOTING_CELL_S * cells
            else:
                work = costs.orbit_cpu_s(cells, len(entry["types"]))
            _charge(row, tile_rule, n_tiles, work + n_tiles * JOB_START_S)
            _charge(row, "aggregate_orbits", 1, costs.aggregate_s("aggregate_orbits"))
            parts.append(f"{_n(cells, 'cell')} x {_n(len(entry['types']), 'type')}")
        if "boundaries" in needs:
            row.bytes += 200_000 * len(entry["types"])       # the boundary curves Fig. 16 draws
            _charge(row, "trace_boundaries", 1,
                    costs.boundaries_cpu_s(len(entry["types"])) + JOB_START_S)
            parts.append("boundary curves")
        block = entry.get("attractors")
        if needs & {"basins", "lyapunov"}:
            a_rows, a_tiles = attractor_rows(entry)
            a_cells = len(a_rows) * grid_size(block["delta"])
            n_starts = int(block["n_starts"])
            row.orbit_cells += a_cells
            row.bytes += a_cells * (8 * 5 * n_starts + 400) + 2 * FILE_OVERHEAD
            _charge(row, "solve_attractor_tile", a_tiles,
                    costs.attractor_cpu_s(a_cells, n_starts) + a_tiles * JOB_START_S)
            _charge(row, "aggregate_attractors", 1, costs.aggregate_s("aggregate_attractors"))
            parts.append(f"attractors {_n(a_cells, 'cell')} x {_n(n_starts, 'start')}")
        row.detail = ", ".join(parts + [_n(n_figs, "figure")])
        plan.rows.append(row)
    for name in sorted(build["sweeps"]):
        n = len(config["sweeps"][name]["studies"])
        row = Row(f"sweeps.{name}", f"{_n(n, 'study')} side by side, 1 figure",
                  bytes=FIGURE_BYTES)
        _charge(row, "draw_sweep", 1, FIGURE_S + JOB_START_S)
        plan.rows.append(row)
    reports = build["reports"]
    if reports:
        row = Row("reports", f"{_n(reports, 'notebook')} executed, with HTML",
                  bytes=reports * REPORT_BYTES)
        _charge(row, "report", reports, reports * (REPORT_S + JOB_START_S)
                + build["map_reports"] * MAP_REPORT_S)
        plan.rows.append(row)
    validation = build["validation"]
    if validation:
        runs = sum(f.endswith(".nc") for f in validation)
        figs = sum(f.endswith(".png") for f in validation)
        notebooks = sum(f.endswith(".html") for f in validation)
        row = Row("validation", f"work-precision and stress-sample runs ({runs}), "
                  f"{_n(figs, 'figure')}, {_n(notebooks, 'report')}",
                  bytes=figs * FIGURE_BYTES + notebooks * REPORT_BYTES)
        for path in sorted(validation):
            if path.endswith(".nc"):        # the rule writing it: its file's name
                rule = VALIDATION_RULES[Path(path).stem]
                _charge(row, rule, 1,
                        _validation_runs_cpu_s(config["validation"], [path]) + JOB_START_S)
        _charge(row, "draw_validation_figure", figs,
                figs * (VALIDATION_FIGURE_S + FIGURE_JOB_START_S))
        _charge(row, "report", notebooks, notebooks * (REPORT_S + JOB_START_S))
        plan.rows.append(row)
    copies = build["copies"]
    if copies:
        row = Row("paper_figures", _n(copies, "copy"), bytes=copies * FIGURE_BYTES)
        _charge(row, "copy_paper_figure", copies, 0.0)      # a local copy: no benchmark file
        plan.rows.append(row)
    try:
        probe = Path(results)
        while not probe.exists():
            probe = probe.parent
        plan.free_bytes = shutil.disk_usage(probe).free
    except OSError:
        plan.free_bytes = None
    return plan


def _validation_runs_cpu_s(block, files):
    """CPU seconds of the validation runs among ``files`` (start-up excluded)."""
    cpu_s = 0.0
    if targets.VALIDATION_FIGURES["work_precision"] in files:
        cpu_s += costs.work_precision_cpu_s(block["work_precision"])
    if targets.VALIDATION_FIGURES["stress"] in files:
        cpu_s += costs.stress_cpu_s(block["stress"])
    return cpu_s


def _hours(cpu_s, jobs):
    """``"; runs for hours: ..."`` for a map of more than an hour of CPU (its tiles in
    parallel on every core, at best), else ``""``."""
    if cpu_s < 3600:
        return ""
    return (f"; RUNS FOR HOURS: ~{_time(cpu_s)} of CPU, at best ~{_time(cpu_s / jobs)} "
            f"with its {_n(jobs, 'tile')} on as many cores (a smaller grid, a lower "
            f"map.max_periods or a larger map.target_stderr shortens it)")


def _charge(row, rule, jobs, cpu_s):
    """``jobs`` jobs of kind ``rule`` (its benchmark files' folder) costing ``cpu_s`` in all,
    on ``row`` and its per-rule account (:meth:`Plan.rule_costs`)."""
    if not jobs:
        return
    row.jobs += jobs
    row.cpu_s += cpu_s
    n, c = row.rules.get(rule, (0, 0.0))
    row.rules[rule] = (n + jobs, c + cpu_s)


def _add(row, cells, jobs, nbytes, cpu_s):
    row.cells += cells
    row.jobs += jobs
    row.bytes += nbytes + jobs * FILE_OVERHEAD
    row.cpu_s += cpu_s
