"""Every job asks a scheduler for at least what it used: the rules' memory and run time
requests (`vibroimpact.pipeline.config.requests`, the plan's cost model of each job's work)
against the peak memory and wall time measured in two builds of different sizes, the default
config and a 4x finer Fig. 15 map (tests/data/job_requests.json, written by
``benchmarks/job_requests.py`` from the builds' benchmark files; nothing is timed here)."""
import json
from pathlib import Path
import re

import pytest

from vibroimpact.pipeline import config as configuration
from vibroimpact.pipeline.config import requests

ROOT = Path(__file__).resolve().parents[1]
MEASURED = json.loads((ROOT / "tests" / "data" / "job_requests.json").read_text())
RULES_TEXT = "".join(p.read_text() for p in sorted((ROOT / "workflow" / "rules").glob("*.smk")))

#: A request holds its job's measured peak resident memory with this much to spare: a
#: job's peak moved by up to ~10 % between builds of one config (the allocator, the order
#: in which numpy frees its temporaries, a threaded tile's threads).
MEM_HEADROOM = 1.2
#: A request holds its job's measured wall time twice over: the builds were measured on a
#: shared 2-core node, where a job's wall time doubles under the load of other builds.
TIME_HEADROOM = 2.0


@pytest.mark.parametrize("size", sorted(MEASURED))
def test_every_job_asks_at_least_what_it_used(size):
    """At each recorded size, every measured job's request at its first attempt holds its
    peak resident memory and its wall time with the headroom above; the retried attempts
    ask twice and three times as much."""
    record = MEASURED[size]
    config, plan = configuration.load(root=ROOT, user_files=record["configfiles"])
    short = []
    for job in record["jobs"]:
        request = requests.job_request(job["rule"], config, plan.studies, job["wildcards"])
        if (MEM_HEADROOM * job["max_rss_mb"] > request.mem_mb
                or TIME_HEADROOM * job["s"] > 60 * request.runtime):
            short.append(f"{job['rule']} {job['wildcards']}: used {job['max_rss_mb']:.0f} MB "
                         f"and {job['s']:.1f} s, asks {request.mem_mb} MB and "
                         f"{request.runtime} min")
        third = requests.job_request(job["rule"], config, plan.studies, job["wildcards"],
                                     attempt=3)
        assert (third.mem_mb, third.runtime) == (3 * request.mem_mb, 3 * request.runtime)
    assert not short, "\n".join(short)


def test_the_measurements_cover_the_submitted_rules_at_two_sizes():
    """Both sizes are recorded, the larger map's predictors used more memory than the
    default's and its request grew with them, and every rule a cluster runs as a SLURM job
    (not a `localrule`) was measured."""
    assert {"default", "fine_map"} <= set(MEASURED)
    jobs = {size: [j for j in MEASURED[size]["jobs"] if j["rule"] == "map_predictors"]
            for size in ("default", "fine_map")}
    peak = {size: max(j["max_rss_mb"] for j in jobs[size]) for size in jobs}
    assert peak["fine_map"] > 1.5 * peak["default"], peak
    asked = {}
    for size in jobs:
        config, plan = configuration.load(root=ROOT, user_files=MEASURED[size]["configfiles"])
        asked[size] = max(requests.job_request("map_predictors", config, plan.studies,
                                               j["wildcards"]).mem_mb for j in jobs[size])
    # the request grows with the map by more than the base: the model, not a constant
    assert asked["fine_map"] - asked["default"] > 0.5 * (peak["fine_map"] - peak["default"])
    local = set(re.findall(r"rule (\w+):\n(?:    .*\n)*?    localrule: True", RULES_TEXT))
    every = set(re.findall(r"^rule (\w+):", RULES_TEXT, re.M))
    assert every == set(requests.RULES)
    measured = {j["rule"] for s in MEASURED.values() for j in s["jobs"]}
    # the two-wall and plane rules are built by config/examples, not by these two sizes
    assert every - local - measured == {"solve_clearance_orbit_tile",
                                        "solve_plane_attractor_tile"}


def test_every_rule_asks_what_the_model_gives_it():
    """Each rule's ``mem_mb`` and ``runtime`` are its own `requests.job_request` (through
    common.smk's `job_mem_mb` and `job_runtime`), not a constant."""
    blocks = re.split(r"^rule ", RULES_TEXT, flags=re.M)[1:]
    for block in blocks:
        name = block.split(":", 1)[0]
        assert f'mem_mb=job_mem_mb("{name}")' in block, name
        assert f'runtime=job_runtime("{name}")' in block, name
