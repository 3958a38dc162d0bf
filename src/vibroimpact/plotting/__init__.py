"""The paper's figures, one function each: data in, :class:`matplotlib.figure.Figure` out.

Every function takes already opened :class:`xarray.Dataset` objects laid out as in
``docs/datasets.md`` and returns a Figure; none of them touches a file. :func:`save` is the
only writer (the workflow's figure rule calls it). Axis labels come from one vocabulary in
the paper's symbols, `LABELS` (a variable outside it is labelled by its ``long_name`` and
``units``), and headers write the plain names of text stored with the data as symbols
(:func:`symbols`); every density figure follows one sparse-bin rule (`MIN_BIN_COUNT`,
:func:`merge_sparse_bins`) and draws a family of curves with colour, line style and marker
(:func:`family_styles`); the look comes from the one style file
``vibroimpact.mplstyle``, applied by :func:`style`. Every figure prints the parameters it
was computed with (zeta, eps, delta, the input's rms and spectrum, the harmonic forcing).

Datasets and the figures that read them (docs/figures.md)::

    results/noise/{noise}.nc            fig04, fig05           (random)
    results/traces/{study}.nc           fig03, fig10           (random, harmonic)
    results/datasets/{study}_spectra.nc fig06, fig11, fig12    (random, harmonic)
    results/datasets/{study}_events.nc  fig07, fig08, fig09, fig13, fig14
    results/datasets/{study}_map.nc     fig15, fig15_vs_fig16, residence  (harmonic)
                                        map_stack (a sweep's maps over one plane)
    results/datasets/{study}_escape.nc  escape_vs_noise        (harmonic)
    results/orbits/{name}.nc            fig16, fig15_vs_fig16  (orbits), basins (attractors)
    results/orbits/{name}_boundaries.nc fig16                  (orbits)
    results/orbits/{name}_basins.nc     basins                 (attractors)
    results/orbits/{name}_lyapunov.nc   lyapunov               (attractors)
    results/validation/work_precision.nc   work_precision      (validation)
    results/validation/stress_sample.nc    stress              (validation)

A map may run over any two parameters: its dataset names them in
``attrs["axes"]`` (x first) and what it holds fixed in ``attrs["fixed"]`` (JSON); the map
figures read the axes by name, label them from `LABELS` (every parameter's symbol,
`vibroimpact._symbols`) and print the fixed caption. A dataset without ``axes`` is the
paper's (1/beta, delta) plane, drawn as it always was.

Plotting never imports the simulator or the orbit solver; it may use small helpers of
`vibroimpact.stats`.
"""
from vibroimpact.plotting._common import (COLLISION_QUANTITIES, LABELS, MIN_BIN_COUNT,
                                          STYLE_FILE, SYMBOLS, axis_label, bin_counts,
                                          family_styles, merge_sparse_bins, save, style,
                                          symbols)
from vibroimpact.plotting.attractors import basins, lyapunov
from vibroimpact.plotting.escape import escape_vs_noise
from vibroimpact.plotting.harmonic import fig10, fig11, fig12, fig13, fig14
from vibroimpact.plotting.maps import fig15, fig15_vs_fig16, map_agreement, residence
from vibroimpact.plotting.orbits import fig16
from vibroimpact.plotting.planes import map_stack
from vibroimpact.plotting.random import (critical_delta, fig03, fig04, fig05, fig06, fig07,
                                         fig08, fig09)
from vibroimpact.plotting.validation import stress, work_precision

__all__ = [
    "STYLE_FILE", "style", "axis_label", "critical_delta", "save", "LABELS", "MIN_BIN_COUNT",
    "bin_counts", "family_styles", "merge_sparse_bins", "SYMBOLS", "symbols",
    "COLLISION_QUANTITIES",
    "fig03", "fig04", "fig05", "fig06", "fig07", "fig08", "fig09",
    "fig10", "fig11", "fig12", "fig13", "fig14", "fig15", "fig15_vs_fig16", "fig16",
    "map_agreement", "basins", "lyapunov", "work_precision", "stress", "residence",
    "escape_vs_noise", "map_stack",
]
