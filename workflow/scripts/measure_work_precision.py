"""Rule measure_work_precision: run time against impact error, the simulator and its peers."""
from vibroimpact.pipeline import io, tasks
from vibroimpact.pipeline.provenance import provenance
from vibroimpact.validation.work_precision import work_precision

with tasks.logged(snakemake.log[0]):
    block = dict(snakemake.params.block)
    ds = work_precision(**block)
    ds.attrs.update(provenance(block, seed=block["seed"]))
    io.write_dataset(ds, snakemake.output[0])
