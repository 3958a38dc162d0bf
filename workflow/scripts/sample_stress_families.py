"""Rule sample_stress_families: a seeded sample of every stress family."""
from vibroimpact.pipeline import io, tasks
from vibroimpact.pipeline.provenance import provenance
from vibroimpact.validation.campaign import stress_sample

with tasks.logged(snakemake.log[0]):
    block = dict(snakemake.params.block)
    ds = stress_sample(block["seed"], size=block["size"])
    ds.attrs.update(provenance(block, seed=block["seed"]))
    io.write_dataset(ds, snakemake.output[0])
