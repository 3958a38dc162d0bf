"""A study: the physical parameters and its plane's grid of cells, from its config entry.

A study's plane is (1/beta, delta) unless its ``plane`` names two other parameters of
`PLANE_PARAMETERS` (a map over, e.g., (eps, delta)): the two named are grids, every other
parameter is fixed.

Pure functions of the config mapping (validated by ``workflow/schemas/config.schema.yaml``):
the workflow uses them to enumerate cells and tiles, the cell jobs to find their parameters.
Cells are addressed by an integer index; the files store both the index and the parameter values.
"""
from dataclasses import dataclass
import math

import numpy as np

from vibroimpact._plane import DEFAULT_PLANE

#: Significant decimals kept when a grid is given as start/stop/step (so 0.1 * 3 is 0.3, not
#: 0.30000000000000004), relative to the grid's scale: 10 decimals for a grid of scale >= 1,
#: more for a smaller one (1e-12 ... 5e-12 keeps 22), so no two values merge (`grid_decimals`).
GRID_DECIMALS = 10


def grid_decimals(scale):
    """Decimals a grid of values up to ``scale`` (its largest magnitude, or its step) is
    rounded to: `GRID_DECIMALS` for ``scale >= 1``, and as many more as ``scale`` has
    leading zeros below 1 (rounding at 1e-10 of the scale)."""
    scale = abs(float(scale))
    if not scale > 0.0 or not math.isfinite(scale):
        return GRID_DECIMALS
    return GRID_DECIMALS - min(0, math.floor(math.log10(scale)))


#: The keys of a study entry each kind of job reads (the workflow passes exactly these to the
#: job as its params, so changing one reruns the jobs that read it and no other). Every other
#: key of a study is read before any job (``rms``, ``seed``: its noise record, by the sweep
#: expansion), by a figure (``figures`` and the figure options of `pipeline.figures`) or by
#: its report (``report_with``); a test holds the schema's study keys to exactly these.
#: ``gap`` and ``eps_lower`` (the second wall) are job keys of every kind that simulates; a
#: one-wall entry has neither, so its params are those it had before walls could be two.
_WALLS = ("gap", "eps_lower")
#: ``law`` and ``law_lower`` (the walls' impact laws) likewise, of the kinds that simulate: an
#: entry under Newton's law has neither
_LAWS = ("law", "law_lower")
_PHYSICS = ("noise", "zeta", "eps", "amplitude", "inv_beta", "transient", "tile_size",
            "sweep") + _WALLS + _LAWS
JOB_KEYS = {
    "events": _PHYSICS + ("delta", "t_end", "n_batches", "motion_window", "motions", "bins",
                          "rebound_floor"),
    # a plane's axes (``plane``) and, with the rms an axis, its grid (``rms``): a study without
    # a plane has neither key, so its map jobs' params are those they always were
    "map": _PHYSICS + ("delta", "n_batches", "motion_window", "motions", "map", "plane", "rms"),
    "spectra": _PHYSICS + ("spectra", "n_batches"),
    "trace": _PHYSICS + ("trace",),
    # its own records (no noise file, no grid): the noise entry's spectrum and seed reach the
    # job as a param of their own (common.smk, ``escape_noise``)
    "escape": ("noise", "zeta", "eps", "amplitude", "transient", "sweep", "motion_window",
               "motions", "escape") + _WALLS + _LAWS,
    # a plane study's trace is at its cell [x, y] (and the rms axis's value scales the record)
    "plane_trace": _PHYSICS + ("trace", "plane", "delta", "rms"),
    # a plane study's escape cells are [x, y] in its plane: the fixed values of the others
    "plane_escape": ("noise", "zeta", "eps", "amplitude", "inv_beta", "delta", "plane",
                     "transient", "sweep", "motion_window", "motions", "escape") + _WALLS
    + _LAWS,
    # a plane study's basins and Lyapunov exponents: the harmonic force alone (no noise, no
    # record), over the study's plane
    "attractors": ("zeta", "eps", "amplitude", "inv_beta", "delta", "tile_size", "plane",
                   "attractors") + _WALLS,
    # joining them: with two walls the basins are counted over the study's own motions
    "attractor_basins": ("zeta", "eps", "amplitude", "inv_beta", "delta", "tile_size", "plane",
                         "attractors", "motions") + _WALLS,
}

#: The keys of an ``orbits`` entry each of its job kinds reads (the rest, ``figures``, reruns
#: only figures): the map's tiles, the boundary curves seeded from the map, the attractors.
ORBIT_JOB_KEYS = {
    # ``plane`` and ``amplitude``: absent from an entry over (inv_beta, delta), so its jobs'
    # params are those they always were
    "orbits": ("zeta", "eps", "inv_beta", "delta", "types", "tile_rows", "plane",
               "amplitude") + _WALLS + _LAWS,
    "boundaries": ("zeta", "eps", "inv_beta", "delta", "types", "plane", "amplitude") + _WALLS
    + _LAWS,
    "attractors": ("zeta", "eps", "types", "attractors") + _WALLS,
}


def grid_size(spec):
    """Number of values of a grid, without building it (a huge grid is refused on this count).

    Raises
    ------
    ValueError
        As :func:`grid_values`, for a step that is not > 0 or a stop below the start.
    """
    if isinstance(spec, dict):
        start, stop, step = float(spec["start"]), float(spec["stop"]), float(spec["step"])
        if not step > 0.0:
            raise ValueError(f"grid step must be > 0, got {step!r}")
        if stop < start:
            raise ValueError(f"grid stop must be >= start, got start={start!r}, stop={stop!r}")
        return int(math.floor((stop - start) / step + 1e-9)) + 1
    return len(spec)


def grid_values(spec):
    """Values of a grid given as a list or as ``{start, stop, step}`` (``stop`` included).

    Parameters
    ----------
    spec : list of float or dict
        Explicit values, or a mapping with ``start``, ``stop`` and ``step > 0``.

    Returns
    -------
    ndarray of float64
    """
    if isinstance(spec, dict):
        start, step = float(spec["start"]), float(spec["step"])
        scale = max(abs(start), abs(float(spec["stop"])), step)
        return np.round(start + step * np.arange(grid_size(spec)), grid_decimals(scale))
    values = np.asarray([float(v) for v in spec], dtype=float)
    if values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError(f"grid must hold at least one finite value, got {spec!r}")
    return values


#: The parameters a study's map may run over (``plane: [x, y]``): the model's (damping,
#: the two walls' restitutions, the play, the clearance, the forcing's amplitude and period
#: ratio) and the noise's rms.
PLANE_PARAMETERS = ("zeta", "eps", "eps_lower", "delta", "gap", "amplitude", "inv_beta", "rms")
#: Of `PLANE_PARAMETERS`, those of the noise (no harmonic-force problem has them: no Fig. 16).
NOISE_PARAMETERS = ("rms",)


def study_plane(entry):
    """The two axes ``(x, y)`` a study entry names in ``plane``, or None (the default plane,
    (inv_beta, delta), as every study had before planes)."""
    plane = entry.get("plane")
    return None if plane is None else tuple(str(p) for p in plane)


@dataclass(frozen=True)
class Cell:
    """One parameter cell: its index in the study and its parameter values.

    ``i_inv_beta, i_delta`` are the cell's indices along the plane's x and y axes (the
    default plane's (1/beta_f, delta)); ``inv_beta, delta`` its values of those two
    parameters, whether axes or fixed. ``axes``: for a study with a ``plane``, the plane's
    ``((x, value), (y, value))``; empty for the default plane.
    """

    index: int
    i_inv_beta: int
    i_delta: int
    inv_beta: float
    delta: float
    axes: tuple = ()

    @property
    def values(self):
        """``{x: value, y: value}`` of the plane's axes (the default plane's ``inv_beta``,
        ``delta``)."""
        if self.axes:
            return dict(self.axes)
        return {"inv_beta": self.inv_beta, "delta": self.delta}


@dataclass(frozen=True)
class Study:
    """The parameters of one study and its grid of cells (inv_beta-major order)."""

    name: str
    zeta: float
    eps: float
    amplitude: float
    inv_beta: np.ndarray
    delta: np.ndarray
    spectra_delta: np.ndarray
    tile_size: int
    motions: tuple = ()
    #: the second wall: the clearance below the wall at delta (None: one wall) and its
    #: restitution (None: eps)
    gap: float | None = None
    eps_lower: float | None = None
    #: a plane named by the entry: its axes ``(x, y)`` (None: the default (inv_beta,
    #: delta)); the axes' values in ``axes``, the other parameters in ``fixed``. A scalar
    #: field above that is an axis holds NaN (its values are the cells').
    plane: tuple | None = None
    axes: dict | None = None
    #: the walls' impact laws: the speed scales of `vibroimpact.model.Restitution` (inf:
    #: Newton's law; the lower wall's None: the upper wall's)
    speed_scale: float = math.inf
    speed_scale_lower: float | None = None

    @classmethod
    def from_config(cls, name, entry, grids=None):
        """Build from a validated config entry ``studies[name]`` (the schema's defaults
        filled in), or the part of it a job reads: an entry without ``delta`` has an empty
        events grid, one without ``motions`` classifies none (a spectra or trace job).

        ``grids``: the entry's grids already expanded (``{"inv_beta", "delta",
        "spectra_delta"}``, as `pipeline.config.checks.check` returns them), used as they
        are instead of expanding them again."""
        grids = grids or {}
        if study_plane(entry) is not None:
            return cls._from_plane(name, entry, grids)
        amplitude = float(entry["amplitude"])
        inv_beta = (np.array([1.0]) if amplitude == 0.0 else grids["inv_beta"]
                    if grids.get("inv_beta") is not None else grid_values(entry["inv_beta"]))
        if np.any(inv_beta <= 0.0):
            raise ValueError(f"studies.{name}.inv_beta must hold values > 0, got {inv_beta!r}")
        spectra = entry.get("spectra") or {}
        gap, eps_lower = walls(entry, f"studies.{name}")

        def grid(key, spec):
            return grids[key] if grids.get(key) is not None else grid_values(spec)

        return cls(name=name, zeta=float(entry["zeta"]), eps=float(entry["eps"]),
                   amplitude=amplitude, inv_beta=inv_beta,
                   delta=grid("delta", entry["delta"]) if "delta" in entry else np.empty(0),
                   spectra_delta=(grid("spectra_delta", spectra["delta"])
                                  if spectra.get("delta") else np.empty(0)),
                   tile_size=int(entry["tile_size"]),
                   motions=tuple(tuple(int(k) for k in m) for m in entry.get("motions", ())),
                   gap=gap, eps_lower=eps_lower, **laws(entry, f"studies.{name}"))

    @classmethod
    def _from_plane(cls, name, entry, grids):
        """A study over the plane ``entry["plane"]`` (`from_config`)."""
        plane = study_plane(entry)
        axes = {}
        for key in plane:
            spec = entry[key]
            if not isinstance(spec, (list, dict)):
                raise ValueError(f"studies.{name}.{key} = {spec!r}: an axis of the plane "
                                 f"{list(plane)} needs a grid (a list or {{start, stop, step}})")
            axes[key] = grids[key] if grids.get(key) is not None else grid_values(spec)
        nan = math.nan

        def fixed(key, default=None):
            if key in axes:
                return nan
            value = entry.get(key, default)
            if isinstance(value, (list, dict)):
                raise ValueError(f"studies.{name}.{key} = {value!r}: fixed in the plane "
                                 f"{list(plane)}, so a number (only the plane's axes are grids)")
            return None if value is None else float(value)

        gap = fixed("gap")
        eps_lower = fixed("eps_lower") if (gap is not None or "eps_lower" in axes) else None
        if gap is not None and eps_lower is None:
            eps_lower = fixed("eps")        # the upper wall's (NaN: eps is an axis)
        inv_beta = axes.get("inv_beta", np.array([fixed("inv_beta")]))
        delta = axes.get("delta", np.array([fixed("delta")]))
        return cls(name=name, zeta=fixed("zeta"), eps=fixed("eps"),
                   amplitude=fixed("amplitude", 0.0), inv_beta=inv_beta, delta=delta,
                   spectra_delta=np.empty(0), tile_size=int(entry["tile_size"]),
                   motions=tuple(tuple(int(k) for k in m) for m in entry.get("motions", ())),
                   gap=gap, eps_lower=eps_lower, plane=plane, axes=axes,
                   **laws(entry, f"studies.{name}"))

    @property
    def n_walls(self):
        """1, or 2 with a ``gap`` (fixed or an axis)."""
        return 1 if self.gap is None else 2

    @property
    def axis_names(self):
        """``(x, y)``: the plane's axes, the default ``("inv_beta", "delta")`` without one."""
        return self.plane or DEFAULT_PLANE

    def fixed(self):
        """``{parameter: value}`` of the model's parameters that are not axes of the
        study's plane (the dataset's ``fixed`` attribute); the second wall's only with one.
        The noise's rms is the noise entry's, not the study's: not among them."""
        values = dict(zeta=self.zeta, eps=self.eps, amplitude=self.amplitude,
                      inv_beta=float(self.inv_beta[0]), delta=float(self.delta[0]))
        if self.gap is not None:
            values.update(gap=self.gap, eps_lower=self.eps_lower)
        # an eps_lower that follows an eps axis is no fixed value
        return {k: float(v) for k, v in values.items()
                if k not in self.axis_names and not math.isnan(v)}

    def parameters(self, cell):
        """``{zeta, eps, delta, amplitude, inv_beta[, gap, eps_lower][, rms]}`` of one cell:
        the fixed values with the cell's axes in (``rms`` only when it is an axis; an
        ``eps_lower`` not given is the cell's ``eps``)."""
        values = dict(zeta=self.zeta, eps=self.eps, amplitude=self.amplitude,
                      inv_beta=cell.inv_beta, delta=cell.delta)
        if self.gap is not None:
            values.update(gap=self.gap, eps_lower=self.eps_lower)
        values.update(cell.values)
        if self.gap is not None and self.plane is not None and math.isnan(values["eps_lower"]):
            values["eps_lower"] = values["eps"]
        return values

    def walls(self):
        """``{"gap": ..., "eps_lower": ...}`` for a two-wall study (the keywords of
        `vibroimpact.simulate` and of `pipeline.cells`), ``{}`` for one wall (so a one-wall
        call is the call it always was); with the walls' laws (`laws`)."""
        out = {} if self.gap is None else dict(gap=self.gap, eps_lower=self.eps_lower)
        return dict(out, **self.laws())

    def laws(self):
        """``{"speed_scale": ..., "speed_scale_lower": ...}`` of a study whose walls do not
        follow Newton's law (the keywords of `vibroimpact.model.Model.paper`), ``{}``
        otherwise."""
        if self.speed_scale == math.inf and self.speed_scale_lower is None:
            return {}
        return dict(speed_scale=self.speed_scale, speed_scale_lower=self.speed_scale_lower)


    def cells(self, kind="events"):
        """All cells of the events grid (``inv_beta x delta``; also the map's) or of the
        spectra grid (``kind="spectra"``); of a study with a ``plane``, the plane's cells
        (``x x y``, x-major: ``index = i * n_y + j``)."""
        if self.plane is not None:
            x, y = self.plane
            xs, ys = self.axes[x], self.axes[y]
            out = []
            for i, xv in enumerate(xs):
                for j, yv in enumerate(ys):
                    values = {x: float(xv), y: float(yv)}
                    out.append(Cell(i * len(ys) + j, i, j,
                                    values.get("inv_beta", float(self.inv_beta[0])),
                                    values.get("delta", float(self.delta[0])),
                                    axes=((x, float(xv)), (y, float(yv)))))
            return out
        deltas = self.spectra_delta if kind == "spectra" else self.delta
        return [Cell(i * len(deltas) + j, i, j, float(ib), float(d))
                for i, ib in enumerate(self.inv_beta) for j, d in enumerate(deltas)]

    def n_tiles(self, kind="events"):
        """Number of tiles (jobs) covering the grid of ``kind``."""
        return -(-len(self.cells(kind)) // self.tile_size)

    def tile(self, t, kind="events"):
        """The cells of tile ``t``: every ``n_tiles``-th cell from ``t``.

        Striding spreads neighbouring cells, whose cost is alike (many impacts at small or
        negative play, few at large play), over all tiles, so parallel jobs finish together.
        """
        n = self.n_tiles(kind)
        if not 0 <= t < n:
            raise ValueError(f"tile must lie in [0, {n - 1}], got {t!r}")
        return self.cells(kind)[t::n]


def laws(entry, where):
    """``{speed_scale, speed_scale_lower}`` of a study's ``law`` and ``law_lower`` (the
    keywords of `Study`): ``inf`` and None under Newton's law.

    Raises
    ------
    ValueError
        For ``law_lower`` without ``gap`` (naming ``where``) or a speed scale not > 0 (the
        schema checks these first; jobs read blocks too).
    """
    out = {}
    for key, field in (("law", "speed_scale"), ("law_lower", "speed_scale_lower")):
        law = entry.get(key)
        if law is None:
            continue
        if key == "law_lower" and entry.get("gap") is None:
            raise ValueError(f"{where}.law_lower = {law!r} needs a second wall: give "
                             f"{where}.gap (> 0) as well, or leave law_lower out")
        scale = float(law["speed_scale"])
        if not scale > 0.0:
            raise ValueError(f"{where}.{key}.speed_scale must be > 0, got {scale!r}")
        out[field] = scale
    return out


def shooting(entry):
    """Whether an ``orbits`` entry's map is the shooting solver's (`periodic_motions`: a second
    wall, or an impact law other than Newton's) rather than the one-wall closed form's: its
    tiles' rule (``solve_clearance_orbit_tile``, else ``solve_orbit_tile``), their cost and
    their folder follow."""
    plane = entry.get("plane") or ()
    return (entry.get("gap") is not None or "gap" in plane
            or any(entry.get(k) is not None for k in _LAWS))


def walls(entry, where):
    """``(gap, eps_lower)`` of a study or ``orbits`` entry: ``(None, None)`` with one wall;
    with a ``gap``, ``eps_lower`` defaults to the entry's ``eps``.

    Raises
    ------
    ValueError
        For ``eps_lower`` without ``gap`` (naming ``where``), a gap not > 0 or an
        ``eps_lower`` outside [0, 1] (the schema checks these first; jobs read blocks too).
    """
    gap, eps_lower = entry.get("gap"), entry.get("eps_lower")
    if gap is None:
        if eps_lower is not None:
            raise ValueError(f"{where}.eps_lower = {eps_lower!r} needs a second wall: give "
                             f"{where}.gap (> 0) as well, or leave eps_lower out")
        return None, None
    gap = float(gap)
    if not (gap > 0.0 and math.isfinite(gap)):
        raise ValueError(f"{where}.gap must be a finite number > 0, got {gap!r}")
    eps_lower = float(entry["eps"] if eps_lower is None else eps_lower)
    if not 0.0 <= eps_lower <= 1.0:
        raise ValueError(f"{where}.eps_lower must lie in [0, 1], got {eps_lower!r}")
    return gap, eps_lower


def escape_seed(seed, index):
    """The seed of the escape record at noise level ``index``: ``SeedSequence(seed,
    spawn_key=(index,))``, the ``index``-th child of the noise entry's seed
    (``SeedSequence(seed).spawn``), so the levels' records are independent of each other and
    of the entry's own record, and each is fixed by ``(seed, index)`` alone."""
    return np.random.SeedSequence(int(seed), spawn_key=(int(index),))


def escape_samples(transient, record_length, dt):
    """Samples of an escape record: ``transient + record_length`` rounded up to whole sample
    steps, plus the first sample (`pipeline.cells.escape_cell`)."""
    return int(math.ceil((float(transient) + float(record_length)) / float(dt) - 1e-9)) + 1


def noise_record(entry):
    """``(n_samples, dt, tau_end)`` of a ``noises`` entry: its samples, step and last time."""
    n, dt = int(entry["n_samples"]), float(entry["dt"])
    return n, dt, (n - 1) * dt


def orbit_tiled_axis(entry):
    """The axis an ``orbits`` entry's tiles split: ``inv_beta`` without a plane; with one,
    its axis other than ``delta`` (the cells along delta are one branch followed, which a
    tile must not cut: `vibroimpact.orbits.plane.orbit_plane`), else its x axis."""
    plane = entry.get("plane")
    if not plane:
        return "inv_beta"
    return plane[1] if plane[0] == "delta" else plane[0]


def orbit_rows(entry):
    """The values of an ``orbits`` entry's tiled axis (`orbit_tiled_axis`: ``inv_beta``
    without a plane) and its number of tiles (row groups)."""
    rows = grid_values(entry[orbit_tiled_axis(entry)])
    return rows, -(-rows.size // int(entry["tile_rows"]))


def orbit_plane_cells(entry):
    """Cells of an ``orbits`` entry's map (the product of its two axes' sizes)."""
    plane = entry.get("plane") or ("inv_beta", "delta")
    return grid_size(entry[plane[0]]) * grid_size(entry[plane[1]])


def attractor_rows(entry):
    """The ``inv_beta`` values of an ``orbits`` entry's attractor map and its number of
    tiles (row groups)."""
    block = entry["attractors"]
    rows = grid_values(block["inv_beta"])
    return rows, -(-rows.size // int(block["tile_rows"]))


def plane_attractor_rows(entry):
    """The x values of a plane study's attractor map (its plane's first axis) and its number
    of tiles (``attractors.tile_rows`` x values a tile, strided over the tiles)."""
    x = study_plane(entry)[0]
    rows = grid_values(entry[x])
    return rows, -(-rows.size // int(entry["attractors"]["tile_rows"]))


def map_cap_steps(n_samples, dt, transient, max_periods, beta_f, where="max_periods"):
    """Sample steps to a map cell's cap: ``transient + max_periods`` forcing periods.

    Raises
    ------
    ValueError
        If a record of ``n_samples`` samples is shorter; the message names ``where`` (the
        config key) and the ``n_samples`` that would do.
    """
    period = 2.0 * math.pi / beta_f
    need = transient + max_periods * period
    n_cap = int(math.ceil(need / dt - 1e-9))
    if n_cap > n_samples - 1:
        tau = (n_samples - 1) * dt
        raise ValueError(
            f"{where} = {max_periods}: {max_periods} forcing periods at 1/beta_f = "
            f"{1.0 / beta_f:g} after the transient {transient:g} reach tau = {need:.6g}, beyond "
            f"the noise record (tau <= {tau:.6g}); allowed: max_periods <= "
            f"{max(int((tau - transient) / period), 0)}, or n_samples >= {n_cap + 1}")
    return n_cap
