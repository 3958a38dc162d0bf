"""Statistics of one parameter cell, computed while the simulation streams.

Each function runs :func:`vibroimpact.simulate_chunks` over a force record and reduces what
the figures need on the fly: impact events for densities and means (no a(tau) recorded),
Welch spectra of a(tau) accumulated segment by segment (no long series kept), or a short
sampled trace. Inputs are arrays or sliceable records; outputs are dicts of numpy values.
"""
import math

import numpy as np

from vibroimpact import stats
from vibroimpact.impact import simulate_chunks

MOTIONS = stats.DEFAULT_MOTIONS


def _record_end(noise, dt, t_end):
    full = (len(noise) - 1) * dt
    return full if t_end is None else min(float(t_end), full)


def event_statistics(noise, dt, *, zeta, eps, delta, amplitude=0.0, beta_f=1.0,
                     transient=0.0, t_end=None, bins, n_batches=stats.DEFAULT_N_BATCHES,
                     motion_window=stats.DEFAULT_MOTION_WINDOW, chunk_size=2**20):
    """Impact statistics of one cell (Figs. 7-9, 13-15).

    Parameters
    ----------
    noise : array_like, shape (N,)
        Random force samples at spacing ``dt``.
    zeta, eps, delta, amplitude, beta_f : float
        Physical parameters (``beta_f``: frequency ratio of ``amplitude * sin(beta_f tau)``).
    transient : float
        Time discarded before statistics (impacts before it are dropped).
    t_end : float, optional
        End of the record used (default: the whole noise record).
    bins : dict
        ``{"v_after": edges, "interval": edges, "ratio": edges}`` histogram bin edges.
    n_batches : int
        Batches for the batch-means standard errors.
    motion_window : float
        Half-width w of the impact-motion classification (FIGURES.md, fig15).

    Returns
    -------
    dict
        Scalars ``n_impacts, impact_rate, simulated_time, v_after_mean, v_after_stderr,
        interval_mean, interval_stderr, contact_fraction, n_chatter`` and arrays
        ``v_after_density(_stderr), interval_density(_stderr), ratio_density`` (on the bins)
        and ``motion_probability`` (one value per motion of ``MOTIONS``).
    """
    t_end = _record_end(noise, dt, t_end)
    if not 0.0 <= transient < t_end:
        raise ValueError(f"transient must lie in [0, t_end = {t_end!r}), got {transient!r}")
    steps, offsets, u_minus = [], [], []
    n_chatter = 0
    contact = 0.0
    for chunk in simulate_chunks(zeta, eps, delta, noise=noise, dt=dt, amplitude=amplitude,
                                 beta=beta_f, t_end=t_end, chunk_size=chunk_size):
        keep = chunk.impact_time >= transient
        steps.append(chunk.impact_step[keep])
        offsets.append(chunk.impact_offset[keep])
        u_minus.append(chunk.impact_velocity[keep])
        n_chatter += chunk.n_chatter
        contact += _clipped_contact(chunk.stick_start, chunk.stick_end, transient)
    steps, offsets, u_minus = (np.concatenate(a) for a in (steps, offsets, u_minus))
    duration = t_end - transient
    v_after = stats.velocity_after_impact(u_minus, eps)
    z = stats.impact_intervals(steps, offsets, dt)
    v_stats = stats.batch_means(v_after, n_batches) if v_after.size else None
    z_stats = stats.batch_means(z, n_batches) if z.size else None
    v_dens = stats.density(v_after, bins["v_after"], total=v_after.size)
    z_dens = stats.density(z, bins["interval"], total=z.size)
    ratio_dens = stats.density(stats.interval_ratio(z, beta_f), bins["ratio"], total=z.size)
    motion = stats.impact_motion_probabilities(z, beta_f, motion_window, total_time=duration,
                                               motions=MOTIONS)
    nan = math.nan
    return dict(
        n_impacts=int(u_minus.size),
        impact_rate=u_minus.size / duration,
        simulated_time=duration,
        v_after_mean=v_stats.mean if v_stats else nan,
        v_after_stderr=v_stats.stderr if v_stats else nan,
        interval_mean=z_stats.mean if z_stats else nan,
        interval_stderr=z_stats.stderr if z_stats else nan,
        contact_fraction=contact / duration,
        n_chatter=int(n_chatter),
        v_after_density=v_dens.density, v_after_density_stderr=v_dens.stderr,
        interval_density=z_dens.density, interval_density_stderr=z_dens.stderr,
        ratio_density=ratio_dens.density,
        motion_probability=np.array(list(motion.values())),   # in the order of MOTIONS
    )


def _clipped_contact(start, end, transient):
    """Time resting on the wall after ``transient``."""
    return float(np.sum(np.clip(end, transient, None) - np.clip(start, transient, None)))


def spectra_statistics(noise, dt, *, zeta, eps, delta, amplitude=0.0, beta_f=1.0,
                       transient=0.0, t_end=None, nperseg=4096, chunk_size=2**20):
    """Welch PSDs of a(tau) and of the total input force for one cell (Figs. 6, 11, 12).

    a(tau) is recorded at every sample and fed segment by segment to a
    :class:`vibroimpact.stats.WelchAccumulator`; nothing longer than a chunk is kept.

    Returns
    -------
    dict
        ``beta`` (>= 0), ``S_a`` and ``S_f`` (paper's two-sided angular convention, eq. 9),
        ``n_segments``.
    """
    t_end = _record_end(noise, dt, t_end)
    skip = int(math.ceil(transient / dt - 1e-9))
    acc_a = stats.WelchAccumulator(dt, nperseg)
    acc_f = stats.WelchAccumulator(dt, nperseg)
    for chunk in simulate_chunks(zeta, eps, delta, noise=noise, dt=dt, amplitude=amplitude,
                                 beta=beta_f, t_end=t_end, record_every=1, chunk_size=chunk_size):
        k = np.rint(chunk.grid_time / dt).astype(np.int64)
        keep = k >= skip
        if not keep.any():
            continue
        k = k[keep]
        acc_a.feed(chunk.a[keep])
        force = np.asarray(noise[k[0] : k[-1] + 1], dtype=float)
        if amplitude != 0.0:
            force = force + amplitude * np.sin(beta_f * dt * k)
        acc_f.feed(force)
    beta, S_a = acc_a.result()
    _, S_f = acc_f.result()
    return dict(beta=beta, S_a=S_a, S_f=S_f, n_segments=acc_a.n_segments)


def trace(noise, dt, *, zeta, eps, delta, amplitude=0.0, beta_f=1.0, t_end):
    """A short sampled record from rest (Figs. 3 and 10): force, a(tau) and impacts."""
    res = next(iter(simulate_chunks(zeta, eps, delta, noise=noise, dt=dt, amplitude=amplitude,
                                    beta=beta_f, t_end=t_end, record_every=1,
                                    chunk_size=int(math.ceil(t_end / dt)) + 1)))
    k = np.rint(res.grid_time / dt).astype(np.int64)
    r = np.asarray(noise[k[0] : k[-1] + 1], dtype=float)
    f = r + amplitude * np.sin(beta_f * res.grid_time)
    return dict(tau=res.grid_time, r=r, f=f, a=res.a, x=delta - res.a,
                impact_time=res.impact_time, impact_velocity=res.impact_velocity)
