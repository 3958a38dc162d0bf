"""The cost model of the workflow's jobs: CPU time, output bytes, memory, scheduler time.

One model, in functions of plain numbers, for the plan (`vibroimpact.pipeline.config.plan`:
what a build costs, printed and checked against ``limits`` before it runs) and for the
memory and run time each job asks of a scheduler (`vibroimpact.pipeline.config.requests`,
which the rules' ``resources:`` call). The costs were measured on the default build
(``results/benchmarks/*``, 2 cores; README, "Job costs").
"""
import math

from vibroimpact.pipeline.study import escape_samples, grid_values, map_cap_steps, shooting

__all__ = ["record_steps", "map_steps", "plane_cap_steps", "plane_map_cpu_s", "study_steps",
           "simulate_cpu_s",
           "runtime_min", "simulate_mem_mb", "noise_cpu_s", "orbit_cpu_s",
           "orbit_plane_cpu_s",
           "attractor_cpu_s", "boundaries_cpu_s", "escape_record_samples", "escape_cpu_s",
           "work_precision_cpu_s", "stress_cpu_s", "predictors_cpu_s", "map_orbits_cpu_s",
           "read_mem_mb", "predictors_mem_mb", "orbit_mem_mb", "attractor_mem_mb"]

# --- CPU seconds -----------------------------------------------------------------------------
#: Interpreter, numpy, xarray (and numba's cache) start-up of one job: the cheapest jobs of
#: a default build take 0.97-1.0 CPU-s (the harmonic trace, noise and the escape levels,
#: which compile nothing; their benchmark files' cpu_time).
JOB_START_S = 1.0
NS_PER_STEP = 25.0         # simulated sample step, with impacts (~20 ns measured)
#: What an events cell costs per step on top of NS_PER_STEP: the self-audit
#: (`impact.audit.audit_moments`: exact integrals over every step), the state recorded at
#: every sample for it, and the statistics. The audit alone, CPU ns by
#: benchmarks/bench_audit.py (5e5 steps, zeta 0.05, eps 0.5, band-limited rms 0.5, dt 0.1;
#: 2-core node, load ~7): 4-5 at delta 3, ~9 at 0.5, ~18 at 0, ~40 at -0.5 and with the
#: harmonic force; a mean over the sweep's cells, most of them beyond delta = 1. The default
#: config's five events jobs take ~27.4 CPU-s on an idle 2-core node (their benchmark files
#: in a default build; `benchmarks/job_costs.py --plan` compares them with the plan): 5 s
#: of start-up and 7.26e8 steps at 25 + 6 ns.
NS_PER_AUDIT_STEP = 6.0
NS_PER_SAMPLE = 50.0       # noise generation
#: A noise job's sample: generated, written to its netCDF file and checksummed. The default
#: build's two noise jobs (11.6e6 samples) take 3.0-3.5 CPU-s (their benchmark files in
#: three default builds, idle 2-core node): (3.2 - 2 JOB_START_S) / 11.6e6 ~ 100 ns.
NS_PER_NOISE_SAMPLE = 100.0
US_PER_ORBIT = 45.0        # one (1/beta, delta, type) orbit solve
#: One start of the attractor map, settled or run to its cap, the solver's orbits run in
#: parallel and their m = 3 scan shared per row: the default map's job (5,187 cells x 64
#: starts) takes 11.6 CPU-s, its start-up included (its benchmark file in a default build,
#: 2 cores, load ~1.5): (11.6 - JOB_START_S) / 331,968 starts = 32 us.
US_PER_START = 32.0
#: The share of its cap (`~vibroimpact.pipeline.study.map_cap_steps`) a map cell runs on
#: average before its probabilities reach their target standard error: 0.29 on the default
#: map (its `record_end` summed: 1.20e9 steps against 4.18e9 at the caps). A map whose cells
#: all run to the cap costs up to 1 / 0.29 = 3.4 times the plan's figure.
MAP_CAP_FRACTION = 0.29
#: A map cell's CPU besides its sample steps (its precision checks regroup the collisions
#: and classify the intervals in Python): measured on config/examples/planes.yaml, fresh
#: builds on a shared 2-core node, 1.8-2.0 s of cell CPU over 153-204 cells of 1e4-7e4 steps
#: (~10 ms a cell; the steps at NS_PER_STEP give 0.1-0.2 s). Costed for the cells of a plane
#: (`plane_map_cpu_s`), whose short caps it dominates; the paper's map keeps the model its
#: README numbers were measured with (its cells are 15-100 times longer).
MAP_CELL_S = 0.010
#: The boundary curves of one (m/n) type: 2.7 CPU-s for the default entry's 5 types, start-up
#: (JOB_START_S) included, with the kernels compiled at installation (its benchmark file in
#: a default build, idle 2-core node; 6.2 CPU-s when the job compiles them itself).
BOUNDARIES_S = 0.35
#: One cell and type of a plane without delta (`vibroimpact.orbits.periodic_orbits` alone,
#: no branch to follow: 97 us measured over (zeta, eps), 10 x 10 cells x 3 types, warm cache;
#: a plane along delta costs `US_PER_ORBIT` a solve, measured 45 us over (eps, delta)), and
#: one cell of a two-wall plane (the shooting solver, seeded by the simulator: ~135 ms a
#: cell, timed over a two-wall plane's cells).
ORBIT_CELL_S = 1.0e-4
SHOOTING_CELL_S = 0.135
#: One figure drawn and saved (PNG at 200 dpi and PDF), besides its job's start-up
#: (`FIGURE_JOB_START_S`): the default build's 19 figure jobs, forked, take 29.0-31.0
#: CPU-s in all (their benchmark files in two default builds, 2 cores, load ~1.5; 0.6-3.3
#: each): 1.55 a figure, 1.5 besides the fork. Each in a process of its own, they take
#: 36.4 CPU-s (0.9 besides a JOB_START_S).
FIGURE_S = 1.5
#: The start-up of a figure job (draw_figure, draw_validation_figure): a fork of Snakemake's
#: process, which imported the plotting modules and drew one small figure once
#: (`pipeline.forked`, ~1.2 CPU-s in that process, in no job's benchmark file); the fork
#: and its first writes to shared pages. fig03 forked: 0.78 CPU-s against 1.49 in a process
#: of its own, load ~2; the default build's 19 figures 28.2 CPU-s forked against 43.6 each
#: in a process of its own (benchmark files of `benchmarks/bench_make.py --make`, load 6-7).
FIGURE_JOB_START_S = 0.05
#: One report notebook executed (papermill, its kernel a process of its own) and rendered
#: twice (nbconvert) in one job, besides its start-up: the reports that show no map
#: (random_force, performance, stability) take 1.21-1.48 CPU-s in all (their benchmark
#: files' cpu_time in a default build).
REPORT_S = 0.3
#: What a report that shows a map adds (``nb.predictors``, reading the predictors' dataset
#: of rule ``map_predictors``; ``nb.markov_summary``; ``nb.map_agreement`` with its import
#: of matplotlib): the three default reports that show the map (the motion_map and harmonic
#: studies' and the orbits entry's) take 2.9-3.9 CPU-s a job (the jobs' process trees' CPU,
#: best of 3, `benchmarks/job_costs.py --jobs --only report`, load 4-6); their benchmark
#: files' cpu_time in a build, 2.6-3.9. ~2.9 a job, 1.6 of it the map's.
MAP_REPORT_S = 1.6
#: The predictors of a map's P (rule ``map_predictors``: `reports.predictors`' bootstrap, 1,000
#: resamples of the cells for each motion's P and its four predictors, in the stable domain
#: and over the plane), per map cell and motion, besides the job's start-up: 2.0-2.3 CPU-s on
#: the default map (5,187 cells, 3 motions; its benchmark file in a build, and forced alone
#: 3 times by `benchmarks/job_costs.py --jobs --only map_predictors`, load ~4), 1.2 of it
#: besides `JOB_START_S`.
PREDICTORS_CELL_S = 7.5e-5
#: The orbits of Fig. 16's types solved at a map's cells (rule ``solve_map_orbits``:
#: `orbits.cells.orbits_at_cells`, `orbit_map` along each row and `periodic_orbits` at each
#: stable cell for its multipliers), per map cell and motion, besides the job's start-up:
#: 2.4 CPU-s on the default map (5,187 cells, 3 motions; its benchmark file's cpu_time in a
#: build, load ~4), 1.4 of it besides `JOB_START_S`.
MAP_ORBITS_CELL_S = 9.0e-5
#: The rule writing each validation dataset (``results/validation/<name>.nc``).
VALIDATION_RULES = {"work_precision": "measure_work_precision",
                    "stress_sample": "sample_stress_families"}
#: One validation figure drawn, besides its job's start-up: the work-precision and stress
#: figures take 4.1-4.2 CPU-s together (2.0-2.1 each; their benchmark files in a default
#: build).
VALIDATION_FIGURE_S = 2.0
#: One aggregation job (tiles joined into a dataset), start-up included, by kind (default
#: ``"*"``): 0.44-0.48 CPU-s each (their benchmark files in a default build), the events
#: joins 0.46 and 0.97 (their bins), the spectra joins 0.97-0.98.
AGGREGATE_S = {"*": 0.5, "aggregate_events": 0.7, "aggregate_spectra": 1.0}
#: Numba compilation on an empty cache, CPU-s, by the kind of job that compiles in a default
#: build whose jobs compile (the first tile of its kind: solve_orbit_tile 9.6 CPU-s against
#: 2.4 for the other tiles; simulate_escape 8.0 against 2.0; the random trace 4.9 against
#: 1.0). `make` compiles the kernels when it installs (`vibroimpact.warm`), so the plan of a
#: build charges none of it; `Plan.rule_costs(cold_cache=True)` adds it, to compare with a
#: build whose jobs compiled (`benchmarks/job_costs.py --plan --cold-cache`).
COMPILE_S = {"solve_orbit_tile": 7.0, "simulate_escape": 6.0, "simulate_trace": 4.0}
#: A spectra cell's analysis besides its sample steps (the Welch estimate of its record):
#: the default build's 4 spectra tiles (10 + 8 cells) take 6.9 CPU-s (their benchmark
#: files), 2.2 more than their start-up and steps at `NS_PER_STEP`.
SPECTRA_CELL_S = 0.12
#: A map cell's sample step: the simulator's step and the map's own work on top of it (the
#: hop check with its bounded walk, the physical grouping of the collisions, the statistics
#: in their lean tally forms): ~31.5 ns over the default map's 1.42e9 steps, start-up
#: apart. The cells' CPU is measured on a built map by ``benchmarks/bench_map_floor.py
#: --no-main`` (``--stride 4``: 11.90 CPU-s over 1297 of its cells) and, per part of a
#: cell, by ``benchmarks/bench_map_stats.py``.
NS_PER_MAP_STEP = 31.5
#: The work-precision job (`work_precision_cpu_s`), besides its start-up: imports of scipy and
#: mpmath, the numba cache loads and the simulator's own runs. With the constants below it
#: gives 7.8 CPU-s (9.1 with the start-up) at the default sizes, against 7.9-8.9 measured
#: (benchmarks/ab_validation_sizes.py, 3 runs, load ~22; the job's own CPU: 1.8 s timing
#: solve_ivp, 3.5 its runs over the compared stretches, 1.0 the references, 0.6 RK4); that
#: script's larger "old" sizes (impacts 20, stretch 100, long_samples 1e5, repeats 3) give
#: 43.7 against 45.3 in a default build at those sizes (its benchmark file).
WP_FIXED_S = 1.0
#: One restarted solve_ivp run per unit of simulated time (CPU s): 1-6 ms over the default
#: methods, tolerances and plays (restart overhead: one restart per force sample).
SOLVE_IVP_S_PER_UNIT = 2.6e-3
#: The 34-digit reference and its 53-bit twin per unit of compared stretch, per play (CPU s):
#: 2-3 ms without chatter, ~20 ms in the chatter of delta = -0.5; a mean.
REFERENCE_S_PER_UNIT = 6e-3
#: A compared stretch is as long as ``impacts`` need at this many time units each (a mean over
#: the default plays: one impact every ~14 time units at delta = 1, ~3 at 0, ~0.2 at -0.5),
#: between ``stretch`` and ``max_stretch``.
UNITS_PER_IMPACT = 2.1
#: One RK4 step of the event-locating peer (CPU ns).
RK4_NS_PER_STEP = 30.0
#: The stress job, besides its start-up, per size (`stress_cpu_s`): every family's cases, the
#: streamed record written, streamed by three processes (~0.8 CPU-s each to start) and
#: replayed. Measured with benchmarks/ab_validation_sizes.py (load ~22, the job's process
#: and its children): 6.7-7.1 CPU-s at ``sample`` (3 runs), 22.6 at ``quick``.
STRESS_S = {"sample": 5.6, "quick": 21.0}

# --- bytes of the outputs (measured file sizes of the default build) -------------------------
FILE_OVERHEAD = 20_000
FIGURE_BYTES = 400_000     # png + pdf
REPORT_BYTES = 4_000_000   # executed notebook + HTML, figures embedded

# --- what a job asks of a scheduler ----------------------------------------------------------
#: The time a job asks over its CPU estimate: for a simulate job 2.4 x 25 ns = 60 ns a step,
#: for a slower or shared node (x3 the ~20 ns measured on one core).
RUNTIME_MARGIN = 2.4
#: Minutes every job asks besides its CPU estimate: start-up, reading, writing.
RUNTIME_FLOOR_MIN = 5
#: Resident memory of a job (MB): ~550 MB of interpreter, numba and scipy.
BASE_MEM_MB = 600
#: A noise job: chunked generation, one chunk (8 MB) plus the 2**22-sample head kept for the
#: estimates.
NOISE_MEM_MB = BASE_MEM_MB + 200
#: What a job that reads a map (its aggregation, its figures, its report, the orbits at its
#: cells) or simulates a map's tile holds besides `BASE_MEM_MB`, per 1,000 cells of the
#: largest grid it reads or of its tile: its datasets' variables in memory, a few copies
#: each. Measured (``benchmarks/job_requests.py``, tests/data/job_requests.json): from the
#: default map's 5,187 cells to the 20,453 of benchmarks/configs/fine_map.yaml these jobs'
#: peaks grew by 0.1-1.3 MB per 1,000 cells (aggregate_map 104 -> 123 MB, fig15 236 -> 253,
#: solve_map_orbits 236 -> 248; a map tile 4 MB per 1,000 cells, 1,297 -> 5,114 cells: 256
#: -> 271 MB), on peaks of 100-330 MB against the 600 of `BASE_MEM_MB`. 8 (KB a cell) is
#: twice the tile's growth and six times the readers'.
READ_MB_PER_KCELL = 8.0
#: The predictors of a map's P (rule ``map_predictors``), per 1,000 map cells: the bootstrap
#: of `vibroimpact.reports.predictors` holds up to 7 (resamples, cells) arrays of ranks and
#: one of cells, 1,000 resamples of 8 bytes (64 MB per 1,000 cells at most). Measured peaks
#: (``benchmarks/job_requests.py``): 422 MB at the default map's 5,187 cells, 1,049 MB at
#: the 20,453 of benchmarks/configs/fine_map.yaml (41 MB per 1,000 cells between them), and
#: 2.87 GB at a map of 81,225 cells (step 0.0125 on both axes): asked 808, 1,419
#: and 3,849 MB.
PREDICTORS_MB_PER_KCELL = 40.0
#: An attractor tile's starts (5 float64 a start: the final state, the exponent, the motion)
#: and an orbit tile's solutions, held while the tile is written: its output's bytes, twice.
OUTPUT_COPIES = 2
#: A simulate job: the simulator's chunk buffers (~100 MB at the default chunk of 2**20
#: samples; the events cell's self-audit adds none measured, its kernel walks the chunk),
#: besides the noise record held in memory (8 bytes a sample).
SIMULATE_BUFFERS_MB = 200


def record_steps(n_samples, dt, t_end=None):
    """Sample steps of a record of ``n_samples`` at ``dt`` up to ``t_end`` (None: to its end)."""
    end = (n_samples - 1) * dt if t_end is None else float(t_end)
    return end / dt


def map_steps(n_samples, dt, transient, max_periods, inv_beta):
    """Sample steps of a map cell at ``1/beta_f = inv_beta`` run to its cap (the most it
    runs: `~vibroimpact.pipeline.study.map_cap_steps`)."""
    return map_cap_steps(n_samples, dt, transient, max_periods, 1.0 / inv_beta)


def study_steps(kind, entry, noise, inv_beta=None):
    """Sample steps of one cell of a ``kind`` job (``events``, ``map``, ``spectra``) of the
    study ``entry`` driven by the ``noises`` entry ``noise``; a map cell at ``inv_beta``
    (None: the study's longest forcing period, the dearest cell)."""
    n, dt = int(noise["n_samples"]), float(noise["dt"])
    if kind == "map":
        if inv_beta is None:        # the study's longest forcing period (its inv_beta grid)
            inv_beta = (float(grid_values(entry["inv_beta"]).max())
                        if float(entry["amplitude"]) != 0.0 else 1.0)
        return map_steps(n, dt, float(entry["transient"]), int(entry["map"]["max_periods"]),
                         inv_beta)
    block = entry["spectra"] if kind == "spectra" else entry
    return record_steps(n, dt, block.get("t_end"))


def plane_cap_steps(study, entry, noise):
    """Sample steps of every map cell of a study with a ``plane``, each run to its cap at
    its own forcing period (`map_steps`; the rms, the walls and the restitution do not move
    the cap, only how soon a cell reaches its precision)."""
    n, dt = int(noise["n_samples"]), float(noise["dt"])
    transient, max_periods = float(entry["transient"]), int(entry["map"]["max_periods"])
    per_period = {}
    for cell in study.cells():
        if cell.inv_beta not in per_period:
            per_period[cell.inv_beta] = map_steps(n, dt, transient, max_periods, cell.inv_beta)
    return float(sum(per_period[cell.inv_beta] for cell in study.cells()))


def map_cpu_s(steps):
    """CPU seconds of a paper map's cells running ``steps`` sample steps in all."""
    return steps * NS_PER_MAP_STEP * 1e-9


def aggregate_s(rule):
    """CPU seconds of one aggregation job of kind ``rule`` (`AGGREGATE_S`)."""
    return AGGREGATE_S.get(rule, AGGREGATE_S["*"])


def plane_map_cpu_s(study, entry, noise):
    """CPU seconds of the map cells of a study with a ``plane``: every cell's cap
    (`plane_cap_steps`) at `MAP_CAP_FRACTION`, plus `MAP_CELL_S` a cell."""
    cells = len(study.cells())
    return (simulate_cpu_s(1, plane_cap_steps(study, entry, noise) * MAP_CAP_FRACTION)
            + cells * MAP_CELL_S)


def simulate_cpu_s(cells, steps, audit=False):
    """CPU seconds of ``cells`` cells of ``steps`` sample steps each (``audit``: events cells,
    which also integrate the power balance and the virial over every step)."""
    return cells * steps * (NS_PER_STEP + (NS_PER_AUDIT_STEP if audit else 0.0)) * 1e-9


def runtime_min(cpu_s):
    """Minutes a job of ``cpu_s`` CPU seconds (the plan's estimate) asks a scheduler."""
    return RUNTIME_FLOOR_MIN + math.ceil(RUNTIME_MARGIN * cpu_s / 60)


def simulate_mem_mb(n_samples, records=1):
    """Memory (MB) of a simulate job over a noise record of ``n_samples`` samples
    (``records``: copies of it held at once; 2 for a map over the rms, which scales the
    unit-rms record into a cell's)."""
    return BASE_MEM_MB + SIMULATE_BUFFERS_MB + records * -(-8 * n_samples // 2**20)


def read_mem_mb(cells):
    """Memory (MB) a light job adds to `BASE_MEM_MB` reading a grid of ``cells`` cells."""
    return READ_MB_PER_KCELL * cells / 1000


def predictors_mem_mb(cells):
    """Memory (MB) the predictors of a map of ``cells`` cells add to `BASE_MEM_MB`."""
    return PREDICTORS_MB_PER_KCELL * cells / 1000


def orbit_mem_mb(cells, types=5):
    """Memory (MB) an orbit tile or the boundaries of ``cells`` cells of ``types`` types add
    to `BASE_MEM_MB`: its solutions (2 x 34 bytes a cell and type, the plan's bytes)."""
    return OUTPUT_COPIES * 2 * 34 * cells * types / 2**20


def attractor_mem_mb(cells, n_starts):
    """Memory (MB) an attractor tile of ``cells`` cells of ``n_starts`` starts adds to
    `BASE_MEM_MB`: its starts' results (the plan's bytes)."""
    return OUTPUT_COPIES * cells * (8 * 5 * n_starts + 400) / 2**20


def noise_cpu_s(n_samples):
    """CPU seconds of a noise job of ``n_samples`` samples, start-up included."""
    return JOB_START_S + n_samples * NS_PER_NOISE_SAMPLE * 1e-9


def orbit_cpu_s(cells, types):
    """CPU seconds of the orbit solves of ``cells`` (1/beta, delta) cells of ``types`` types."""
    return cells * types * US_PER_ORBIT * 1e-6


def orbit_plane_cpu_s(entry, cells):
    """CPU seconds of an ``orbits`` entry's map over its ``plane`` of ``cells`` cells: along
    delta the map's branch following (`orbit_cpu_s`); a plane without delta solves each cell
    alone (`ORBIT_CELL_S` a type: the global scan, the finer m = 3 one included); two walls or
    an impact law the shooting solver (`SHOOTING_CELL_S` a cell)."""
    types = len(entry["types"])
    if shooting(entry):
        return cells * SHOOTING_CELL_S
    if "delta" in entry["plane"]:
        return orbit_cpu_s(cells, types)
    return cells * types * ORBIT_CELL_S


def attractor_cpu_s(cells, n_starts):
    """CPU seconds of the attractor map's ``n_starts`` starts in each of ``cells`` cells."""
    return cells * n_starts * US_PER_START * 1e-6


def map_orbits_cpu_s(cells, motions):
    """CPU seconds of solving an orbit map's types at a map's cells (rule
    ``solve_map_orbits``) besides its start-up: ``cells`` of the map, ``motions`` of it."""
    return MAP_ORBITS_CELL_S * cells * motions


def predictors_cpu_s(cells, motions):
    """CPU seconds of a map's predictors job (rule ``map_predictors``) besides its start-up:
    ``cells`` of the map, ``motions`` of its P."""
    return PREDICTORS_CELL_S * cells * motions


def boundaries_cpu_s(types):
    """CPU seconds of tracing the stable domains' edges of ``types`` (m/n) types."""
    return types * BOUNDARIES_S


def escape_record_samples(entry, dt):
    """Samples of one escape record of study ``entry`` at sample step ``dt``."""
    return escape_samples(entry["transient"], entry["escape"]["record_length"], dt)


def escape_cpu_s(entry, dt, levels=None):
    """CPU seconds of the escape jobs of study ``entry`` (``levels``: that many of them; None:
    every level): each generates its record and runs every cell over it (start-up apart, as
    `simulate_cpu_s`: the plan adds it per job)."""
    n = escape_record_samples(entry, dt)
    levels = len(entry["escape"]["rms"]) if levels is None else int(levels)
    cells = len(entry["escape"]["cells"])
    return levels * (n * NS_PER_SAMPLE * 1e-9 + simulate_cpu_s(cells, n - 1))


def work_precision_cpu_s(block):
    """CPU seconds of the work-precision job at the config block ``validation.work_precision``
    (start-up excluded): solve_ivp timed ``repeats`` times on ``stretch`` and run once over the
    compared stretch, at every play and setting; the reference over the compared stretch; RK4
    with event location ``repeats`` times over ``long_samples`` at every step count."""
    n_delta = len(block["delta"])
    stretch, max_stretch = float(block["stretch"]), float(block.get("max_stretch", 1e300))
    compared = min(max_stretch, max(stretch, UNITS_PER_IMPACT * int(block["impacts"])))
    ivp_runs = len(block["solvers"]) * len(block["rtol"])
    repeats = int(block["repeats"])
    ivp = SOLVE_IVP_S_PER_UNIT * ivp_runs * (repeats * stretch + compared)
    reference = REFERENCE_S_PER_UNIT * compared
    rk4 = RK4_NS_PER_STEP * 1e-9 * int(block["long_samples"]) * sum(block["rk4_steps"]) * repeats
    return WP_FIXED_S + n_delta * (ivp + reference + rk4)


def stress_cpu_s(block):
    """CPU seconds of the stress job at the config block ``validation.stress`` (start-up
    excluded)."""
    return STRESS_S[block.get("size", "sample")]
