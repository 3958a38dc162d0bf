"""``vibroimpact`` (the console script) and ``python -m vibroimpact``: plan, run, report,
stale, warm, ``--version`` (`vibroimpact.pipeline.cli`; README)."""
import sys


def main(argv=None):
    """The command line: ``warm`` compiles the kernels (`vibroimpact.warm`, which reaches the
    validation's peers: above the pipeline's layer), everything else is the pipeline's."""
    argv = sys.argv[1:] if argv is None else list(argv)
    command = next((a for a in argv if not a.startswith("-")), None)
    if command == "warm":
        from vibroimpact import warm

        return warm.main(argv[argv.index(command) + 1:])
    from vibroimpact.pipeline.cli import main as pipeline_main

    return pipeline_main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
