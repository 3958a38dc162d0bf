rule aggregate_events:
    input:
        tiles("events"),
    output:
        "results/datasets/{study}_events.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_events/{study}.log",
    params:
        entry=study_entry,
        provenance=study_provenance,
    script:
        "../scripts/aggregate_events.py"


rule aggregate_spectra:
    input:
        tiles=tiles("spectra"),
        noise=study_noise,
    output:
        "results/datasets/{study}_spectra.nc",
    conda:
        "../envs/vibroimpact.yaml"
    log:
        "results/logs/aggregate_spectra/{study}.log",
    params:
        entry=study_entry,
        provenance=study_provenance,
    script:
        "../scripts/aggregate_spectra.py"
