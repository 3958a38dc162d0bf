"""The site of a SLURM run: the account and the partition its jobs are submitted to.

The SLURM profile (``workflow/profiles/slurm/config.v8+.yaml``) reads both from the
environment, in its ``default-resources``; the Snakefile and ``python -m vibroimpact run``
refuse a run through that profile without them, in one line naming both variables (SLURM
would otherwise pick its default partition and the SLURM plugin guess an account from the
user's last job: a build charged to whatever account that was, on whatever nodes).
"""
import os
from pathlib import Path

__all__ = ["ACCOUNT_ENV", "PARTITION_ENV", "NO_ACCOUNT", "PROFILE", "NUMBA_CPU_NAME",
           "site_problem", "uses_site", "is_slurm_profile", "use_cluster_target"]

#: The account of the jobs (``sbatch -A``); `NO_ACCOUNT` on a cluster that has none.
ACCOUNT_ENV = "VIBROIMPACT_SLURM_ACCOUNT"
#: The partition of the jobs (``sbatch -p``).
PARTITION_ENV = "VIBROIMPACT_SLURM_PARTITION"
#: The account value of a cluster without accounts: no ``-A`` at all.
NO_ACCOUNT = "none"
#: The profile that reads them (from the project's folder).
PROFILE = "workflow/profiles/slurm/config.v8+.yaml"
#: The CPU numba compiles for in a cluster run (``NUMBA_CPU_NAME``). numba keys each cached
#: kernel by the CPU it was compiled for, so on a cluster of mixed CPUs a job on a node of
#: another model than the one that compiled finds no entry and compiles; compiled for
#: ``generic`` (baseline x86-64), one entry serves every node. Measured on this project's
#: 2-core Xeon (host CPU emeraldrapids, AVX-512; `benchmarks/numba_cpu_target.py`, whole
#: process, medians of paired runs, load 4-7): a job whose entry is missing 9.66 CPU-s against
#: 0.91 with it (x10.4: the simulator compiled, 3 runs); the simulator's kernel over 4e6
#: samples x 2 plays, generic against host 0.98 of the CPU (0.85-1.05, 7 pairs) and
#: x86-64-v3 (AVX2) against host 0.92 (0.80-1.03): no loss measured, the recurrence being
#: scalar; results bit-identical (tests/test_slurm.py compares every dataset).
NUMBA_CPU_NAME = "generic"


def site_problem(environ=None):
    """One line naming both variables when either is unset or empty, else None."""
    environ = os.environ if environ is None else environ
    missing = [name for name in (ACCOUNT_ENV, PARTITION_ENV) if not environ.get(name, "").strip()]
    if not missing:
        return None
    return (f"a SLURM run needs its account and partition: {' and '.join(missing)} "
            f"{'is' if len(missing) == 1 else 'are'} not set; export {ACCOUNT_ENV}=<account, "
            f"or {NO_ACCOUNT} on a cluster without accounts> {PARTITION_ENV}=<partition> "
            f"before the run ({PROFILE} reads them)")


def uses_site(default_resources):
    """Whether Snakemake's default resources (``workflow.resource_settings.
    default_resources``: the profile's, as given) read `ACCOUNT_ENV` or `PARTITION_ENV`."""
    if default_resources is None:
        return False
    for _, resource in default_resources.items():
        raw = str(getattr(resource, "raw", resource))
        if ACCOUNT_ENV in raw or PARTITION_ENV in raw:
            return True
    return False


def is_slurm_profile(folder):
    """Whether the Snakemake profile ``folder`` (``--workflow-profile``, ``--profile``)
    reads the SLURM site: its config names `ACCOUNT_ENV` or `PARTITION_ENV`."""
    for name in ("config.v8+.yaml", "config.yaml"):
        path = Path(folder) / name
        if path.is_file():
            text = path.read_text()
            return ACCOUNT_ENV in text or PARTITION_ENV in text
    return False


def use_cluster_target(environ=None):
    """Compile numba's kernels for `NUMBA_CPU_NAME` in this process and every job it submits
    (SLURM passes the submitting environment on), unless ``NUMBA_CPU_NAME`` is set already."""
    environ = os.environ if environ is None else environ
    environ.setdefault("NUMBA_CPU_NAME", NUMBA_CPU_NAME)
