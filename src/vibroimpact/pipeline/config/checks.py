"""The cross-field checks of a config that has passed the schema.

What JSON Schema cannot say: a study's records, grids and figures against each other and
against its noise record (a ``t_end`` beyond the record, a figure value off the study's
grid, a figure that needs a block the study lacks, an orbit type the solver does not find),
and the noise records against the generator's limits. :func:`check` finds every problem
before it raises, one or two lines each.

Loads no kernel, numba or scipy: the solver's and the generator's limits come from
`vibroimpact._limits`.
"""
from fractions import Fraction
import math

import numpy as np

from vibroimpact._limits import (ATTRACTOR_MATCH_TOL, MAX_M, MIN_FIT_LEVELS, attractor_min_time,
                                 cutoff)
from vibroimpact.pipeline import figures
from vibroimpact.pipeline.config.messages import ConfigError, _num, _Problems
from vibroimpact.pipeline.study import (NOISE_PARAMETERS, PLANE_PARAMETERS, escape_samples,
                                        grid_decimals, grid_size, grid_values, map_cap_steps,
                                        noise_record, shooting)

__all__ = ["GRID_RTOL", "check"]

#: Relative tolerance for "on the grid" (a value written as 1/1.1 matches 0.9090909091).
GRID_RTOL = 1e-6


def _on_grid(value, grid):
    """Whether ``value`` is a value of ``grid`` within `GRID_RTOL` of the larger of its own
    magnitude and the grid's (a grid of plays 1e-7 ... 3e-7 tells 1.5e-7 from 2e-7)."""
    scale = max(abs(value), float(np.max(np.abs(grid))))
    return bool(np.any(np.abs(grid - value) <= GRID_RTOL * scale))


def _grid_text(grid):
    if grid.size <= 8:
        return ", ".join(_num(float(v)) for v in grid)
    return f"{_num(float(grid[0]))}, {_num(float(grid[1]))}, ..., {_num(float(grid[-1]))}"


def _repeated(values):
    """The values of a list given more than once: equal once rounded as a grid of their
    scale is (`vibroimpact.pipeline.study.grid_decimals`: 10 significant decimals of the
    largest magnitude), ascending."""
    v = np.asarray(values, dtype=float)
    v = np.sort(np.round(v, grid_decimals(np.max(np.abs(v)))))
    return sorted(set(v[1:][np.diff(v) == 0.0].tolist()))


def _distinct(problems, where, values):
    """Record a list of values that repeats one (one cell, study or figure twice); True when
    it does not."""
    repeated = _repeated(values) if values else []
    if repeated:
        problems.add(where, values, f"{', '.join(map(_num, repeated))} listed more than once",
                     "distinct values")
    return not repeated


def _grid(problems, where, spec, limit, positive=False):
    """Values of a grid, or None after recording why it is unusable."""
    try:
        n = grid_size(spec)
    except ValueError as err:
        key = "stop" if "stop" in str(err) else "step"
        problems.add(f"{where}.{key}", spec.get(key), str(err).split(",")[0].removeprefix("grid "),
                     f"stop >= start = {_num(spec['start'])}" if key == "stop" else "> 0")
        return None
    if n > limit:
        problems.add(where, spec, f"{n:,} values (more than the limit of cells)",
                     f"at most {limit:,} values (limits.max_cells), e.g. a larger step")
        return None
    if isinstance(spec, list) and not _distinct(problems, where, spec):
        return None
    if isinstance(spec, dict) and not _stop_on_grid(problems, where, spec, n):
        return None
    values = grid_values(spec)
    if positive and np.any(values <= 0.0):
        bad = float(values[values <= 0.0][0])
        key = f"{where}.start" if isinstance(spec, dict) else where
        problems.add(key, spec["start"] if isinstance(spec, dict) else spec,
                     f"1/beta_f = {_num(bad)} is not a forcing period ratio",
                     "values > 0")
        return None
    return values


def _stop_on_grid(problems, where, spec, n):
    """Record a ``{start, stop, step}`` whose stop is not start + a whole number of steps
    (the grid would end before it, dropping the stop the README says is included), naming
    the nearest stops; True when it is on the grid (within 1e-6 of a step)."""
    start, stop, step = (float(spec[k]) for k in ("start", "stop", "step"))
    if (stop - start) / step - (n - 1) <= 1e-6:
        return True
    decimals = grid_decimals(max(abs(start), abs(stop), step))
    below, above = (round(start + k * step, decimals) for k in (n - 1, n))
    problems.add(f"{where}.stop", spec["stop"], f"not start + a whole number of steps "
                 f"{_num(step)}: the grid would end at {_num(below)}",
                 f"a stop on the grid, e.g. {_num(below)} or {_num(above)}, or a step that "
                 f"divides stop - start = {_num(stop - start)}")
    return False


def _check_noises(config, problems):
    for name, entry in config["noises"].items():
        where = f"noises.{name}"
        kind, dt = entry["kind"], float(entry["dt"])
        needs = {"white": (), "band_limited": ("beta_c",), "lowpass2": ("beta_c", "zeta_f")}[kind]
        ok = True
        for key in ("beta_c", "zeta_f"):
            given = entry.get(key) is not None
            if given != (key in needs):
                ok = False
                problems.add(f"{where}.{key}", entry.get(key),
                             f"{'required' if not given else 'not used'} for kind {kind}",
                             "a number > 0" if not given else "null (or leave it out)")
        nyquist = math.pi / dt
        beta_c = entry.get("beta_c")
        if beta_c is not None and beta_c > nyquist * (1 + 1e-9):
            ok = False
            problems.add(f"{where}.beta_c", beta_c,
                         f"above the Nyquist frequency pi/dt of dt = {_num(dt)}",
                         f"0 < beta_c <= {nyquist:.6g}")
        if int(entry["nperseg"]) > int(entry["n_samples"]):
            problems.add(f"{where}.nperseg", entry["nperseg"], "longer than the record",
                         f"16 <= nperseg <= n_samples = {entry['n_samples']}")
        if ok and kind == "lowpass2":
            _check_correlation_time(where, entry, problems)
        if ok and beta_c is not None:
            try:        # the generator's own limits (the FIR length), without loading it
                cutoff(kind, float(beta_c), dt)
            except ValueError as err:
                problems.add(where, None, str(err),
                             "see workflow/schemas/config.schema.yaml, noises")


#: Correlation times a lowpass2 record must span: the sample variance of a record T long
#: has a relative s.d. of about sqrt(c tau_c / T) (c = 1 for a lightly damped filter, whose
#: correlation rho^2 integrates to tau_c/2 on each side; 2 for an overdamped one), so 100
#: correlation times put it within ~10-15 % of rms^2.
RECORD_CORRELATION_TIMES = 100


def correlation_time(beta_c, zeta_f):
    """Decay time of the correlation of a lowpass2 noise: 1/|Re p| of its slower pole,
    ``1/(zeta_f beta_c)`` for ``zeta_f <= 1``, ``(zeta_f + sqrt(zeta_f^2 - 1))/beta_c``
    above."""
    if zeta_f <= 1.0:
        return 1.0 / (zeta_f * beta_c)
    return (zeta_f + math.sqrt(zeta_f * zeta_f - 1.0)) / beta_c


def _check_correlation_time(where, entry, problems):
    """Record a lowpass2 record short against its correlation time: one slowly varying
    sinusoid whose variance is not rms^2, under titles that say rms."""
    tau_c = correlation_time(float(entry["beta_c"]), float(entry["zeta_f"]))
    length = int(entry["n_samples"]) * float(entry["dt"])
    if length >= RECORD_CORRELATION_TIMES * tau_c:
        return
    need = RECORD_CORRELATION_TIMES * tau_c
    problems.add(f"{where}.n_samples", entry["n_samples"],
                 f"a record of {length:.3g} time units, {length / tau_c:.3g} correlation "
                 f"times of this noise (tau_c = {tau_c:.3g}: 1/(zeta_f beta_c), the decay of "
                 f"its correlation): its variance would not be rms^2",
                 f"n_samples dt >= {RECORD_CORRELATION_TIMES} tau_c = {need:.4g} (n_samples "
                 f">= {math.ceil(need / float(entry['dt'])):,}; the sample variance then "
                 f"within ~10-15 % of rms^2, 1 s.d.), or a larger zeta_f or beta_c")


def _check_figures(config, section, name, entry, problems, grids):
    where = f"{section}.{name}.figures"
    kind = "study" if section == "studies" else "orbits"
    if not entry["figures"]:
        allowed_ = sorted(f for f, s in figures.FIGURES.items() if s["owner"] == kind)
        problems.add(where, [], "no figure listed: this entry would build nothing",
                     f"a list of figures from {', '.join(allowed_)}")
        return
    seen = set()
    for i, item in enumerate(entry["figures"]):
        fig = item if isinstance(item, str) else item["name"]
        spec = figures.figure_spec(fig, kind) or figures.FIGURES[fig]
        at = f"{where}[{i}]"
        if spec["owner"] != kind:
            allowed_ = sorted(f for f, s in figures.FIGURES.items() if s["owner"] == kind)
            source = "a study" if kind == "study" else "an orbits map"
            problems.add(at, fig, f"not drawn from {source}",
                         ", ".join(allowed_))
            continue
        if fig in seen:
            problems.add(at, fig, "listed twice", "each figure once (a list of values under "
                         "its `inv_beta` draws it several times)")
        seen.add(fig)
        if kind == "study" and spec.get("needs") and not entry.get("plane"):
            problems.add(at, fig, f"a study draws {fig} over its plane, and this study has "
                         "none", f"a `plane: [x, y]` with an `{spec['needs']}:` block, or "
                         f"{fig} in an orbits entry's figures (the paper's (1/beta_f, delta))")
            continue
        if kind != "study" or spec.get("needs"):
            block = spec.get("needs")
            if block and not entry.get(block):
                problems.add(f"{section}.{name}.{block}", None, f"missing, and {fig} draws it",
                             f"an `{block}:` block (workflow/schemas/config.schema.yaml), "
                             f"or drop {fig}")
            continue
        if spec.get("harmonic") and not entry.get("amplitude"):
            problems.add(f"studies.{name}.amplitude", entry.get("amplitude", 0.0),
                         f"{fig} shows the harmonic force", "amplitude != 0 for this figure")
        for block in ("trace", "spectra", "escape"):
            if block in spec["reads"] and not entry.get(block):
                problems.add(f"studies.{name}.{block}", None,
                             f"missing, and {fig} draws it",
                             f"a `{block}:` block (workflow/schemas/config.schema.yaml), "
                             f"or drop {fig}")
        item = {} if isinstance(item, str) else item
        for key in item:
            if key == "name":
                continue
            usable = (key == spec.get("per") or key in spec.get("options", ())
                      or key in spec.get("sources", ())
                      or (key == "beta_max" and "spectra" in spec["reads"]))
            if not usable:
                problems.add(f"{at}.{key}", item[key], f"not an option of {fig}",
                             _figure_keys(fig))
        if spec.get("per") == "inv_beta" and "inv_beta" in item:
            _distinct(problems, f"{at}.inv_beta", item["inv_beta"])
            for j, v in enumerate(item["inv_beta"]):
                if not _on_grid(v, grids["inv_beta"]):
                    problems.add(f"{at}.inv_beta[{j}]", v, "not on the study's inv_beta grid",
                                 _grid_text(grids["inv_beta"]))
        _distinct(problems, f"{at}.density_delta", item.get("density_delta"))
        for j, v in enumerate(item.get("density_delta", [])):
            if not _on_grid(v, grids["delta"]):
                problems.add(f"{at}.density_delta[{j}]", v, "not on the study's delta grid",
                             _grid_text(grids["delta"]))
        if "orbits" in spec.get("sources", ()):
            _check_orbits_item(config, name, entry, at, fig, item, problems)


def _figure_keys(fig):
    spec = figures.FIGURES[fig]
    keys = [*([spec["per"]] if spec.get("per") else []), *spec.get("options", ()),
            *spec.get("sources", ()), *(["beta_max"] if "spectra" in spec["reads"] else [])]
    return f"name, {', '.join(keys)}" if keys else f"only name ({fig} has no options)"


def _check_orbits_item(config, name, entry, at, fig, item, problems):
    orbits = item.get("orbits")
    names = sorted(config.get("orbits", {}))
    if orbits not in config.get("orbits", {}):
        problems.add(f"{at}.orbits", orbits, f"{fig} is drawn over an orbit map; give its "
                     f"entry as {{name: {fig}, orbits: <name>}}", ", ".join(names) or
                     "an `orbits` entry (none defined)")
        return
    other = config["orbits"][orbits]
    law = next((k for k in ("law", "law_lower") if other.get(k) is not None), None)
    if law is not None:
        problems.add(f"{at}.orbits", orbits, f"orbits.{orbits}.{law} is an impact law other "
                     f"than Newton's, and {fig} compares the map with the closed-form orbits "
                     f"of Newton's law at its cells", f"an `orbits` entry without {law}")
        return
    if entry.get("plane") or other.get("plane"):
        _check_orbits_item_plane(name, entry, at, orbits, other, problems)
    else:
        _check_orbits_item_system(entry, at, orbits, other, problems)
    if other.get("gap") is not None:
        _check_orbit_grid_holds(name, entry, at, orbits, other, problems)
    types = {tuple(t) for t in other["types"]}
    missing = [m for m in entry["motions"] if tuple(m) not in types]
    if missing:
        problems.add(f"{at}.orbits", orbits, f"orbits.{orbits} maps no {missing} motion, "
                     f"which studies.{name}.motions lists", "an `orbits` entry whose types "
                     "include every motion of the study")


def _check_orbit_grid_holds(name, entry, at, orbits, other, problems):
    """A two-wall orbits entry's motions are read at the map's cells from its own grid
    (`vibroimpact.orbits.cells`: shooting is not run again per cell), so its grid must hold
    every value of the map's axes."""
    plane = list(entry.get("plane") or ("inv_beta", "delta"))
    for key in plane:
        spec, ospec = entry.get(key), other.get(key)
        if not isinstance(spec, (list, dict)) or not isinstance(ospec, (list, dict)):
            continue                        # a plane mismatch, said by its own check
        try:
            values, held = grid_values(spec), grid_values(ospec)
        except (ValueError, TypeError):
            continue                        # a malformed grid, said by its own check
        scale = max(1.0, float(np.abs(held).max(initial=0.0)))
        missing = [float(v) for v in values
                   if not np.any(np.abs(held - v) <= 1e-9 * scale)]
        if missing:
            shown = ", ".join(_num(v) for v in missing[:6]) + (", ..." if len(missing) > 6
                                                                 else "")
            problems.add(f"{at}.orbits", orbits, f"orbits.{orbits}.{key} lacks {shown} of the "
                         f"study's {key} grid: a two-wall entry's motions are read at the "
                         f"map's cells from its own grid, not solved there",
                         f"orbits.{orbits}.{key} holding every value of studies.{name}.{key}")


#: The parameters a map over a plane and its orbits entry must share (each fixed, or an
#: axis of both): the harmonic-force problem's.
SHARED_PLANE_PARAMETERS = ("zeta", "eps", "eps_lower", "delta", "gap", "amplitude", "inv_beta")


def _check_orbits_item_plane(name, entry, at, orbits, other, problems):
    """fig15_vs_fig16 of a study and an orbits entry, one of them with a plane: the same
    plane, and the same value of every parameter both hold fixed (a missing amplitude of
    the orbits entry is 1)."""
    plane = list(entry.get("plane") or ("inv_beta", "delta"))
    oplane = list(other.get("plane") or ("inv_beta", "delta"))
    if plane != oplane:
        problems.add(f"{at}.orbits", orbits, f"orbits.{orbits} maps the plane {oplane}, the "
                     f"study the plane {plane}", f"an `orbits` entry with plane: {plane}")
        return
    for key in SHARED_PLANE_PARAMETERS:
        if key in plane:
            continue
        a = entry.get(key)
        b = other.get(key, 1.0 if key == "amplitude" else None)
        if key == "eps_lower":
            if entry.get("gap") is None or other.get("gap") is None:
                continue            # a wall below in one only: the gap's line says so
            if a is None and b is None:
                continue            # both follow eps (fixed alike, or the same axis)
            a = entry["eps"] if a is None else a        # absent with a gap: the study's eps
            b = other["eps"] if b is None else b
        if (a is None) != (b is None) or (a is not None and (
                isinstance(a, (list, dict)) or isinstance(b, (list, dict))
                or float(a) != float(b))):
            b_text, a_text = _told_apart(b, a)
            problems.add(f"{at}.orbits", orbits, f"orbits.{orbits} has {key} = {b_text}, the "
                         f"study {key} = {a_text}",
                         f"an `orbits` entry over {plane} with the study's fixed values")


def _check_orbits_item_system(entry, at, orbits, other, problems):
    for key in ("zeta", "eps", "gap", "eps_lower"):
        a, b = entry.get(key), other.get(key)
        if key == "eps_lower":
            if entry.get("gap") is None or other.get("gap") is None:
                continue            # a wall below in one only: the gap's line says so
            a = entry["eps"] if a is None else a        # absent with a gap: the entry's eps
            b = other["eps"] if b is None else b
        if a != b and (b is None or a is None or float(b) != float(a)):
            b_text, a_text = _told_apart(b, a)
            problems.add(f"{at}.orbits", orbits, f"orbits.{orbits} has {key} = {b_text}, the "
                         f"study {key} = {a_text}",
                         "an `orbits` entry of the same zeta and eps (and walls)")


def _told_apart(a, b):
    """Two values as text, numbers with as many digits as it takes to tell them apart (up
    to 17: "0.9090909090909091" and "0.90909090909091"), "none" for None."""
    def text(v, digits):
        if v is None:
            return "none"
        if isinstance(v, (int, float)):
            return f"{float(v):.{digits}g}" if isinstance(v, float) else str(v)
        return str(v)
    for digits in range(6, 18):
        ta, tb = text(a, digits), text(b, digits)
        if ta != tb:
            return ta, tb
    return ta, tb


def _check_walls(where, entry, problems):
    """A second wall: ``eps_lower`` only with a ``gap``; True for a two-wall entry."""
    if entry.get("gap") is None:
        if entry.get("eps_lower") is not None:
            problems.add(f"{where}.eps_lower", entry["eps_lower"], "the restitution of a "
                         "second wall, and this entry has one wall (no gap)",
                         f"leave it out, or give {where}.gap > 0 (the wall at x = delta - gap)")
        return False
    return True


def _check_laws(where, entry, problems):
    """The walls' impact laws (``law``, ``law_lower``): the second wall's only with one, and
    none where a solver holds Newton's law (the closed-form orbits of fig15_vs_fig16, the
    attractors block)."""
    laws = [k for k in ("law", "law_lower") if entry.get(k) is not None]
    if "law_lower" in laws and entry.get("gap") is None:
        problems.add(f"{where}.law_lower", entry["law_lower"], "the impact law of a second "
                     "wall, and this entry has one wall (no gap)",
                     f"leave it out, or give {where}.gap > 0 (the wall at x = delta - gap)")
    if not laws:
        return
    names = [f if isinstance(f, str) else f.get("name") for f in entry.get("figures", [])]
    if "fig15_vs_fig16" in names:
        problems.add(f"{where}.figures", "fig15_vs_fig16", f"the closed-form orbits it draws "
                     f"under the map hold Newton's law, and {where}.{laws[0]} is another",
                     f"leave fig15_vs_fig16 out, or leave {where}.{laws[0]} out (Newton's "
                     f"law); the shooting solver takes any law (vibroimpact.periodic_motions)")
    if entry.get("attractors"):
        problems.add(f"{where}.attractors", None, f"the attractor maps hold Newton's law, and "
                     f"{where}.{laws[0]} is another", f"leave attractors out, or leave "
                     f"{where}.{laws[0]} out (Newton's law)")


def _check_motions(where, entry, two_walls, problems):
    """The motions a study classifies: walls, repeats, ratios that cannot be told apart."""
    motions = [tuple(m) for m in entry["motions"]]
    walled = [list(m) for m in motions if len(m) == 3]
    if walled and not two_walls:
        problems.add(f"{where}.motions", walled, "two-wall motions [m_upper, m_lower, n], "
                     "and this study has one wall (no gap)", "[m, n] pairs, or give "
                     f"{where}.gap > 0")
    for j, m in enumerate(motions):
        if len(m) == 3 and m[2] < 1:
            problems.add(f"{where}.motions[{j}][2]", m[2], "a motion over no forcing period",
                         "n >= 1 in [m_upper, m_lower, n]")
        if len(m) == 3 and m[0] + m[1] < 1:
            problems.add(f"{where}.motions[{j}]", list(m), "a motion without a collision",
                         "[m_upper, m_lower, n] with m_upper + m_lower >= 1")
    if len(set(motions)) != len(motions):
        problems.add(f"{where}.motions", entry["motions"], "a motion is listed twice",
                     "distinct [m, n] pairs")
    else:
        ratios = {}
        for m, n_ in (m for m in motions if len(m) == 2):
            first = ratios.setdefault(Fraction(n_, m), (m, n_))
            if first != (m, n_):
                problems.add(f"{where}.motions", entry["motions"],
                             f"({m}/{n_}) has z_j/z = {_num(n_ / m)} like ({first[0]}/"
                             f"{first[1]}): the classification on z_j/z cannot tell them apart",
                             "[m, n] pairs of distinct n/m")


def _check_study(config, name, entry, problems, limits, unforced):
    """The checks of a study, over the paper's ``(1/beta_f, delta)`` grid or over its ``plane``
    (any two parameters): one prelude (the grids' shapes, the walls and their laws, the
    reports, the noise record), then the statistics each accepts: events, spectra, densities
    and the map over the paper's grid (`_check_grid_statistics`), the map alone over a plane
    (`_check_plane_statistics`). Returns the study's grids (those of a plane: its axes', and
    the fixed ``inv_beta``, ``delta`` as one-value arrays) or None."""
    where = f"studies.{name}"
    plane = None if entry.get("plane") is None else list(entry["plane"])
    if plane is None:
        _refuse_plane_attractors(where, entry, problems)
        if not _grid_shapes(where, entry, problems):
            return None
    else:
        grids, ok = _plane_axes(where, entry, plane, problems, limits, unforced)
    if plane is None or "gap" not in plane:    # an axis gap is its plane's to check
        _check_walls(where, entry, problems)
    two_walls = entry.get("gap") is not None
    _check_laws(where, entry, problems)
    _check_report_with(config, name, entry, problems)
    if plane is not None:
        _refuse_event_keys(where, entry, plane, problems)
    if entry["noise"] not in config["noises"]:
        problems.add(f"{where}.noise", entry["noise"], "no such noise record",
                     ", ".join(sorted(config["noises"])))
        return None
    record = noise_record(config["noises"][entry["noise"]])
    if plane is None:
        return _check_grid_statistics(config, name, entry, problems, limits, unforced,
                                      two_walls, record)
    return _check_plane_statistics(config, name, entry, problems, plane, grids, ok, two_walls,
                                   record)


def _refuse_plane_attractors(where, entry, problems):
    """A study's attractors block needs a plane (an orbits entry's is the paper's plane)."""
    if entry.get("attractors"):
        # an orbits entry's attractors block is one-wall only: with a gap, a plane is the way
        other = ("a `plane: [x, y]` in the study (with the second wall: e.g. plane: "
                 "[inv_beta, delta] and gap fixed)" if entry.get("gap") is not None else
                 "a `plane: [x, y]` in the study, or the attractors block of an orbits entry "
                 "(the paper's (1/beta_f, delta) plane)")
        problems.add(f"{where}.attractors", None, "basins and Lyapunov exponents of a study "
                     "run over its plane, and this study has none", other)


def _grid_shapes(where, entry, problems):
    """Over the paper's grid: ``inv_beta`` and ``delta`` grids, every other parameter a number
    (an axis needs a plane). False with the problems recorded."""
    shapes_ok = True
    for key in PLANE_PARAMETERS:        # a grid where a number is due: axes need a plane
        if key in ("inv_beta", "delta"):
            if not isinstance(entry.get(key, []), (list, dict)):
                shapes_ok = False
                problems.add(f"{where}.{key}", entry[key], "a number, and this study has no "
                             "plane that fixes it", f"a grid (a list or {{start, stop, step}}), "
                             f"or a `plane` that does not name {key}")
        elif isinstance(entry.get(key), (list, dict)):
            shapes_ok = False
            problems.add(f"{where}.{key}", entry[key], "a grid, and this study has no plane "
                         "naming it", f"a number, or `plane: [{key}, delta]` (say) to map over "
                         f"it")
    return shapes_ok


def _check_grid_statistics(config, name, entry, problems, limits, unforced, two_walls, record):
    """The statistics of a study over the paper's grid (events, spectra, densities, trace,
    map, escape, figures) on its noise ``record`` ``(n, dt, tau)``; its grids or None."""
    where = f"studies.{name}"
    n, dt, tau = record
    record = f"the record of noises.{entry['noise']} ends at tau = {tau:.6g}"
    grids = {"delta": _grid(problems, f"{where}.delta", entry["delta"], limits["max_cells"])}
    resolved = {}       # the grids, and the spectra's plays: what the study resolves to
    harmonic = float(entry["amplitude"]) != 0.0
    grids["inv_beta"] = (_grid(problems, f"{where}.inv_beta", entry["inv_beta"],
                               limits["max_cells"], positive=True)
                         if harmonic else np.array([1.0]))
    trace_inv_beta = (entry.get("trace") or {}).get("inv_beta")
    if harmonic:
        for key, values in (("inv_beta", grids["inv_beta"]),
                            ("trace.inv_beta", [trace_inv_beta] if trace_inv_beta else None)):
            _check_forcing_period(where, entry, key, values, dt, problems)
    amplitude_swept = "amplitude" in entry.get("sweep", {}).get("values", {})
    if not harmonic and not amplitude_swept:
        # keys of the harmonic force a random study would silently ignore
        for key, value, default in (("inv_beta", entry["inv_beta"], unforced),
                                    ("trace.inv_beta", trace_inv_beta, None)):
            if value is not None and value != default:
                problems.add(f"{where}.{key}", value, "1/beta_f of the harmonic force, and "
                             "this study has none (amplitude = 0)", "leave it out, or give "
                             "the study an amplitude != 0")
    transient = float(entry["transient"])
    t_end = entry.get("t_end")
    end = tau if t_end is None else float(t_end)
    if t_end is not None and t_end > tau * (1 + 1e-9):
        problems.add(f"{where}.t_end", t_end, f"longer than the noise record ({record})",
                     f"transient < t_end <= {tau:.6g}, or null for the whole record")
    elif transient >= end:
        problems.add(f"{where}.transient", transient, "leaves no record for the statistics "
                     f"(t_end = {end:.6g})", f"0 <= transient < {end:.6g}")
    uses = {r for f in entry["figures"] for r in figures.FIGURES[
        f if isinstance(f, str) else f["name"]]["reads"]}
    if "events" in uses and (t_end is None or t_end <= tau * (1 + 1e-9)):
        # the batches cut the events' record (a trace or a spectrum has none)
        _check_batches(where, entry, end - transient, dt, problems)
    spectra = entry.get("spectra")
    if spectra:
        s_end = tau if spectra.get("t_end") is None else float(spectra["t_end"])
        if s_end > tau * (1 + 1e-9):
            problems.add(f"{where}.spectra.t_end", spectra["t_end"],
                         f"longer than the noise record ({record})",
                         f"transient < t_end <= {tau:.6g}, or null")
        elif s_end <= transient:
            if transient < end:
                problems.add(f"{where}.spectra.t_end", spectra["t_end"],
                             f"leaves no record after the transient ({_num(transient)})",
                             f"{_num(transient)} < t_end <= {tau:.6g}, or null")
        else:
            # the samples k dt with transient <= k dt <= t_end (cells.spectra_cell)
            samples = (math.floor(s_end / dt + 1e-9) - math.ceil(transient / dt - 1e-9) + 1)
            if samples < 16:
                problems.add(f"{where}.spectra", None, f"its record holds {samples} samples "
                             f"(transient to t_end, at dt = {_num(dt)}), fewer than a Welch "
                             f"segment's 16", f"a record of 16 samples or more: n_samples >= "
                             f"{16 + math.ceil(transient / dt - 1e-9)} in noises."
                             f"{entry['noise']}, or a longer spectra.t_end")
            elif samples < int(spectra["nperseg"]):
                problems.add(f"{where}.spectra.nperseg", spectra["nperseg"],
                             f"longer than the spectra record ({samples} samples from the "
                             f"transient to t_end)",
                             f"16 <= nperseg <= {samples}, or a longer spectra.t_end")
        sgrid = _grid(problems, f"{where}.spectra.delta", spectra["delta"], limits["max_cells"])
        resolved["spectra_delta"] = sgrid
        if sgrid is not None and grids["delta"] is not None:
            for j, v in enumerate(sgrid):
                if not _on_grid(v, grids["delta"]):
                    problems.add(f"{where}.spectra.delta" + (f"[{j}]" if isinstance(
                        spectra["delta"], list) else ""), float(v),
                        "not on the study's delta grid (a spectrum's cell has its impact "
                        "statistics too)", _grid_text(grids["delta"]))
    trace = entry.get("trace")
    if trace and trace.get("cell") is not None:
        problems.add(f"{where}.trace.cell", trace["cell"], "a point [x, y] of a plane, and "
                     "this study has none", "delta (and inv_beta) of the trace, or a `plane`")
    if trace and trace.get("delta") is None:
        problems.add(f"{where}.trace.delta", None, "missing: the play of the trace",
                     "a number under trace.delta")
    _check_trace_t_end(where, entry, dt, tau, record, problems)
    _distinct(problems, f"{where}.density_delta", entry["density_delta"])
    if grids["delta"] is not None:
        for j, v in enumerate(entry["density_delta"]):
            if not _on_grid(v, grids["delta"]):
                problems.add(f"{where}.density_delta[{j}]", v, "not on the delta grid",
                             _grid_text(grids["delta"]))
    _check_motions(where, entry, two_walls, problems)
    if "map" in uses and harmonic and grids["inv_beta"] is not None:
        _check_map_record(where, entry, grids["inv_beta"], n, dt, tau, problems)
    if "map" in uses and harmonic:
        _plane(problems, where, grids, "fig15")
    if entry.get("escape"):
        _check_escape(where, entry, grids, harmonic, dt, problems)
    if all(g is not None for g in grids.values()):
        _check_figures(config, "studies", name, entry, problems, grids)
    resolved.update(grids)
    return resolved

def _check_forcing_period(where, entry, key, values, dt, problems):
    """A forcing period ``2 pi / beta_f`` (``values`` of 1/beta_f under ``key``) no shorter
    than the noise record's sample step; True when it holds."""
    shortest = dt / (2 * math.pi)       # a forcing period of one sample step
    fast = [float(v) for v in (values if values is not None else []) if v < shortest]
    if fast:
        problems.add(f"{where}.{key}", fast[0], f"a forcing period 2 pi/beta_f shorter than the "
                     f"sample step dt = {_num(dt)} of noises.{entry['noise']} (the pressed mass "
                     f"would stick and release many times a step)",
                     f"1/beta_f >= dt/(2 pi) = {shortest:.6g}")
    return not fast


def _check_map_record(where, entry, inv_beta, n, dt, tau, problems):
    """A map's records (a study on the paper's plane or on its own): the cap of its longest
    forcing period within the noise record of ``n`` samples (the job's own check, at parse
    time), ``transient + map.min_time`` inside it, and batches of the shortest cell's record
    (``map.min_time``) long enough."""
    spec, transient = entry["map"], float(entry["transient"])
    try:
        map_cap_steps(n, dt, transient, int(spec["max_periods"]), 1.0 / float(inv_beta.max()),
                      where=f"{where}.map.max_periods")
    except ValueError as err:
        problems.append(f"{err} in noises.{entry['noise']}")
    if transient + float(spec["min_time"]) > tau * (1 + 1e-9):
        problems.add(f"{where}.map.min_time", spec["min_time"], f"transient + min_time is beyond "
                     f"the record (the record of noises.{entry['noise']} ends at tau = "
                     f"{tau:.6g})", f"0 < min_time <= {tau - transient:.6g}")
    _check_batches(where, entry, float(spec["min_time"]), dt, problems,
                   record="a map cell's shortest, map.min_time", longer="a map.min_time")


def _check_report_with(config, name, entry, problems):
    """``report_with``: other studies of the config (not itself, nor its sweep's own)."""
    siblings = {name}           # itself, or every study of its sweep
    if "sweep" in entry:
        siblings = set(config.get("sweeps", {}).get(entry["sweep"]["name"], {}).get(
            "studies", [name]))
    for other in entry.get("report_with", []):
        if other in siblings or other not in config["studies"]:
            problems.add(f"studies.{name}.report_with", other, "no other study of this name",
                         ", ".join(sorted(set(config["studies"]) - siblings)) or "none")


#: Keys of a study that only its event statistics read (Figs. 3-14), with the schema's
#: defaults: a plane study draws its map alone, which runs each cell from rest to its own
#: target or cap (``map``), so a value other than the default would be ignored. (Its
#: ``n_batches`` cut the map's records: checked against the shortest, ``map.min_time``.)
_EVENT_ONLY = {"t_end": None, "density_delta": []}


def _check_trace_t_end(where, entry, dt, tau, record, problems):
    """A trace (``trace.t_end``) within the noise record and at least one sample step."""
    trace = entry.get("trace")
    if trace and float(trace["t_end"]) > tau * (1 + 1e-9):
        problems.add(f"{where}.trace.t_end", trace["t_end"],
                     f"longer than the noise record ({record})", f"0 < t_end <= {tau:.6g}")
    elif trace and float(trace["t_end"]) < dt * (1 - 1e-9):
        problems.add(f"{where}.trace.t_end", trace["t_end"], f"shorter than one sample step "
                     f"(dt = {_num(dt)} of noises.{entry['noise']}): a trace of one point",
                     f"{_num(dt)} <= t_end <= {tau:.6g}")


def _check_plane_trace(where, entry, plane, grids, dt, tau, problems):
    """A plane study's trace: at its ``cell`` [x, y] inside the plane (no delta, inv_beta of
    its own: the plane fixes them or runs over them)."""
    at = f"{where}.trace"
    trace = entry["trace"]
    for key in ("delta", "inv_beta"):
        if trace.get(key) is not None:
            problems.add(f"{at}.{key}", trace[key], f"a study with a plane ({plane}) gives its "
                         "trace's point as cell: [x, y]", f"trace.cell: [{plane[0]}, "
                         f"{plane[1]}], the others the study's fixed values")
    cell = trace.get("cell")
    if cell is None:
        problems.add(f"{at}.cell", None, f"missing: the trace's point in the plane {plane}",
                     f"[{plane[0]}, {plane[1]}]")
    else:
        for k, v in zip(plane, (float(c) for c in cell)):
            test, allowed_ = _AXIS_BOUNDS[k]
            box = grids.get(k)
            if not test(v):
                problems.add(f"{at}.cell", cell, f"{k} = {_num(v)} is out of its range",
                             f"[{plane[0]}, {plane[1]}] with {allowed_}")
            elif box is not None and not (
                    float(box.min()) - GRID_RTOL * max(1.0, abs(float(box.min()))) <= v
                    <= float(box.max()) + GRID_RTOL * max(1.0, abs(float(box.max())))):
                problems.add(f"{at}.cell", cell, f"outside the study's ({plane[0]}, "
                             f"{plane[1]}) plane", f"{k} in [{_num(float(box.min()))}, "
                             f"{_num(float(box.max()))}]")
    record = f"the record of noises.{entry['noise']} ends at tau = {tau:.6g}"
    _check_trace_t_end(where, entry, dt, tau, record, problems)


#: The bounds of each parameter a plane may run over, as (test, allowed) (the schema's for a
#: number: an axis's values are checked here, after its grid is expanded).
_AXIS_BOUNDS = {
    "zeta": (lambda v: 0.0 < v <= 0.9999, "0 < zeta <= 0.9999"),
    "eps": (lambda v: 0.0 <= v <= 1.0, "0 <= eps <= 1"),
    "eps_lower": (lambda v: 0.0 <= v <= 1.0, "0 <= eps_lower <= 1"),
    "gap": (lambda v: v > 0.0, "gap > 0"),
    "amplitude": (lambda v: v != 0.0, "amplitude != 0 (a map needs the harmonic force)"),
    "inv_beta": (lambda v: v > 0.0, "1/beta_f > 0"),
    "rms": (lambda v: v >= 0.0, "rms >= 0"),
    "delta": (lambda v: True, "any play"),
}
#: The figures a study with a plane draws: its map's, its basins and Lyapunov maps (an
#: `attractors` block), its escape (cells in the plane's coordinates) and its trace (Fig. 10
#: at a cell); and fig15_vs_fig16 over an orbits entry of the same plane
#: (`_check_orbits_item`), unless the plane names a noise parameter.
PLANE_FIGURES = ("fig15", "residence", "basins", "lyapunov", "escape_vs_noise", "fig10")



def _axis_grid(problems, where, spec, max_cells, bounds):
    """The values of a plane's axis ``spec`` (a list or {start, stop, step}) within
    ``bounds`` (``(test, allowed)``), or None with the problem recorded."""
    values = _grid(problems, where, spec, max_cells)
    if values is None:
        return None
    test, allowed = bounds
    bad = [float(v) for v in values if not test(float(v))]
    if bad:
        problems.add(where, spec, f"holds {_num(bad[0])}", allowed)
        return None
    return values


def _plane_axes(where, entry, plane, problems, limits, unforced):
    """A plane's two axes: grids of values in their bounds, every other parameter a number,
    the harmonic force present. ``(grids, ok)``."""
    grids, ok = {}, True
    for key in plane:
        spec = entry.get(key)
        if key == "inv_beta" and spec == unforced:
            # the schema's default, or the same one value written: a one-value axis either way
            problems.add(f"{where}.{key}", spec, f"missing, or the one value {unforced} (the "
                         f"default): an axis of the plane {plane} needs a grid",
                         f"a grid of at least 2 values under {key}: a list or "
                         f"{{start, stop, step}}")
            ok = False
            continue
        if spec is None:
            problems.add(f"{where}.{key}", None, f"missing: an axis of the plane {plane}",
                         f"a grid under {key}: a list or {{start, stop, step}}")
            ok = False
            continue
        if not isinstance(spec, (list, dict)):
            problems.add(f"{where}.{key}", spec, f"a number, and {key} is an axis of the "
                         f"plane {plane}", f"a grid (a list or {{start, stop, step}}), or a "
                         f"plane that does not name {key}")
            ok = False
            continue
        values = _axis_grid(problems, f"{where}.{key}", spec, limits["max_cells"],
                            _AXIS_BOUNDS[key])
        if values is None:
            ok = False
            continue
        grids[key] = values
    for key in PLANE_PARAMETERS:
        if key in plane or key not in entry:
            continue
        value = entry[key]
        if key == "inv_beta" and value == unforced:
            problems.add(f"{where}.inv_beta", value, f"missing, or the list {unforced} (the "
                         f"default grid of a study without a plane): the plane {plane} fixes "
                         f"1/beta_f", "a number > 0 under inv_beta (a map needs the forcing "
                         "period), e.g. inv_beta: 1.0")
            ok = False
        elif isinstance(value, (list, dict)):
            problems.add(f"{where}.{key}", value, f"a grid, and {key} is fixed in the plane "
                         f"{plane} (only the plane's axes are grids)",
                         f"a number, or name {key} in the plane (a sweep of maps: a list "
                         f"under zeta, eps, amplitude, rms or seed that the plane does not "
                         f"name, one study each)")
            ok = False
    if "amplitude" not in plane and not float(entry["amplitude"]):
        problems.add(f"{where}.amplitude", entry["amplitude"], "a study with a plane draws "
                     "its map, which needs the harmonic force", "amplitude != 0")
        ok = False
    return grids, ok


def _refuse_event_keys(where, entry, plane, problems):
    """Keys the event statistics alone read, in a study that draws its map alone."""
    for key, default in _EVENT_ONLY.items():
        if entry.get(key, default) != default:
            problems.add(f"{where}.{key}", entry[key], f"read by the event statistics only, "
                         f"and a study with a plane ({plane}) draws its map alone (each cell "
                         f"run to its own target or cap: map)", f"leave {key} out, or put it "
                         f"in a study without a plane")


def _check_plane_statistics(config, name, entry, problems, plane, grids, ok, two_walls, record):
    """The statistics of a study with a ``plane`` on its noise ``record`` ``(n, dt, tau)``:
    only map figures (Fig. 16 not over a noise parameter), the record long enough for the
    map's cap. Returns its grids or None."""
    where = f"studies.{name}"
    n, dt, tau = record
    if entry.get("spectra"):
        problems.add(f"{where}.spectra", None, f"a study with a plane ({plane}) has no "
                     "spectra: they run at plays of the (1/beta_f, delta) grid (Figs. 6, "
                     "11, 12: a curve per play)", "leave spectra out, or put them in a study "
                     "without a plane at the plane's fixed values")
    if entry.get("escape") and set(plane) & set(NOISE_PARAMETERS):
        problems.add(f"{where}.escape", None, f"the escape runs its own noise levels "
                     f"(escape.rms), and the plane {plane} has the rms as an axis",
                     "leave escape out, or a plane without rms")
        ok = False
    for i, item in enumerate(entry["figures"]):
        fig = item if isinstance(item, str) else item["name"]
        if fig == "fig15_vs_fig16" and set(plane) & set(NOISE_PARAMETERS):
            noise_axis = sorted(set(plane) & set(NOISE_PARAMETERS))[0]
            problems.add(f"{where}.figures[{i}]", fig, f"Fig. 16 is the harmonic-force "
                         f"problem's, which has no {noise_axis} (a parameter of the noise): "
                         f"the plane {plane} has no Fig. 16", ", ".join(PLANE_FIGURES))
            ok = False
        elif fig not in PLANE_FIGURES + ("fig15_vs_fig16",):
            problems.add(f"{where}.figures[{i}]", fig, f"a study with a plane ({plane}) "
                         "draws its map only", ", ".join(PLANE_FIGURES + ("fig15_vs_fig16",)))
            ok = False
    _check_motions(where, entry, two_walls, problems)
    if entry.get("attractors"):
        ok &= _check_plane_attractors(where, entry, plane, grids, problems)
    transient = float(entry["transient"])
    if transient >= tau:
        problems.add(f"{where}.transient", transient, "leaves no record for the statistics "
                     f"(the record of noises.{entry['noise']} ends at tau = {tau:.6g})",
                     f"0 <= transient < {tau:.6g}")
        return None
    if not ok:
        return None
    for key in ("inv_beta", "delta"):
        if key not in grids:
            grids[key] = np.array([float(entry[key])])
    if not _check_forcing_period(where, entry, "inv_beta", grids["inv_beta"], dt, problems):
        return None
    _check_map_record(where, entry, grids["inv_beta"], n, dt, tau, problems)
    for key in plane:
        if grids[key].size < 2:
            problems.add(f"{where}.{key}", entry[key], f"fig15 draws contours over the "
                         f"plane {plane}", "at least 2 values")
    if entry.get("trace"):
        _check_plane_trace(where, entry, plane, grids, dt, tau, problems)
    if entry.get("escape") and not set(plane) & set(NOISE_PARAMETERS):
        amp = grids.get("amplitude")
        harmonic = bool(float(entry["amplitude"])) if amp is None else bool(np.all(amp != 0))
        _check_escape(where, entry, grids, harmonic, dt, problems, axes=plane)
    _check_figures(config, "studies", name, entry, problems, grids)
    return dict(grids, spectra_delta=None)


def _check_plane_attractors(where, entry, plane, grids, problems):
    """A plane study's attractors block: a plane of the harmonic problem (no noise axis), a
    force (amplitude > 0 everywhere), the starts' box on the free side of the wall and within
    the smallest clearance, one-wall closed-form types, a cap long enough to settle at the
    smallest zeta. True when it holds."""
    at = f"{where}.attractors"
    block = entry["attractors"]
    before = len(problems)
    noise_axes = sorted(set(plane) & set(NOISE_PARAMETERS))
    if noise_axes:
        problems.add(at, None, f"basins and Lyapunov exponents are those of the harmonic force "
                     f"alone, which has no {noise_axes[0]} (a parameter of the noise): the plane "
                     f"{plane} has none", "leave attractors out, or a plane over zeta, eps, "
                     "eps_lower, delta, gap, amplitude or inv_beta")
        return False

    def values(key):
        if key in plane:
            return grids.get(key)
        return None if entry.get(key) is None else np.array([float(entry[key])])

    amp = values("amplitude")
    if amp is not None and float(amp.min()) <= 0.0:
        problems.add(f"{where}.amplitude", entry["amplitude"], "the attractors of "
                     "A sin(beta_f tau) are those of sin(beta_f tau) at delta / A for A > 0 "
                     "(A < 0 is a half-period shift, A = 0 has no force)", "amplitude > 0")
    low, high = (float(v) for v in block["gap"])
    if low < 0.0:
        problems.add(f"{at}.gap", block["gap"], f"a distance from the wall of {_num(low)} "
                     "puts starts beyond the wall (x0 = delta - g > delta)",
                     "[low, high] with 0 <= low < high")
    elif not low < high:
        problems.add(f"{at}.gap", block["gap"], "an empty range", "[low, high], low < high")
    clearance = values("gap")
    if clearance is not None and high > float(clearance.min()):
        problems.add(f"{at}.gap", block["gap"], f"starts below the lower wall: the smallest "
                     f"clearance of the plane is gap = {_num(float(clearance.min()))}",
                     f"[low, high] with high <= {_num(float(clearance.min()))}")
    vlow, vhigh = (float(v) for v in block["velocity"])
    if not vlow < vhigh:
        problems.add(f"{at}.velocity", block["velocity"], "an empty range",
                     "[low, high], low < high")
    for j, t in enumerate(block["types"]):
        if len(t) != 2 or not 1 <= int(t[0]) <= MAX_M:
            problems.add(f"{at}.types[{j}]", t, "the attractors match the closed-form "
                         f"solver's (m/n) orbits, m <= {MAX_M} (with a second wall, those that "
                         "stay above it)", f"[m, n] pairs with 1 <= m <= {MAX_M}")
    zeta = values("zeta")
    if zeta is not None:
        shortest = attractor_min_time(float(zeta.min()))
        if float(block["max_time"]) < shortest:
            problems.add(f"{at}.max_time", block["max_time"], f"too short for a start to "
                         f"settle: the damping alone needs ln(1/{ATTRACTOR_MATCH_TOL:g})/zeta "
                         f"= {shortest:.4g} at the plane's smallest zeta",
                         f">= {shortest:.4g}")
    return len(problems) == before


#: Shortest batch of the batch-means standard errors: a natural period 2 pi (time units),
#: the motion's own time scale (shorter batches are not near independent); and 2 samples.
MIN_BATCH_TIME = 2 * math.pi


def _check_batches(where, entry, length, dt, problems, record="transient to t_end",
                   longer="a record (t_end - transient)"):
    """Record a statistics record (``record``, ``length``) too short for its ``n_batches``
    batches, each at least `MIN_BATCH_TIME` and 2 samples long."""
    if length <= 0.0:
        return          # reported as the transient's
    shortest = max(MIN_BATCH_TIME, 2 * dt)
    n_batches = int(entry["n_batches"])
    if length >= n_batches * shortest:
        return
    fits = int(length // shortest)
    allowed_ = (f"n_batches <= {fits}, or " if fits >= 2 else "") + (
        f"{longer} of at least n_batches x {shortest:.4g} = {n_batches * shortest:.4g}")
    problems.add(f"{where}.n_batches", n_batches, f"batches of {length / n_batches:.3g} time "
                 f"units ({length / dt / n_batches:.3g} samples) over the statistics record of "
                 f"{length:.3g} ({record}), shorter than a natural period 2 pi or 2 "
                 f"samples", allowed_)


#: Samples of one escape record, held in memory by its job (8 bytes each: 400 MB).
ESCAPE_MAX_SAMPLES = 50_000_000


#: The schema's default escape cells (``studies.<name>.escape.cells``): [inv_beta, delta].
DEFAULT_ESCAPE_CELLS = [[1.1, 1.0], [1.1, 0.1], [1.2, 2.5]]


def _check_escape(where, entry, grids, harmonic, dt, problems, axes=("inv_beta", "delta")):
    """The escape block: cells inside the study's plane (``axes``: the paper's (1/beta_f,
    delta), or the plane a study names, each cell ``[x, y]`` in its coordinates), distinct
    levels, a record its job can hold, a fit with two levels at least."""
    where = f"{where}.escape"
    block = entry["escape"]
    pair = f"[{axes[0]}, {axes[1]}]"
    plane_words = ("(1/beta_f, delta)" if tuple(axes) == ("inv_beta", "delta")
                   else f"({axes[0]}, {axes[1]})")
    if not harmonic:
        problems.add(where, None, "the escape cells lie in the (1/beta_f, delta) plane of the "
                     "harmonic force, and this study has none (amplitude = 0)",
                     "leave it out, or give the study an amplitude != 0")
        return
    if tuple(axes) != ("inv_beta", "delta") and block["cells"] == DEFAULT_ESCAPE_CELLS:
        # the schema's default cells are [inv_beta, delta] pairs: no cells of this plane
        problems.add(f"{where}.cells", block["cells"], "missing, or the default cells "
                     "(pairs [inv_beta, delta]): a study with a plane names its escape cells "
                     "in its own coordinates", f"cells: a list of {pair} pairs inside the "
                     f"study's {plane_words} plane")
        return
    box = {k: (float(g.min()), float(g.max())) for k, g in grids.items() if g is not None}
    for i, cell in enumerate(block["cells"]):
        values = [float(v) for v in cell]
        bad = [(k, v) for k, v in zip(axes, values) if not _AXIS_BOUNDS[k][0](v)]
        if bad:
            k, v = bad[0]
            if k == "inv_beta":
                problems.add(f"{where}.cells[{i}]", cell, f"1/beta_f = {_num(v)} is not a "
                             "forcing period ratio", f"{pair} with inv_beta > 0")
            else:
                problems.add(f"{where}.cells[{i}]", cell, f"{k} = {_num(v)} is out of its "
                             "range", f"{pair} with {_AXIS_BOUNDS[k][1]}")
            continue
        outside = [f"{k} in [{_num(lo)}, {_num(hi)}]" for k, v in zip(axes, values)
                   if k in box for lo, hi in [box[k]]
                   if not lo - GRID_RTOL * max(1.0, abs(lo)) <= v
                   <= hi + GRID_RTOL * max(1.0, abs(hi))]
        if outside:
            problems.add(f"{where}.cells[{i}]", cell, f"outside the study's {plane_words} "
                         "plane", "a cell with " + " and ".join(outside))
    pairs = [tuple(float(v) for v in c) for c in block["cells"]]
    if len(set(pairs)) != len(pairs):
        problems.add(f"{where}.cells", block["cells"], "a cell is listed twice",
                     f"distinct {pair} pairs")
    _distinct(problems, f"{where}.rms", block["rms"])
    n = escape_samples(entry["transient"], block["record_length"], dt)
    if n > ESCAPE_MAX_SAMPLES:
        problems.add(f"{where}.record_length", block["record_length"],
                     f"{n:,} samples at dt = {_num(dt)}, held in memory by each job",
                     f"transient + record_length <= {_num(ESCAPE_MAX_SAMPLES * dt)}")
    top = block.get("fit_max_rms")
    if top is not None and sum(float(r) <= float(top) for r in block["rms"]) < MIN_FIT_LEVELS:
        problems.add(f"{where}.fit_max_rms", top, f"leaves fewer than {MIN_FIT_LEVELS} noise "
                     "levels for the fits", "null, or at least the third smallest of escape.rms")


def _plane(problems, where, grids, fig):
    """Record a (1/beta_f, delta) plane too small for `fig`'s contours (2 values an axis)."""
    for key in ("inv_beta", "delta"):
        if grids[key] is not None and grids[key].size < 2:
            problems.add(f"{where}.{key}", float(grids[key][0]), f"{fig} draws contours "
                         f"over the (1/beta_f, delta) plane", "at least 2 values")


#: Endings of the datasets an orbits entry derives (results/orbits/<name>_basins.nc ...): an
#: entry named like one would collide with another entry's file.
DERIVED_SUFFIXES = ("_boundaries", "_basins", "_lyapunov")


def _check_orbits(config, name, entry, problems, limits):
    where = f"orbits.{name}"
    if name.endswith(DERIVED_SUFFIXES):
        problems.add(where, name, "ends like a dataset an orbits entry derives "
                     "(results/orbits/<name>_basins.nc ...)",
                     f"a name not ending in {', '.join(DERIVED_SUFFIXES)}")
    _check_laws(where, entry, problems)
    if entry.get("plane"):
        if not _check_orbits_plane(where, entry, problems, limits):
            return
        two_walls = entry.get("gap") is not None
        if shooting(entry):
            _check_shooting_orbits(where, entry, problems)
    else:
        for key in ("zeta", "eps", "eps_lower", "gap", "amplitude", "inv_beta", "delta"):
            fixed_only = key not in ("inv_beta", "delta")
            if isinstance(entry.get(key), (list, dict)) == fixed_only:
                problems.add(f"{where}.{key}", entry[key], "a grid, and this entry has no "
                             "plane naming it" if fixed_only else "a number, and this "
                             "entry has no plane that fixes it", f"a number, or `plane: "
                             f"[{key}, delta]` (say) to map over it" if fixed_only else
                             f"a grid (a list or {{start, stop, step}}), or a `plane` that "
                             f"does not name {key}")
                return
        if entry.get("amplitude") is not None:
            problems.add(f"{where}.amplitude", entry["amplitude"], "the amplitude of an entry "
                         "over the paper's (1/beta_f, delta) plane, whose map is Fig. 16's "
                         "(A = 1)", "leave it out, or give the entry a `plane` (A is then "
                         "fixed or an axis)")
        two_walls = _check_walls(where, entry, problems)
        if shooting(entry):
            _check_shooting_orbits(where, entry, problems)
        grids = {"inv_beta": _grid(problems, f"{where}.inv_beta", entry["inv_beta"],
                                   limits["max_orbit_cells"], positive=True),
                 "delta": _grid(problems, f"{where}.delta", entry["delta"],
                                limits["max_orbit_cells"])}
        if "fig16" in [f if isinstance(f, str) else f["name"] for f in entry["figures"]]:
            _plane(problems, where, grids, "fig16")
    for j, t in enumerate(entry["types"]):
        if len(t) == 3:
            if not two_walls:
                problems.add(f"{where}.types[{j}]", t, "a two-wall type [m_upper, m_lower, n], "
                             "and this entry has one wall (no gap)", "[m, n] pairs, or give "
                             f"{where}.gap > 0")
            continue
        m, n = t
        if two_walls:
            problems.add(f"{where}.types[{j}]", t, "an (m/n) pair in a two-wall entry (the "
                         "shooting solver names a motion by its impacts at each wall)",
                         "[m_upper, m_lower, n] triples, e.g. [1, 1, 1]")
            continue
        if m > MAX_M:
            problems.add(f"{where}.types[{j}]", [m, n], f"the orbit solver finds (m/n) motions "
                         f"with m <= {MAX_M} impacts a period only", f"[m, n] with 1 <= m <= "
                         f"{MAX_M} and 1 <= n <= 12")
    types = [tuple(t) for t in entry["types"]]
    if len(set(types)) != len(types):
        problems.add(f"{where}.types", entry["types"], "a type is listed twice",
                     "distinct [m, n] pairs")
    if entry.get("attractors"):
        _check_attractors(where, entry, problems, limits)
    _check_figures(config, "orbits", name, entry, problems, None)


#: Bounds of an orbits plane's axes (the harmonic-force problem: the amplitude is > 0, the
#: motions at -A being those at A shifted by half a period).
_ORBIT_AXIS_BOUNDS = dict(_AXIS_BOUNDS, amplitude=(lambda v: v > 0.0, "amplitude > 0"))


def _check_orbits_plane(where, entry, problems, limits):
    """An orbits entry with a ``plane``: no noise parameter on it, its axes grids in their
    bounds (at least 2 values), every other parameter a number, no attractors block. False
    when the entry cannot be checked further."""
    plane = list(entry["plane"])
    noise = sorted(set(plane) & set(NOISE_PARAMETERS))
    if noise:
        problems.add(f"{where}.plane", plane, f"names {noise[0]}, a parameter of the random "
                     f"force: the periodic motions of Fig. 16 are those of the harmonic force "
                     f"alone, so a plane over the noise has no Fig. 16",
                     "two of zeta, eps, delta, amplitude, inv_beta (and gap, eps_lower with "
                     "a second wall)")
        return False
    ok = True
    two_walls = "gap" in plane or entry.get("gap") is not None
    if "eps_lower" in plane and not two_walls:
        problems.add(f"{where}.plane", plane, "names eps_lower, the restitution of a second "
                     "wall, and this entry has one wall (no gap)", f"give {where}.gap > 0, or "
                     "a plane without eps_lower")
        ok = False
    for key in plane:
        spec = entry.get(key)
        if not isinstance(spec, (list, dict)):
            problems.add(f"{where}.{key}", spec, f"{'missing' if spec is None else 'a number'}"
                         f", and {key} is an axis of the plane {plane}",
                         "a grid (a list or {start, stop, step})")
            ok = False
            continue
        values = _axis_grid(problems, f"{where}.{key}", spec, limits["max_orbit_cells"],
                            _ORBIT_AXIS_BOUNDS[key])
        if values is None:
            ok = False
        elif values.size < 2:
            problems.add(f"{where}.{key}", spec, f"fig16 draws contours over the plane "
                         f"{plane}", "at least 2 values")
            ok = False
    for key in ("zeta", "eps", "eps_lower", "gap", "amplitude", "inv_beta", "delta"):
        if key in plane or entry.get(key) is None:
            continue
        if isinstance(entry[key], (list, dict)):
            problems.add(f"{where}.{key}", entry[key], f"a grid, and {key} is fixed in the "
                         f"plane {plane} (only the plane's axes are grids)",
                         f"a number, or name {key} in the plane")
            ok = False
        else:
            test, allowed_ = _ORBIT_AXIS_BOUNDS[key]
            if not test(float(entry[key])):
                problems.add(f"{where}.{key}", entry[key], "out of range", allowed_)
                ok = False
    if "gap" not in plane:
        _check_walls(where, entry, problems)
    if entry.get("attractors"):
        # the one orbits entry with them is a one-wall entry over (inv_beta, delta); a study
        # with a plane has them over any plane, with a second wall too
        elsewhere = ("a study with plane: " + str(plane) + " and this gap has them (its "
                     "`attractors` block)" if entry.get("gap") is not None else
                     "an entry over (inv_beta, delta) without a gap has them, and so does a "
                     f"study with plane: {plane}")
        problems.add(f"{where}.attractors", None, f"basins and Lyapunov exponents over the "
                     f"plane {plane} are not a job of an orbits entry", "leave the attractors "
                     f"block out of an entry with a plane; {elsewhere}")
        ok = False
    return ok


#: Periods n the shooting solver's orbit map solves for (its cost grows with n).
MAX_SHOOTING_N = 4


def _check_shooting_orbits(where, entry, problems):
    """An ``orbits`` entry the shooting solver maps (`study.shooting`: a second wall or an
    impact law): types of at most `MAX_SHOOTING_N` periods with an impact, fig16 only (no
    attractors block: its kernels' workflow job knows one wall under Newton's law)."""
    for j, t in enumerate(entry["types"]):
        if len(t) == 3 and not (1 <= t[2] <= MAX_SHOOTING_N and t[0] + t[1] >= 1):
            problems.add(f"{where}.types[{j}]", t, "a two-wall type the shooting map does not "
                         "solve for", f"[m_upper, m_lower, n] with m_upper + m_lower >= 1 and "
                         f"1 <= n <= {MAX_SHOOTING_N}")
        elif len(t) == 2 and not 1 <= t[1] <= MAX_SHOOTING_N:
            problems.add(f"{where}.types[{j}]", t, "a type the shooting map (an entry with an "
                         "impact law) does not solve for", f"[m, n] with 1 <= n <= "
                         f"{MAX_SHOOTING_N}")
    if entry.get("attractors") and entry.get("gap") is not None:
        problems.add(f"{where}.attractors", None, "basins and Lyapunov exponents of a "
                     "two-wall entry are not a workflow job yet", "leave the attractors "
                     "block out of an entry with gap")


def _check_attractors(where, entry, problems, limits):
    """The attractors block of an orbits entry: its grid, a box of starts on the free side of
    the wall, a cap long enough to settle."""
    where = f"{where}.attractors"
    block = entry["attractors"]
    grids = {"inv_beta": _grid(problems, f"{where}.inv_beta", block["inv_beta"],
                               limits["max_orbit_cells"], positive=True),
             "delta": _grid(problems, f"{where}.delta", block["delta"],
                            limits["max_orbit_cells"])}
    if entry.get("figures"):
        for fig in ("basins", "lyapunov"):
            if fig in [f if isinstance(f, str) else f["name"] for f in entry["figures"]]:
                _plane(problems, where, grids, fig)
    low, high = (float(v) for v in block["gap"])
    if low < 0.0:
        problems.add(f"{where}.gap", block["gap"], f"a distance from the wall of {_num(low)} "
                     "puts starts beyond the wall (x0 = delta - g > delta)",
                     "[low, high] with 0 <= low < high")
    elif not low < high:
        problems.add(f"{where}.gap", block["gap"], "an empty range", "[low, high], low < high")
    low, high = (float(v) for v in block["velocity"])
    if not low < high:
        problems.add(f"{where}.velocity", block["velocity"], "an empty range",
                     "[low, high], low < high")
    shortest = attractor_min_time(float(entry["zeta"]))
    if float(block["max_time"]) < shortest:
        problems.add(f"{where}.max_time", block["max_time"],
                     f"too short for a start to settle: the damping alone needs "
                     f"ln(1/{ATTRACTOR_MATCH_TOL:g})/zeta = {shortest:.4g} to bring a "
                     f"perturbation under the matching tolerance {ATTRACTOR_MATCH_TOL:g}",
                     f">= {shortest:.4g} (zeta = {_num(float(entry['zeta']))})")


def _check_paper_figures(config, problems, only=None):
    for fig, name in config["paper_figures"].items():
        if only is not None and fig not in only:
            continue    # the paper's, not built (paper: false): a replaced entry may differ
        section = "orbits" if figures.FIGURES[fig]["owner"] == "orbits" else "studies"
        where = f"paper_figures.{fig}"
        if name not in config[section]:
            problems.add(where, name, f"{fig} is drawn from {section} entries; no such entry",
                         ", ".join(sorted(config[section])))
            continue
        names = [f if isinstance(f, str) else f["name"] for f in config[section][name]["figures"]]
        if names and fig not in names:      # (an empty list is reported with its entry)
            problems.add(where, name, f"{section}.{name} does not list {fig} in its figures",
                         f"an entry listing {fig}, or add {fig} to {section}.{name}.figures")


def check(config, schema, own=None):
    """Check every cross-field relation of ``config``.

    ``config`` has passed `~vibroimpact.pipeline.config.messages.validate` against
    ``schema``; ``own`` is from `~vibroimpact.pipeline.config.layering.compose`.

    Returns
    -------
    dict
        ``{study: {"inv_beta", "delta", "spectra_delta"}}``: each study's grids, expanded
        here once (`pipeline.study.Study.from_config` takes them as ``grids``, so the plan
        and the workflow expand none again).

    Raises
    ------
    ConfigError
        Listing every problem found, one or two lines each.
    """
    limits = config["limits"]
    problems = _Problems()
    _check_noises(config, problems)
    # a random study's inv_beta left out (the schema's default) is not one it ignores
    unforced = schema["$defs"]["study"]["properties"]["inv_beta"]["default"]
    resolved = {}
    for name, entry in config["studies"].items():
        resolved[name] = _check_study(config, name, entry, problems, limits, unforced)
    for name, entry in config["orbits"].items():
        _check_orbits(config, name, entry, problems, limits)
    _check_paper_figures(config, problems, None if own is None else own["paper_figures"])
    if own is not None and not any(own[s] for s in ("studies", "orbits", "paper_figures")):
        problems.add("paper", False, "your file builds nothing of its own",
                     "paper: false with at least one study or orbits entry that lists figures")
    if problems:
        raise ConfigError(problems)
    return resolved
