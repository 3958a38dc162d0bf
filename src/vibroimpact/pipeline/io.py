"""Files: atomic netCDF writes, checked reads, the noise record.

A failed or interrupted write never leaves a file under the final name: everything is
written to a temporary name in the same directory and renamed into place on success. A file
that cannot be read (truncated or damaged by something else) gives :class:`CorruptFileError`:
one line naming the file and telling to delete it, never a traceback from HDF5.

Every array variable the pipeline writes carries HDF5's Fletcher-32 checksum of each of its
chunks (:data:`CHECKSUM`): netCDF4 checks it whenever a chunk is read, so damaged data are
refused (:class:`CorruptFileError`) by every reader, never drawn, and :func:`verify` reads
every variable of a file to check all of them (``python -m vibroimpact run`` does that for
every result before a job starts). Scalar variables cannot carry the filter (HDF5 stores them
unchunked), nor can metadata (attributes): these are checked only as far as HDF5 can parse
them. A file written before the checksums (none of its array variables has one) is read
through and accepted: its writer's code digest changed with them, so the build reruns it.
"""
import contextlib
import os
from pathlib import Path

import netCDF4
import numpy as np

from vibroimpact._files import atomic_path
from vibroimpact.pipeline import conventions

__all__ = ["CHECKSUM", "CorruptFileError", "check_readable", "load_dataset", "verify",
           "verify_png", "write_dataset", "write_noise", "noise_spec", "read_noise_attrs",
           "read_input_correlation", "read_noise"]

#: The netCDF4 encoding every variable the pipeline writes gets: a Fletcher-32 checksum of
#: each chunk, checked by the library whenever the chunk is read (scalars: ignored by HDF5).
CHECKSUM = {"fletcher32": True}

#: Elements :func:`verify` reads at a time from one variable (bounds its memory).
VERIFY_BLOCK = 2**22


class CorruptFileError(OSError):
    """A result file that exists but cannot be read; ``str()`` is one line."""

    def __init__(self, path, reason, what="cannot be read as netCDF"):
        reason = (str(reason).strip().splitlines()[-1] if str(reason).strip()
                  else type(reason).__name__)
        super().__init__(f"{path}: {what} ({reason}): the file is truncated "
                         f"or corrupt; delete it and run make (python -m vibroimpact run) "
                         f"again, which rebuilds it (plain snakemake does not: add "
                         f"--forcerun {path})")
        self.path = Path(path)


@contextlib.contextmanager
def _reading(path):
    """Turn a failure to read an existing ``path`` into :class:`CorruptFileError`."""
    try:
        yield
    except FileNotFoundError:
        raise
    except (OSError, RuntimeError, ValueError, KeyError, IndexError) as err:
        if not Path(path).is_file():
            raise
        raise CorruptFileError(path, err) from None


def _open(path):
    with _reading(path):
        return netCDF4.Dataset(os.fspath(path), "r")


def load_dataset(path):
    """``xarray.load_dataset`` of a result file, or :class:`CorruptFileError`."""
    import xarray as xr

    with _reading(path):
        return xr.load_dataset(path, engine="netcdf4")


def _blocks(shape, block=VERIFY_BLOCK):
    """Index tuples covering an array of ``shape`` in slabs of the first axis, each at most
    ``block`` elements (one row at least)."""
    if not shape:
        return [()]
    row = int(np.prod(shape[1:], dtype=np.int64))
    step = max(1, block // max(row, 1))
    return [(slice(i, i + step),) for i in range(0, max(shape[0], 1), step)]


def verify(path):
    """Read every variable of the netCDF file ``path`` through, which checks the Fletcher-32
    checksum of every chunk of those that carry one (:data:`CHECKSUM`).

    Returns
    -------
    bool
        Whether the file carries checksums (some array variable has one); ``False`` for a
        file written before them, which is read through and accepted all the same.

    Raises
    ------
    CorruptFileError
        The file cannot be opened, or a variable's data cannot be read: named, with "fail
        their Fletcher-32 checksum" when it carries one.
    """
    checked = False
    with _open(path) as nc:
        for name, var in nc.variables.items():
            var.set_auto_maskandscale(False)
            summed = bool(var.ndim and var.filters().get("fletcher32"))
            checked |= summed
            try:
                for index in _blocks(var.shape):
                    var[index]
            except (OSError, RuntimeError, ValueError, IndexError) as err:
                what = (f"the data of variable {name} fail their Fletcher-32 checksum" if summed
                        else f"the data of variable {name} cannot be read")
                raise CorruptFileError(path, err, what=what) from None
    return checked


def check_readable(root):
    """:func:`verify` every netCDF file under ``root`` (not the temporaries), and every
    figure's PNG (:func:`verify_png`): a damaged one raises :class:`CorruptFileError` (the
    first one found) before any job would use it, naming the file relative to the working
    directory (the path ``--forcerun`` takes). PDF, HTML and notebook outputs carry no
    checksum of their own, and no job reads them: they are not checked.

    Returns
    -------
    list of str
        The files checked that carry no checksums (written before them).
    """
    root = Path(root)
    if not root.is_dir():
        return []
    unchecked = []
    for path in sorted(root.rglob("*.nc")):
        if path.name.startswith("."):
            continue
        name = os.path.relpath(path)
        if not verify(name):
            unchecked.append(name)
    for path in sorted(root.rglob("*.png")):
        if not path.name.startswith("."):
            verify_png(os.path.relpath(path))
    return unchecked


def verify_png(path):
    """Check the CRC-32 of every chunk of the PNG file ``path`` (the figures, which
    Snakemake's report embeds): :class:`CorruptFileError` naming it when one fails."""
    from PIL import Image

    try:
        with Image.open(path) as image:
            image.verify()
    except FileNotFoundError:
        raise
    except Exception as err:        # Pillow raises SyntaxError, OSError, struct.error ...
        raise CorruptFileError(path, err, what="fails its PNG chunk checks") from None


def write_dataset(ds, path):
    """Write an ``xarray.Dataset`` to netCDF4 atomically, every variable with a Fletcher-32
    checksum (:data:`CHECKSUM`); the encodings the variables bring along (from a file they
    were read from) are kept, but never ``contiguous`` storage, which takes no checksum.

    The file gets the CF global attributes (`conventions.global_attributes`: ``Conventions``,
    ``source``, ``references``, ``history``) besides the dataset's own.

    Raises
    ------
    ValueError
        A variable or coordinate has no ``long_name`` or no ``units``
        (`conventions.missing`): every file the pipeline writes describes each of them.
    """
    lacking = conventions.missing(ds)
    if lacking:
        raise ValueError(f"{path}: every variable needs long_name and units; missing: "
                         + ", ".join(f"{name}.{key}" for name, key in lacking))
    ds = ds.copy(deep=False)          # new Variable objects: the caller's encodings stay
    ds.attrs = {**ds.attrs, **conventions.global_attributes(ds.attrs, path)}
    for var in ds.variables.values():
        encoding = {k: v for k, v in var.encoding.items() if k != "contiguous"}
        var.encoding = {**encoding, **CHECKSUM}
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")


def _var(nc, name, dims, data, long_name, units, dtype="f8"):
    v = nc.createVariable(name, dtype, dims, **CHECKSUM)
    v[:] = data
    v.setncatts(dict(long_name=long_name, units=units))
    return v


def write_noise(path, spec, n_samples, seed, *, attrs, chunk_size=2**20, n_estimate=2**22,
                nperseg=2048, max_lag=30.0):
    """Generate a noise record chunk by chunk into ``path``, with its estimated statistics.

    Parameters
    ----------
    spec : vibroimpact.noise.NoiseSpec
    n_samples, seed : int
    attrs : dict
        Global attributes (provenance).
    n_estimate : int
        Samples (from the start) used for the estimated autocorrelation and PSD.
    nperseg : int
        Welch segment length of the PSD estimate.
    max_lag : float
        Largest lag tau* of the autocorrelation (time units); a record shorter than that
        gives its lags up to its own length, (n_estimate - 1) dt at most.
    """
    from vibroimpact import noise as noise_mod   # scipy.signal: only the noise job needs it

    with atomic_path(path) as tmp:
        nc = netCDF4.Dataset(tmp, "w", format="NETCDF4")
        try:
            nc.createDimension("sample", n_samples)
            r = nc.createVariable("r", "f8", ("sample",), chunksizes=(min(n_samples, 2**18),),
                                  **CHECKSUM)
            r.setncatts(dict(long_name="random force sample r_k = r(k dt)", units="1"))
            head = []
            k = 0
            for chunk in noise_mod.generate(spec, n_samples, seed, chunk_size=chunk_size):
                r[k : k + chunk.size] = chunk
                if k < n_estimate:
                    head.append(chunk[: n_estimate - k])
                k += chunk.size
            head = np.concatenate(head)
            lag, phi = noise_mod.estimate_autocorrelation(
                head, spec.dt, min(max_lag, (head.size - 1) * spec.dt))
            beta, S = noise_mod.estimate_psd(head, spec.dt, min(nperseg, head.size))
            nc.createDimension("lag", lag.size)
            nc.createDimension("beta", beta.size)
            _var(nc, "lag", ("lag",), lag, "time lag tau*", "1")
            _var(nc, "phi_estimate", ("lag",), phi, "autocorrelation phi_f (estimate, eq. 8)", "1")
            _var(nc, "phi_target", ("lag",), spec.autocorrelation(lag),
                 "autocorrelation phi_f (target)", "1")
            _var(nc, "beta", ("beta",), beta, "frequency ratio beta = omega/omega_0", "1")
            _var(nc, "S_estimate", ("beta",), S,
                 "power spectral density S_f (estimate, eq. 9, two-sided)", "1")
            _var(nc, "S_target", ("beta",), spec.psd(beta),
                 "power spectral density S_f (target, two-sided)", "1")
            _var(nc, "S_target_linear", ("beta",), spec.psd_piecewise_linear(beta),
                 "power spectral density of the piecewise-linear force (target)", "1")
            nc.setncatts({**attrs, **{f"noise_{k}": v for k, v in spec.to_attrs().items()},
                          "dt": spec.dt, "seed": int(seed), "n_samples": int(n_samples),
                          **conventions.global_attributes(attrs, path)})
        finally:
            nc.close()


def noise_spec(nc_attrs):
    """The :class:`~vibroimpact.noise.NoiseSpec` stored in a noise file's attributes."""
    from vibroimpact import noise as noise_mod

    keys = ("kind", "rms", "dt", "beta_c", "zeta_f")
    kwargs = {k: nc_attrs[f"noise_{k}"] for k in keys if f"noise_{k}" in nc_attrs}
    for k in ("rms", "dt", "beta_c", "zeta_f"):
        if k in kwargs:
            kwargs[k] = float(kwargs[k])
    return noise_mod.NoiseSpec(**kwargs)


def read_noise_attrs(path):
    """Global attributes of a noise file (its spec, seed and provenance)."""
    with _open(path) as nc:
        return {k: nc.getncattr(k) for k in nc.ncattrs()}


def read_input_correlation(path):
    """``(lag, phi_estimate, phi_target)``: the random input's autocorrelation (eq. 8)."""
    with _open(path) as nc, _reading(path):
        return tuple(np.asarray(nc.variables[k][:]) for k in ("lag", "phi_estimate", "phi_target"))


def read_noise(path, max_in_memory=2**26):
    """Open a noise record: ``(samples, dt, attrs)``.

    Records up to ``max_in_memory`` samples are read into memory once; longer ones are
    returned as the netCDF variable, which the simulator reads chunk by chunk.
    """
    nc = _open(path)
    with _reading(path):
        var = nc.variables["r"]
        var.set_auto_mask(False)
        attrs = {k: nc.getncattr(k) for k in nc.ncattrs()}
        if var.shape[0] <= max_in_memory:
            samples = var[:]
            nc.close()
            return samples, float(attrs["dt"]), attrs
    return var, float(attrs["dt"]), attrs
