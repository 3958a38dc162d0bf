"""A run through the SLURM profile names its account and partition (workflow/profiles/slurm
reads them from the environment), or is refused before any job in one line naming both."""
import os
from pathlib import Path
import subprocess
import sys

from vibroimpact.pipeline import cluster

ROOT = Path(__file__).resolve().parents[1]


def test_a_slurm_run_without_its_site_is_refused_in_one_line(tmp_path):
    """Through the SLURM profile, without the account and partition: Snakemake (a dry run)
    and ``python -m vibroimpact run`` stop before any job with one line naming both
    variables and the profile; with them, the dry run plans the SLURM jobs."""
    env = {k: v for k, v in os.environ.items()
           if k not in (cluster.ACCOUNT_ENV, cluster.PARTITION_ENV)}
    profile = ["--workflow-profile", str(ROOT / "workflow" / "profiles" / "slurm")]
    dry = [sys.executable, "-m", "snakemake", "--snakefile", str(ROOT / "workflow" / "Snakefile"),
           "--directory", str(tmp_path), "-n", *profile, "results/noise/random_input.nc",
           "--configfile", str(ROOT / "config" / "test.yaml")]
    out = subprocess.run(dry, capture_output=True, text=True, env=env, timeout=300)
    assert out.returncode != 0
    lines = [line for line in out.stdout.splitlines() + out.stderr.splitlines()
             if cluster.ACCOUNT_ENV in line]
    assert len(lines) == 1 and cluster.PARTITION_ENV in lines[0] and cluster.PROFILE in lines[0]
    run = subprocess.run([sys.executable, "-m", "vibroimpact", "run", "--directory",
                          str(tmp_path), "--configfile", str(ROOT / "config" / "test.yaml"),
                          *profile, "-n"], capture_output=True, text=True, env=env, timeout=300)
    assert run.returncode == 2
    assert run.stderr.strip().splitlines()[-1] == f"error: {cluster.site_problem({})}"
    assert not (tmp_path / "results").exists()
    env.update({cluster.ACCOUNT_ENV: "myproject", cluster.PARTITION_ENV: "compute"})
    out = subprocess.run(dry, capture_output=True, text=True, env=env, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "slurm_account=myproject" in out.stdout + out.stderr
    assert "slurm_partition=compute" in out.stdout + out.stderr


def test_the_site_problem_names_what_is_missing():
    both = cluster.site_problem({})
    assert cluster.ACCOUNT_ENV in both and cluster.PARTITION_ENV in both and "are" in both
    one = cluster.site_problem({cluster.ACCOUNT_ENV: "none", cluster.PARTITION_ENV: " "})
    assert one.startswith(f"a SLURM run needs its account and partition: "
                          f"{cluster.PARTITION_ENV} is not set")
    assert cluster.site_problem({cluster.ACCOUNT_ENV: "p", cluster.PARTITION_ENV: "q"}) is None
