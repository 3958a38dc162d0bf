"""Rule job_costs: the CPU time, wall time and peak memory of the build's jobs, by rule."""
from vibroimpact.pipeline import tasks
from vibroimpact.reports import run

with tasks.logged(snakemake.log[0]):
    params = snakemake.params
    table = run.rule_costs(params.owners, params.benchmarks, params.planned)
    run.write_rule_costs(table, snakemake.output.html, snakemake.output.tsv)
