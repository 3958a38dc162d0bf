"""``python -m vibroimpact plan|run``: check, plan and build the workflow (README)."""
from vibroimpact.pipeline.cli import main

raise SystemExit(main())
