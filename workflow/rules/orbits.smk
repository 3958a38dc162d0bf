rule orbit_tile:
    output:
        "results/orbits/{study}/tiles/{tile}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/orbit_tile/{study}/{tile}.log",
    benchmark:
        "results/benchmarks/orbit_tile/{study}/{tile}.tsv"
    params:
        entry=orbits_entry,
        provenance=orbits_provenance,
    script:
        "../scripts/orbit_tile.py"


rule aggregate_orbits:
    input:
        orbit_tiles,
    output:
        "results/orbits/{study}.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_orbits/{study}.log",
    params:
        provenance=orbits_provenance,
    script:
        "../scripts/aggregate_orbits.py"
