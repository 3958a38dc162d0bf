"""Stress family ``streamed_record``: a long force record streamed from disk.

A record of ``n_samples`` unit-variance Gaussian force samples (``>= 1e8`` at full size, 800 MB)
is written to a ``.npy`` file block by block and streamed through
:func:`vibroimpact.simulate_chunks` in several chunk sizes, each run in its own Python process
so that its peak resident memory is its own. Nothing is compared with the slow mpmath reference
run over the whole record; the record is checked by

1. invariants, chunk by chunk, on every run: ``a = delta - x >= -A_TOL`` and finite on the
   recorded grid (every ``record_every`` samples), impact instants strictly increasing in full
   precision (``(impact_step, impact_offset)`` lexicographically, and their difference
   ``(s2 - s1) dt + (o2 - o1) > 0``), ``0 <= impact_offset <= dt``, approach velocities finite
   and ``> 0``, sticking intervals ordered and not overlapping, no impact inside one;
2. equality across chunk sizes: impact steps, offsets and velocities, sticking intervals, the
   recorded grid and the final state must be bit-identical to the first chunk size's run
   (the events are streamed to small binary files and compared block by block, so no run's
   impacts are ever all in memory; the grid is compared by a SHA-256 digest);
3. the velocity reset, on a seeded sample of impacts: for impact ``j`` the flight from
   ``x = delta, x' = -eps u_j`` at ``tau_j`` is replayed in closed form by the mpmath
   reference's :class:`~vibroimpact.validation.reference._Flight` (34 digits, shares no code
   with the float64 kernel) over the record's piecewise-linear force. It must stay below
   ``delta + REPLAY_TOL`` until the next reported impact (certified root search,
   ``_smallest_root``) and reach the wall there with the reported approach velocity,
   ``max(|x - delta|, |x' - u_{j+1}|) <= REPLAY_TOL``. A wrong reset (``-u``, ``-eps^2 u``, a
   lost sign) or a missed or spurious impact in between changes the next impact by O(1);
4. memory: the peak resident set of each streaming process (Linux ``VmHWM``) is reported, with
   the same process's peak after its imports and the kernel's JIT load (the baseline); the
   increment must stay below ``RSS_FRACTION`` of the record's bytes.

Why not ``resource.getrusage(...).ru_maxrss``: on Linux a child started by ``subprocess``
(vfork + exec) inherits into ``ru_maxrss``, and into the parent's ``RUSAGE_CHILDREN``, the
peak of the process it was spawned from: a pytest process holding 800 MB makes every child
report 800 MB. ``VmHWM`` in ``/proc/self/status`` belongs to the child's own address space
and is the figure checked (``ru_maxrss`` is kept in the run's result dict, and used off Linux).

Why the record is mapped by hand rather than with ``np.load(mmap_mode="r")``: pages of a file
mapping that have been read stay in the process's resident set (they are page cache, reclaimable,
but counted), so a mapping streamed to the end shows a peak RSS of the whole record.
:class:`MappedRecord` maps the file the same way and drops the pages of the samples already
simulated (``madvise(MADV_DONTNEED)``) after each chunk. Measured on the 1e8 record (chunks of
2**22, grid every 4 samples): peak 989 MB without dropping the pages, 244 MB with (baseline
161 MB); ``np.load(mmap_mode="r")`` with a grid at every sample peaked at 1.22 GB.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import mmap
import os
import shutil
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

from vibroimpact.model import rebound_velocity
from vibroimpact.validation.report import FamilyReport

FAMILY = "streamed_record"

#: Reference chunk size (``simulate``'s default) first, then a prime (its chunk boundaries
#: fall between those of the power-of-two sizes: they share none before 2**20 * 999_983) and
#: a larger power of two (fewer, longer chunks; the largest memory).
DEFAULT_CHUNK_SIZES = (2**20, 999_983, 2**22)

#: Tolerated wall overshoot on the grid, ``a >= -A_TOL``. A recorded sample is the closed-form
#: propagation of the state; its round-off is a few ulp of the largest term (|r| <= 6.1 for
#: 1e8 unit Gaussians, |x|, |x'| <= ~3): ~1e-15 per step. The propagator contracts by
#: exp(-zeta dt) = 0.995 per step, so even errors that all add up saturate at
#: 1e-15 / (1 - 0.995) = 2e-13. A near-grazing sample is at most that far above the wall;
#: anything beyond 1e-12 is a crossing the simulator failed to catch. (The random-parameter
#: stress test uses 1e-9 for noise of rms up to 3, steps of 0.5 and zeta down to 0.005.)
A_TOL = 1e-12

#: Replayed flights: ``max(|x - delta|, |x' - u_{j+1}|)`` at the next reported impact, and the
#: overshoot allowed before it. The simulator's impact times and velocities carry ~1e-13 of
#: round-off (README: errors 2e-12..5e-11 against the exact solution on impact *sequences*);
#: one flight from an exactly reset state does not amplify them (the flight is a linear,
#: damped map), so 1e-9, the repository's tolerance against the reference, is a wide margin;
#: a wrong reset factor is off by O(u) ~ 0.1..1.
REPLAY_TOL = 1e-9

#: Working precision of the replay (decimal digits), as the reference's default.
REPLAY_DPS = 34

#: Limit on the streaming process's growth in resident memory (peak minus its baseline after
#: imports and JIT load) as a fraction of the record's bytes. The growth is chunk-sized, not
#: record-sized: the mapped pages of the chunk being simulated (8 bytes per sample); the
#: recorded grid, which ``simulate_chunks`` holds as a/v buffers, their copies in the result
#: and ``grid_time`` (40 bytes per recorded sample, 48 while ``grid_time`` is built); and the
#: chunk's events (~100 bytes per impact: the kernel's drained buffers, their concatenation,
#: the result). The events are negligible at the defaults (~6e3 impacts per chunk of 2**22)
#: but not everywhere: at delta = -0.5 with 0.3 sin(0.8 tau) a chunk of 2**22 holds 3.4e6
#: events and the growth was ~570 MB. The baseline (~160 MB: numpy, numba, the kernel's
#: machine code) is not the stream's, exceeds 25 % of a 1e8 record on its own, and is
#: reported apart.
RSS_FRACTION = 0.25

#: Below this record size the memory bound is reported but not enforced: the fixed buffers
#: (events, 6 MB) and the chunk dominate a small record.
RSS_MIN_RECORD_BYTES = 2**27

#: Two events of different runs closer than this in time are the same event with different
#: values (counted as an error); farther apart, one is missed or spurious.
MATCH_WINDOW = 1e-6

IMPACT_DTYPE = np.dtype([("step", "<i8"), ("offset", "<f8"), ("u", "<f8")])
STICK_DTYPE = np.dtype([("start", "<f8"), ("end", "<f8")])

_RESULT_MARK = "STREAMED_RECORD_RESULT "
_BLOCK = 1 << 20          # samples / events per block when writing or comparing
_KEEP = 5                 # violations described per run


# ----------------------------------------------------------------------------- the record


def write_record(path, n_samples, seed, block=_BLOCK):
    """Write ``n_samples`` standard normal samples of ``default_rng(seed)`` to a ``.npy`` file.

    Parameters
    ----------
    path : str or Path
        The file to create (overwritten).
    n_samples : int
        Number of samples, ``>= 2``.
    seed : int
        Seed of :func:`numpy.random.default_rng`.
    block : int
        Samples generated and written at a time: the generation's memory is one block.

    Returns
    -------
    int
        Bytes of sample data (the file also holds a header of a few hundred bytes).

    Notes
    -----
    The generator draws the same sequence in blocks as in one call, so the record equals
    ``default_rng(seed).standard_normal(n_samples)``. The header is written by
    :func:`numpy.lib.format.open_memmap` (which only creates a sparse file); the samples are
    written with plain file writes, not through the mapping, whose dirty pages would count in
    the writer's resident memory.
    """
    n_samples = int(n_samples)
    if n_samples < 2:
        raise ValueError(f"n_samples must be >= 2, got {n_samples!r}")
    header = np.lib.format.open_memmap(path, mode="w+", dtype="<f8", shape=(n_samples,))
    offset = header.offset
    del header
    rng = np.random.default_rng(seed)
    buf = np.empty(min(block, n_samples))
    with open(path, "r+b") as f:
        f.seek(offset)
        for k in range(0, n_samples, block):
            part = buf[: min(block, n_samples - k)]
            rng.standard_normal(out=part)
            part.tofile(f)
    return 8 * n_samples


class MappedRecord:
    """A ``.npy`` record of float64 mapped read-only, whose consumed pages can be dropped.

    ``array`` is an ordinary (writeable, copy-on-write, never written) float64 array over the
    mapping, so the kernel sees the same array type as for an in-memory record (a read-only
    array would make numba compile a second specialisation). :meth:`release` tells the kernel
    that samples before ``k`` are no longer needed: their pages leave the resident set and
    would be read again from the page cache if touched, so releasing too much costs time,
    never correctness.

    Parameters
    ----------
    path : str or Path
        A version 1 or 2 ``.npy`` file holding a 1-D little-endian float64 array.
    """

    def __init__(self, path):
        self._file = open(path, "rb")
        try:
            version = np.lib.format.read_magic(self._file)
            read = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                    else np.lib.format.read_array_header_2_0)
            shape, fortran, dtype = read(self._file)
            if len(shape) != 1 or dtype != np.dtype("<f8"):
                raise ValueError(f"{path}: expected a 1-D <f8 array, got shape {shape}, "
                                 f"dtype {dtype}")
            self.offset = self._file.tell()
            self._map = mmap.mmap(self._file.fileno(), 0, access=mmap.ACCESS_COPY)
        except BaseException:
            self._file.close()
            raise
        self.array = np.ndarray(shape, dtype=dtype, buffer=self._map, offset=self.offset)
        self._released = 0
        self._page = mmap.PAGESIZE

    def release(self, k):
        """Drop the resident pages holding samples ``0 .. k-1`` (only whole pages)."""
        end = (self.offset + 8 * int(k)) // self._page * self._page
        if end > self._released and hasattr(self._map, "madvise"):
            self._map.madvise(mmap.MADV_DONTNEED, self._released, end - self._released)
            self._released = end

    def close(self):
        """Unmap the file. Every view of :attr:`array` must be gone by then."""
        self.array = None
        try:
            self._map.close()
        except BufferError:       # a view is still alive: leave the unmapping to the GC
            pass
        self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _peak_rss_kb():
    """(VmHWM, ru_maxrss) of this process in kB; VmHWM is None off Linux."""
    import resource
    hwm = None
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    hwm = int(line.split()[1])
    except OSError:
        pass
    return hwm, int(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)


# ------------------------------------------------------------------- one streaming run


def stream_run(record_path, chunk_size, out_prefix, params, record_every=1, a_tol=A_TOL):
    """Stream the record through ``simulate_chunks`` once, checking invariants chunk by chunk.

    Meant to run in a fresh process (see :func:`main`), so that the reported memory is this
    run's alone.

    Parameters
    ----------
    record_path : str or Path
        The ``.npy`` record.
    chunk_size : int
        ``chunk_size`` passed to :func:`vibroimpact.simulate_chunks`.
    out_prefix : str or Path
        Events are appended to ``<out_prefix>.impacts`` (:data:`IMPACT_DTYPE` rows) and
        ``<out_prefix>.sticks`` (:data:`STICK_DTYPE` rows), for comparison across runs.
    params : dict
        ``zeta, eps, delta, dt, amplitude, beta`` of the simulation.
    record_every : int
        Grid stride of ``a(tau)``; ``>= 1``.
    a_tol : float
        Tolerated overshoot ``-a`` on the grid.

    Returns
    -------
    dict
        Counts, invariant violations (first few described in ``violations``), SHA-256 digests
        of the impact, stick and grid streams, final state, seconds, memory (kB).
    """
    from vibroimpact import simulate, simulate_chunks

    dt = float(params["dt"])
    # load (or compile) the kernel first: its code is part of the baseline, not of the stream
    simulate(**params, noise=np.zeros(8), record_every=1)
    base_hwm, base_maxrss = _peak_rss_kb()
    out = dict(chunk_size=int(chunk_size), n_chunks=0, n_steps=0, n_impacts=0, n_sticks=0,
               n_grid=0, n_chatter=0, contact_time=0.0, n_a_bad=0, n_nonfinite=0,
               n_order_bad=0, n_offset_bad=0, n_u_bad=0, n_stick_bad=0,
               min_a=math.inf, min_a_time=None, min_interval=math.inf, min_u=math.inf,
               violations=[])
    digests = {name: hashlib.sha256() for name in ("impacts", "sticks", "a", "v")}
    prev_step, prev_off, prev_stick_end = None, None, -math.inf

    def violation(text):
        if len(out["violations"]) < _KEEP:
            out["violations"].append(text)

    t0 = time.perf_counter()
    with MappedRecord(record_path) as rec, \
            open(f"{out_prefix}.impacts", "wb") as f_imp, \
            open(f"{out_prefix}.sticks", "wb") as f_stk:
        gen = simulate_chunks(noise=rec.array, record_every=record_every, chunk_size=chunk_size,
                              **params)
        try:
            for res in gen:
                out["n_chunks"] += 1
                out["n_steps"] += res.n_steps
                out["n_chatter"] += res.n_chatter
                out["contact_time"] += res.contact_time

                # grid: finite, a >= -a_tol; a and v hashed as two streams, straight from
                # the result's buffers (no copy: at record_every = 1 a chunk of 2**22
                # samples already holds 160 MB of grid in simulate_chunks)
                digests["a"].update(res.a)
                digests["v"].update(res.v)
                out["n_grid"] += res.a.size
                bad = ~(np.isfinite(res.a) & np.isfinite(res.v))
                if bad.any():
                    out["n_nonfinite"] += int(bad.sum())
                    violation(f"non-finite a or v at tau = {res.grid_time[bad][0]!r}")
                if res.a.size:
                    i = int(np.argmin(res.a))
                    if res.a[i] < out["min_a"]:
                        out["min_a"], out["min_a_time"] = float(res.a[i]), float(res.grid_time[i])
                    n_bad = int(np.count_nonzero(res.a < -a_tol))
                    if n_bad:
                        out["n_a_bad"] += n_bad
                        violation(f"a = {res.a[i]!r} < -{a_tol} at tau = {res.grid_time[i]!r}")

                # impacts: full-precision order (carried over chunk boundaries), offsets, u > 0
                step, off, u = res.impact_step, res.impact_offset, res.impact_velocity
                if step.size:
                    rows = np.empty(step.size, IMPACT_DTYPE)
                    rows["step"], rows["offset"], rows["u"] = step, off, u
                    digests["impacts"].update(rows.tobytes())
                    rows.tofile(f_imp)
                    del rows
                    out["n_impacts"] += step.size
                    ok_u = np.isfinite(u) & (u > 0.0)
                    ok_off = np.isfinite(off) & (off >= 0.0) & (off <= dt)
                    if not ok_u.all():
                        out["n_u_bad"] += int((~ok_u).sum())
                        violation(f"approach velocity {u[~ok_u][0]!r} at step {step[~ok_u][0]}")
                    if not ok_off.all():
                        out["n_offset_bad"] += int((~ok_off).sum())
                        violation(f"offset {off[~ok_off][0]!r} outside [0, dt] at step "
                                  f"{step[~ok_off][0]}")
                    out["min_u"] = min(out["min_u"], float(np.min(u)))
                    s_all = step if prev_step is None else np.concatenate([[prev_step], step])
                    o_all = off if prev_off is None else np.concatenate([[prev_off], off])
                    ds, do = np.diff(s_all), np.diff(o_all)
                    interval = ds * dt + do         # exact integer part, then the offsets
                    lex = (ds > 0) | ((ds == 0) & (do > 0))
                    ok = lex & (interval > 0.0)
                    if interval.size:
                        out["min_interval"] = min(out["min_interval"], float(interval.min()))
                    if not ok.all():
                        out["n_order_bad"] += int((~ok).sum())
                        i = int(np.flatnonzero(~ok)[0])
                        violation(f"impact times not increasing: (step, offset) ({s_all[i]}, "
                                  f"{o_all[i]!r}) then ({s_all[i + 1]}, {o_all[i + 1]!r})")
                    prev_step, prev_off = int(step[-1]), float(off[-1])

                # sticking intervals: start <= end, ordered, disjoint, no impact inside
                if res.stick_start.size:
                    st = np.empty(res.stick_start.size, STICK_DTYPE)
                    st["start"], st["end"] = res.stick_start, res.stick_end
                    digests["sticks"].update(st.tobytes())
                    st.tofile(f_stk)
                    out["n_sticks"] += st.size
                    prev_ends = np.concatenate([[prev_stick_end], res.stick_end[:-1]])
                    ok = (np.isfinite(res.stick_start) & np.isfinite(res.stick_end)
                          & (res.stick_start <= res.stick_end) & (res.stick_start >= prev_ends))
                    if not ok.all():
                        out["n_stick_bad"] += int((~ok).sum())
                        i = int(np.flatnonzero(~ok)[0])
                        violation(f"sticking interval [{res.stick_start[i]!r}, "
                                  f"{res.stick_end[i]!r}] disordered (previous end "
                                  f"{prev_ends[i]!r})")
                    prev_stick_end = float(res.stick_end[-1])
                    del st

                out["final"] = [res.t_end, res.x_end, res.v_end, res.stuck_end]
                rec.release(out["n_steps"])
                # drop the chunk before the generator builds the next (else two are alive)
                del res, step, off, u
        finally:
            gen.close()
            del gen
    out["seconds"] = time.perf_counter() - t0
    hwm, maxrss = _peak_rss_kb()
    out.update(baseline_hwm_kb=base_hwm, peak_hwm_kb=hwm, baseline_maxrss_kb=base_maxrss,
               peak_maxrss_kb=maxrss, digests={k: h.hexdigest() for k, h in digests.items()})
    return out


def main(argv=None):
    """Command line of one streaming run (used by :func:`run_streamed_record`).

    ``python -m vibroimpact.validation.streaming --record R.npy --chunk-size N --out PREFIX
    --params '{"zeta": 0.05, ...}' [--record-every K] [--a-tol X]`` prints one line
    ``STREAMED_RECORD_RESULT {json}`` (with an ``error`` entry and exit status 1 if the
    simulation raised).
    """
    ap = argparse.ArgumentParser(prog="python -m vibroimpact.validation.streaming",
                                 description=main.__doc__)
    ap.add_argument("--record", required=True)
    ap.add_argument("--chunk-size", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--params", required=True,
                    help="JSON dict: zeta, eps, delta, dt, amplitude, beta")
    ap.add_argument("--record-every", type=int, default=1)
    ap.add_argument("--a-tol", type=float, default=A_TOL)
    args = ap.parse_args(argv)
    try:
        result = stream_run(args.record, args.chunk_size, args.out, json.loads(args.params),
                            args.record_every, args.a_tol)
        status = 0
    except Exception as exc:  # reported to the parent, which counts it as an exception
        result = dict(chunk_size=args.chunk_size,
                      error=f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}")
        status = 1
    print(_RESULT_MARK + json.dumps(result), flush=True)
    return status


def _run_child(record, chunk_size, prefix, params, record_every, a_tol, timeout):
    """One streaming run in a fresh interpreter; its result dict (``error`` if it failed)."""
    cmd = [sys.executable, "-m", "vibroimpact.validation.streaming", "--record", str(record),
           "--chunk-size", str(chunk_size), "--out", str(prefix), "--params", json.dumps(params),
           "--record-every", str(record_every), "--a-tol", repr(a_tol)]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return dict(chunk_size=chunk_size, error=f"timed out after {timeout} s")
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith(_RESULT_MARK):
            result = json.loads(line[len(_RESULT_MARK):])
            result["wall_seconds"] = time.perf_counter() - t0
            return result
    return dict(chunk_size=chunk_size,
                error=f"exit status {proc.returncode}, no result; stderr: {proc.stderr[-2000:]}")


# ------------------------------------------------------------------- comparisons


def _read_events(path, dtype):
    """Events of a run as a read-only memmap (an empty array for an empty file)."""
    if os.path.getsize(path) == 0:
        return np.empty(0, dtype)
    return np.memmap(path, dtype=dtype, mode="r")


def _compare_streams(ref, other, dt, kind):
    """Compare two runs' event files block by block.

    Parameters
    ----------
    ref, other : ndarray (memmap) of IMPACT_DTYPE or STICK_DTYPE
    dt : float
    kind : {"impacts", "sticks"}

    Returns
    -------
    dict
        ``matched`` (events paired), ``missed`` (in ``ref`` only), ``spurious`` (in ``other``
        only), ``worst`` (largest difference of a pair: ``max(|dtau|, |du|/u)`` for impacts,
        ``max(|dstart|, |dend|)`` for sticks), ``first`` (description of the first
        difference, or None).

    Notes
    -----
    Identical blocks (the expected case) are compared as bytes. From the first differing
    block on, the two streams are merged in time order: events closer than
    :data:`MATCH_WINDOW` are a pair, otherwise the earlier one is unmatched.
    """
    n, m = len(ref), len(other)
    i = 0
    while i < min(n, m):
        j = min(i + _BLOCK, n, m)
        if ref[i:j].tobytes() != other[i:j].tobytes():
            break
        i = j
    out = dict(matched=i, missed=0, spurious=0, worst=0.0, first=None)
    if i == n == m:
        return out

    def t(rows, p):
        if kind == "impacts":
            return rows["step"][p], rows["offset"][p]
        return 0, rows["start"][p]

    p, q = i, i
    while p < n or q < m:
        if p < n and q < m:
            sa, oa = t(ref, p)
            sb, ob = t(other, q)
            d = (int(sa) - int(sb)) * dt + (float(oa) - float(ob))
        else:
            d = -math.inf if p < n else math.inf
        if abs(d) <= MATCH_WINDOW:
            if kind == "impacts":
                err = max(abs(d),
                          abs(float(ref["u"][p]) - float(other["u"][q])) / float(ref["u"][p]))
            else:
                err = max(abs(d), abs(float(ref["end"][p]) - float(other["end"][q])))
            if out["first"] is None and ref[p].tobytes() != other[q].tobytes():
                out["first"] = f"{kind} #{p}: {ref[p]} vs {other[q]}"
            out["worst"] = max(out["worst"], err)
            out["matched"] += 1
            p, q = p + 1, q + 1
        elif d < 0:
            if out["first"] is None:
                out["first"] = f"{kind} #{p} {ref[p]} missing in the other run"
            out["missed"] += 1
            p += 1
        else:
            if out["first"] is None:
                out["first"] = f"{kind} #{q} {other[q]} of the other run not in the reference run"
            out["spurious"] += 1
            q += 1
    return out


def _impacts_inside_sticks(imp, sticks, dt):
    """Impacts lying inside a sticking interval by more than the interval ends' round-off.

    Returns ``(count, first description or None)``. Stick times are floats ``step dt + offset``
    (absolute error ~ulp(tau)), hence the margin of 8 ulp of the end times.
    """
    if len(imp) == 0 or len(sticks) == 0:
        return 0, None
    start = np.asarray(sticks["start"])
    end = np.asarray(sticks["end"])
    count, first = 0, None
    for i in range(0, len(imp), _BLOCK):
        rows = imp[i : i + _BLOCK]
        tau = rows["step"] * dt + rows["offset"]
        s = np.searchsorted(start, tau, side="right") - 1
        ok = s >= 0
        sc = np.clip(s, 0, None)
        margin = 8.0 * np.spacing(np.maximum(np.abs(end[sc]), 1.0))
        inside = ok & (tau > start[sc] + margin) & (tau < end[sc] - margin)
        if inside.any():
            count += int(inside.sum())
            if first is None:
                k = int(np.flatnonzero(inside)[0])
                first = (f"impact at tau = {tau[k]!r} inside the sticking interval "
                         f"[{start[sc[k]]!r}, {end[sc[k]]!r}]")
    return count, first


# ------------------------------------------------------------------- velocity reset replay


def _replay_flight(record, imp, j, params, tol, dps=REPLAY_DPS):
    """Replay the flight after impact ``j`` in closed form (mpmath reference).

    Returns ``(error, crossing)``: ``error = max(|x - delta|, |x' - u_{j+1}|)`` at the next
    reported impact, and the time at which the flight first rises to ``delta + tol`` before
    it (None if it does not).
    """
    from mpmath import mp, mpf
    from vibroimpact.validation.reference import _Flight, _Params, _smallest_root

    dt = float(params["dt"])
    with mp.workdps(dps):
        args = (params["zeta"], params["eps"])
        harm = (params["amplitude"], params["beta"])
        P = _Params(*args, params["delta"], *harm)
        # the same flight against a wall raised by tol: a root of it is an overshoot > tol
        P_high = _Params(*args, params["delta"], *harm)
        P_high.delta = P.delta + mpf(tol)
        h = mpf(dt)
        k = int(imp["step"][j])
        t = k * h + mpf(float(imp["offset"][j]))
        t_next = int(imp["step"][j + 1]) * h + mpf(float(imp["offset"][j + 1]))
        u_next = mpf(float(imp["u"][j + 1]))
        x, v = P.delta, rebound_velocity(P.eps, mpf(float(imp["u"][j])))   # the reset
        while True:
            tk = k * h
            end = min((k + 1) * h, t_next)
            if end > t:
                r0, r1 = (mpf(float(z)) for z in record[k : k + 2])
                b = (r1 - r0) / h
                fl = _Flight(P_high, t, x, v, r0 + b * (t - tk), b)
                s = _smallest_root(fl.eval, fl.M, mpf(0), end - t)
                if s is not None:
                    return None, float(t + s)
                x, v = fl.state(end - t)
                t = end
            if t >= t_next:
                return float(max(abs(x - P.delta), abs(v - u_next))), None
            k += 1


def _replay_sample(record, imp, sticks, params, n_replay, seed, tol):
    """Replay the flights after a seeded sample of impacts; list of (j, error, crossing).

    Impacts whose next event is a sticking interval (the end of a chatter sequence) are not
    sampled: the flight after them is not a free flight to the next impact.
    """
    n = len(imp)
    if n < 2 or n_replay <= 0:
        return []
    dt = float(params["dt"])
    starts = np.asarray(sticks["start"]) if len(sticks) else np.empty(0)
    rng = np.random.default_rng([int(seed), 0x5EED])
    cand = rng.permutation(n - 1)[: 8 * n_replay]   # a handful more than needed
    out = []
    for j in cand:
        j = int(j)
        t0 = imp["step"][j] * dt + imp["offset"][j]
        t1 = imp["step"][j + 1] * dt + imp["offset"][j + 1]
        lo, hi = np.searchsorted(starts, [t0 - 1e-6, t1], side="left")
        if hi > lo:
            continue
        err, crossing = _replay_flight(record, imp, j, params, tol)
        out.append((j, err, crossing))
        if len(out) >= n_replay:
            break
    return out


# ------------------------------------------------------------------- the family


def run_streamed_record(n_samples: int, seed: int, workdir, chunk_sizes=DEFAULT_CHUNK_SIZES, *,
                        zeta=0.05, eps=0.5, delta=1.5, dt=0.1, amplitude=0.0, beta=1.0,
                        record_every=4, n_replay=64, timeout=1800.0) -> FamilyReport:
    """Write a long record to disk, stream it in several chunk sizes, check and compare.

    Parameters
    ----------
    n_samples : int
        Force samples in the record (``1e8`` at full size: 800 MB, tau = 1e7 at dt = 0.1).
    seed : int
        Seed of the record (:func:`write_record`) and of the replayed impacts' sample.
    workdir : str or Path
        A directory owned by the caller; the record and event files go into a temporary
        subdirectory of it, removed at the end (also on error).
    chunk_sizes : sequence of int
        Chunk sizes, one streaming run each; the first is the reference of the comparison.
        Use at least three, one of them not a power of two.
    zeta, eps, delta, dt, amplitude, beta : float
        The simulation. Defaults: the paper's zeta and eps, no harmonic force, the wall at
        2.1 standard deviations of the linear response (sigma_x = 0.71 for unit samples at
        dt = 0.1): ~1.4e5 impacts per 1e8 samples, a moderate number to compare.
    record_every : int
        Grid stride of the ``a >= -A_TOL`` check. The default 4 checks 2.5e7 samples of a
        1e8 record and keeps the grid's memory (40-48 bytes per recorded sample per chunk,
        see :data:`RSS_FRACTION`) at ~50 MB for chunks of 2**22; with 1 the grid alone takes
        ~200 MB, over the bound. Between grid samples the wall is checked continuously on
        the replayed flights.
    n_replay : int
        Impacts whose following flight is replayed by the mpmath reference.
    timeout : float
        Seconds allowed to each streaming process.

    Returns
    -------
    FamilyReport
        ``cases``: streaming runs; ``compared``: impacts compared bit for bit across chunk
        sizes (sum over the non-reference runs); ``missed`` / ``spurious``: impacts of the
        reference run absent from another run / present only there; ``exceptions``: runs that
        raised, crashed or timed out; ``worst_error``: the largest of the chunk-size
        differences (must be 0), the grid overshoot ``max(0, -min a)`` (limit :data:`A_TOL`)
        and the replay errors (limit :data:`REPLAY_TOL`, the report's ``tolerance``).
        ``extra``: ``peak_rss_mb`` (largest VmHWM of a streaming process), ``record_mb``,
        ``n_impacts``, ``seconds_per_run`` (streaming loop of each run), and
        ``stream_rss_mb`` (peak minus baseline), ``baseline_rss_mb``, ``rss_bound_mb``,
        ``n_sticks``, ``min_a``, ``replayed``, ``replay_worst``.

    Raises
    ------
    OSError
        If ``workdir`` lacks the free space for the record.
    """
    t_start = time.perf_counter()
    chunk_sizes = [int(c) for c in chunk_sizes]
    if not chunk_sizes or min(chunk_sizes) < 1:
        raise ValueError(f"chunk_sizes must be a non-empty sequence of integers >= 1, "
                         f"got {chunk_sizes!r}")
    if int(record_every) < 1:
        raise ValueError(f"record_every must be >= 1 (the grid is checked), got {record_every!r}")
    params = dict(zeta=float(zeta), eps=float(eps), delta=float(delta), dt=float(dt),
                  amplitude=float(amplitude), beta=float(beta))
    report = FamilyReport(FAMILY, tolerance=REPLAY_TOL,
                          measure="max(replay |dx|,|du|; -min a; chunk diff)")
    case = dict(n_samples=int(n_samples), seed=int(seed), record_every=int(record_every), **params)
    record_bytes = 8 * int(n_samples)
    workdir = Path(workdir)
    free = shutil.disk_usage(workdir).free
    if free < record_bytes * 1.1 + 2**26:
        raise OSError(f"{workdir}: {free / 2**20:.0f} MB free, the record needs "
                      f"{record_bytes / 2**20:.0f} MB")
    tmp = Path(tempfile.mkdtemp(prefix="streamed_record_", dir=workdir))
    runs = []
    try:
        record_path = tmp / "record.npy"
        t0 = time.perf_counter()
        write_record(record_path, n_samples, seed)
        report.extra["write_seconds"] = round(time.perf_counter() - t0, 2)
        for c in chunk_sizes:
            report.cases += 1
            res = _run_child(record_path, c, tmp / f"run{c}", params, record_every, A_TOL, timeout)
            runs.append(res)
            if "error" in res:
                report.exceptions += 1
                report.fail(dict(case, chunk_size=c),
                            f"streaming run raised: {res['error'][:1500]}")
                continue
            _check_run(report, res, case, n_samples, record_every)
        good = [r for r in runs if "error" not in r]
        if good:
            _compare_runs(report, good, tmp, params, case)
            ref = good[0]
            imp = _read_events(tmp / f"run{ref['chunk_size']}.impacts", IMPACT_DTYPE)
            sticks = _read_events(tmp / f"run{ref['chunk_size']}.sticks", STICK_DTYPE)
            n_in, first = _impacts_inside_sticks(imp, sticks, params["dt"])
            if n_in:
                report.fail(dict(case, chunk_size=ref["chunk_size"]),
                            f"{n_in} impacts inside sticking intervals; first: {first}")
            record = np.load(record_path, mmap_mode="r")
            t0 = time.perf_counter()
            replays = _replay_sample(record, imp, sticks, params, n_replay, seed, REPLAY_TOL)
            report.extra["replay_seconds"] = round(time.perf_counter() - t0, 2)
            del record, imp, sticks
            replay_worst = 0.0
            for j, err, crossing in replays:
                where = dict(case, check="replay", impact=j)
                if crossing is not None:
                    report.fail(where, f"flight after impact {j} rises above delta + {REPLAY_TOL} "
                                       f"at tau = {crossing!r}, before the next reported impact")
                    continue
                replay_worst = max(replay_worst, err)
                _note(report, 0, err, where)
                if err > REPLAY_TOL:
                    report.fail(where, f"flight after impact {j} reaches the wall off the next "
                                       f"reported impact: max(|dx|, |du|) = {err:.3e}")
            report.extra.update(replayed=len(replays), replay_worst=float(f"{replay_worst:.3e}"))
            _memory(report, good, record_bytes, case)
            report.extra.update(n_impacts=ref["n_impacts"], n_sticks=ref["n_sticks"],
                                min_a=float(f"{min(r['min_a'] for r in good):.3e}"))
        report.extra["seconds_per_run"] = [round(r.get("seconds", math.nan), 2) for r in runs]
        report.extra["chunk_sizes"] = chunk_sizes
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    report.seconds = time.perf_counter() - t_start
    return report


def _note(report, n, err, case):
    """Add ``n`` compared events whose largest error is ``err``."""
    report.compared += n
    if err > report.worst_error or report.worst_case is None:
        report.worst_error = max(report.worst_error, err)
        report.worst_case = case


def _check_run(report, res, case, n_samples, record_every):
    """Fail the report for every invariant a run violated."""
    where = dict(case, chunk_size=res["chunk_size"])
    over = max(0.0, -res["min_a"]) if math.isfinite(res["min_a"]) else 0.0
    if over > report.worst_error:
        report.worst_error, report.worst_case = over, dict(where, check="min a")
    n_grid_expected = (n_samples - 1) // record_every + 1
    problems = [(res["n_a_bad"], f"grid samples with a < -{A_TOL}"),
                (res["n_nonfinite"], "non-finite grid samples"),
                (res["n_order_bad"], "impacts not after their predecessor"),
                (res["n_offset_bad"], "impact offsets outside [0, dt]"),
                (res["n_u_bad"], "approach velocities not finite and > 0"),
                (res["n_stick_bad"], "disordered sticking intervals"),
                (int(res["n_grid"] != n_grid_expected),
                 f"grid of {res['n_grid']} samples, expected {n_grid_expected}"),
                (int(res["n_steps"] != n_samples - 1),
                 f"{res['n_steps']} steps taken, expected {n_samples - 1}")]
    for count, what in problems:
        if count:
            report.fail(where, f"{count} {what}; first: {res['violations'][:2]}")


def _compare_runs(report, runs, tmp, params, case):
    """Compare every run with the first, bit for bit (events, grid digest, final state)."""
    ref = runs[0]
    dt = params["dt"]
    ref_imp = _read_events(tmp / f"run{ref['chunk_size']}.impacts", IMPACT_DTYPE)
    ref_stk = _read_events(tmp / f"run{ref['chunk_size']}.sticks", STICK_DTYPE)
    for run in runs[1:]:
        where = dict(case, chunk_size=run["chunk_size"], reference_chunk_size=ref["chunk_size"])
        imp = _read_events(tmp / f"run{run['chunk_size']}.impacts", IMPACT_DTYPE)
        stk = _read_events(tmp / f"run{run['chunk_size']}.sticks", STICK_DTYPE)
        ci = _compare_streams(ref_imp, imp, dt, "impacts")
        cs = _compare_streams(ref_stk, stk, dt, "sticks")
        del imp, stk
        report.missed += ci["missed"]
        report.spurious += ci["spurious"]
        _note(report, ci["matched"], max(ci["worst"], cs["worst"]),
              dict(where, check="chunk size"))
        if ci["first"] is not None:
            report.fail(where, f"impacts differ across chunk sizes: {ci['missed']} missed, "
                               f"{ci['spurious']} spurious, worst {ci['worst']:.3e}; "
                               f"first: {ci['first']}")
        if cs["first"] is not None:
            report.fail(where, f"sticking intervals differ across chunk sizes: "
                               f"{cs['missed']} missed, {cs['spurious']} spurious, "
                               f"worst {cs['worst']:.3e}; first: {cs['first']}")
        if ((run["digests"]["a"], run["digests"]["v"])
                != (ref["digests"]["a"], ref["digests"]["v"])):
            report.fail(where, "recorded grid a, v differs across chunk sizes (SHA-256)")
        if run["final"] != ref["final"]:
            report.fail(where, f"final state {run['final']} differs from {ref['final']}")
        for name, cmp in (("impacts", ci), ("sticks", cs)):
            # digests (computed while streaming) and files must tell the same story
            same_digest = run["digests"][name] == ref["digests"][name]
            same_file = cmp["first"] is None and cmp["missed"] == cmp["spurious"] == 0
            if same_digest != same_file:
                report.fail(where, f"{name}: digest and event-file comparison disagree")


def _memory(report, runs, record_bytes, case):
    """Put the memory figures into ``report.extra``; fail a large record over the bound."""
    mb = 2.0**-20
    peaks = [(r["peak_hwm_kb"] or r["peak_maxrss_kb"]) * 1024 for r in runs]
    bases = [(r["baseline_hwm_kb"] or r["baseline_maxrss_kb"]) * 1024 for r in runs]
    growth = [p - b for p, b in zip(peaks, bases)]
    bound = RSS_FRACTION * record_bytes
    enforced = record_bytes >= RSS_MIN_RECORD_BYTES
    report.extra.update(
        peak_rss_mb=round(max(peaks) * mb, 1), record_mb=round(record_bytes * mb, 1),
        stream_rss_mb=round(max(growth) * mb, 1), baseline_rss_mb=round(max(bases) * mb, 1),
        rss_bound_mb=round(bound * mb, 1) if enforced else None)
    for r, g in zip(runs, growth):
        if enforced and g > bound:
            report.fail(dict(case, chunk_size=r["chunk_size"]),
                        f"streaming grew the resident set by {g * mb:.0f} MB, over "
                        f"{RSS_FRACTION:.0%} of the {record_bytes * mb:.0f} MB record")


if __name__ == "__main__":
    sys.exit(main())
