"""The package's shape: light imports for jobs that do not simulate, lazy public API."""
import subprocess
import sys

import pytest


def _modules_after(code):
    code += "\nimport sys; print(' '.join(sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return set(out.stdout.split())


@pytest.mark.parametrize("imports", [
    "import vibroimpact",
    # what a figure job and an aggregation job import
    "from vibroimpact.pipeline import tasks; from vibroimpact import plotting",
])
def test_jobs_that_do_not_simulate_do_not_load_numba(imports):
    loaded = _modules_after(imports)
    assert "numba" not in loaded
    assert not {m for m in loaded if m.startswith(("vibroimpact.impact", "vibroimpact.orbit"))}


def test_public_api_is_re_exported_lazily():
    loaded = _modules_after("from vibroimpact import simulate, periodic_orbits\n"
                            "assert simulate.__module__ == 'vibroimpact.impact.simulate'")
    assert "numba" in loaded
    import vibroimpact
    assert {"simulate", "periodic_orbits", "PeriodicOrbit", "orbit_map"} <= set(dir(vibroimpact))
    with pytest.raises(AttributeError, match="no_such_name"):
        vibroimpact.no_such_name  # noqa: B018  (the lookup is the test)


def test_validators_name_the_argument_and_its_range():
    from vibroimpact import _checks

    with pytest.raises(ValueError,
                       match=r"^zeta must be a finite real number in \(0, 1\), got 1.5$"):
        _checks.zeta(1.5)
    with pytest.raises(ValueError, match=r"^n must be an integer >= 1, got 0$"):
        _checks.integer("n", 0, low=1)
    assert _checks.integer("n_samples", 1.0e8, low=0) == 100_000_000
    with pytest.raises(ValueError, match="dt must be a finite real number > 0, got nan"):
        _checks.real("dt", float("nan"), low=0.0, low_open=True)
    with pytest.raises(ValueError, match="got True"):
        _checks.real("delta", True)


def test_loading_a_config_loads_no_numba_scipy_or_kernel():
    # what the Snakefile does at every parse (a dry run, --lint, each job of a cluster run)
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    loaded = _modules_after("from vibroimpact.pipeline import config as configuration\n"
                            f"configuration.load({{}}, root={str(root)!r})")
    assert not {m for m in loaded if m.split(".")[0] in ("numba", "scipy", "llvmlite")}
    assert not {m for m in loaded if m.startswith(("vibroimpact.impact", "vibroimpact.orbits",
                                                   "vibroimpact.noise"))}


def test_the_configs_fir_length_is_the_generators():
    # the config refuses a band_limited record by the FIR length the generator designs,
    # counted without scipy (vibroimpact._limits); scipy's kaiserord is the reference
    import math

    import numpy as np
    import scipy.signal

    from vibroimpact import _limits

    thetas = np.concatenate([np.geomspace(1e-9, 3.0, 3000),
                             math.pi - np.geomspace(1e-12, 0.1, 1000)])
    for theta in map(float, thetas):
        width = min(_limits.FIR_TRANSITION_FRACTION * theta, 2.0 * (math.pi - theta))
        numtaps, _ = scipy.signal.kaiserord(_limits.FIR_ATTENUATION_DB, width / math.pi)
        assert _limits.fir_taps(theta) == numtaps | 1, theta


def test_every_rule_has_a_one_line_docstring():
    from pathlib import Path
    import re

    root = Path(__file__).resolve().parents[1]
    missing = []
    for path in [root / "workflow" / "Snakefile",
                 *sorted((root / "workflow" / "rules").glob("*.smk"))]:
        lines = path.read_text().splitlines()
        for k, line in enumerate(lines):
            rule = re.match(r"^\s*rule (\w+):", line)
            if rule and not re.fullmatch(r'\s+""".+"""', lines[k + 1]):
                missing.append(f"{path.name}: rule {rule[1]}")
    assert not missing
    assert sum(1 for p in (root / "workflow" / "rules").glob("*.smk")
               for line in p.read_text().splitlines() if re.match(r"^\s*rule \w+:", line)) >= 18
