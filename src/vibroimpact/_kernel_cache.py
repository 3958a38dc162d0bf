"""numba's ``cache=True`` for kernels spread over several modules, invalidated by any of them.

numba stamps a cached function with the source of its own file only: a kernel compiled with an
inlined helper or a constant from another module keeps the old machine code after an edit of
that module (numba's "cache invalidation" limitation). :func:`kernel_decorator` stamps every
kernel of a package with the sources of all of the package's kernel modules, so that an edit of
any of them recompiles them all on their next call, as an edit of a single kernel file did.

Nothing here imports numba: the decorator is handed numba's ``njit``.
"""
import hashlib
from pathlib import Path

#: The files the compiled impact law is made of (:mod:`vibroimpact._law`), relative to the
#: package's root (``src/vibroimpact``).
LAW_MODULES = ("model.py", "_law.py")

#: The modules each kernel package's compiled kernels are made of (constants and the impact
#: law included), relative to the package's root: the simulator's (``impact``) and the orbit
#: solver's (``orbits``) decorators stamp their kernels with theirs, and a package whose
#: kernels inline both (the attractors) with the two.
KERNEL_MODULES = {
    "impact": tuple(f"impact/{m}" for m in (
        "tolerances.py", "layout.py", "motion.py", "events.py", "stepping.py",
        "parameters.py")) + LAW_MODULES,
    "orbits": tuple(f"orbits/{m}" for m in (
        "tolerances.py", "flight.py", "linalg.py", "newton.py", "solutions.py", "m1.py",
        "intervals.py", "scan_m2.py", "scan_m3.py", "solve.py", "domain_map.py",
        "boundaries_kernels.py")) + LAW_MODULES,
}


def package_modules(*packages):
    """The kernel modules of ``packages`` (keys of :data:`KERNEL_MODULES`) as names relative
    to a module one folder below the root, for :func:`kernel_decorator`'s ``modules``."""
    return tuple(f"../{m}" for package in packages for m in KERNEL_MODULES[package])


def sources_digest(anchor, modules):
    """SHA-256 of the files ``modules`` (names of ``.py`` files beside ``anchor``), in order."""
    folder = Path(anchor).resolve().parent
    digest = hashlib.sha256()
    for name in modules:
        data = (folder / name).read_bytes()
        digest.update(f"{name}\0{len(data)}\0".encode())
        digest.update(data)
    return digest.hexdigest()


def kernel_decorator(njit, anchor, modules, **defaults):
    """A decorator ``kernel`` equal to ``njit(cache=True, **defaults)``, its cache stamped with
    :func:`sources_digest` of ``modules``; ``kernel(**options)`` overrides the defaults.

    Relies on numba's cache internals (``Dispatcher._cache._cache_file._source_stamp``, the
    value checked against the index on every load, numba 0.57 .. 0.68); an upgrade that
    renames them fails here, at import, rather than serving stale machine code
    (tests/test_kernel_cache.py checks the invalidation itself).
    """
    stamp = sources_digest(anchor, modules)

    def stamped(fn, options):
        dispatcher = njit(cache=True, **{**defaults, **options})(fn)
        if dispatcher is fn:            # NUMBA_DISABLE_JIT: plain Python, nothing cached
            return fn
        cache_file = dispatcher._cache._cache_file
        cache_file._source_stamp = (cache_file._source_stamp, stamp)
        return dispatcher

    def kernel(fn=None, **options):
        if fn is None:
            return lambda f: stamped(f, options)
        return stamped(fn, options)

    return kernel
