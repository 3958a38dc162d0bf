# vibroimpact: regenerate Irie, Yamada & Matsuzaki (1974) figure by figure.
# `snakemake results/figures/fig07.png` builds one figure and only what it needs.
from snakemake.utils import min_version

from vibroimpact.pipeline import config as configuration  # `config`: Snakemake's dict

min_version("9.0")


report: "workflow/report/workflow.rst"


# The paper's config/config.yaml, with the files given by --configfile layered on it (README,
# "Your own studies"). No `configfile:` directive: Snakemake would deep-merge a user's entry
# into a paper entry of the same name; `configuration.load` adds, refuses collisions, and
# checks and costs the whole config here, before any job (a problem: one or two lines each).
try:
    for _file in workflow.overwrite_configfiles:  # what Snakemake's loader lets through:
        configuration.read_yaml(_file)  # a key given twice, nested aliases
    _config, PLAN = configuration.load(dict(config), root=workflow.basedir)
except configuration.ConfigError as err:
    raise configuration.ConfigError(err.problems) from None
config.clear()
config.update(_config)

# The plan, printed only: the recovery after a crash (stale temporaries removed, damaged
# results refused) is `python -m vibroimpact run`'s, so a plain `snakemake -n` or `--lint`
# changes nothing on disk.
if workflow.is_main_process:  # not again in each job of a cluster run
    from snakemake.logging import logger

    logger.info(f"vibroimpact plan: {PLAN.summary(workflow.resource_settings.cores or 1)}")


include: "workflow/rules/common.smk"
include: "workflow/rules/noise.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/aggregate.smk"
include: "workflow/rules/orbits.smk"
include: "workflow/rules/planes.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/sweeps.smk"
include: "workflow/rules/validation.smk"
include: "workflow/rules/reports.smk"


rule all:
    """Every figure and report of the config's built entries."""
    input:
        all_targets(),
    default_target: True
