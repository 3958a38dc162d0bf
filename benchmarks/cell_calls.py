"""A cell of the pipeline called by the signature of the revision imported.

The benchmarks time `vibroimpact.pipeline.cells` functions of this tree and of peer revisions
(a git worktree or archive on ``PYTHONPATH``). The cells take the cell's
:class:`vibroimpact.model.Model`; older revisions took its loose parameters as keywords
(``zeta, eps, delta, amplitude, beta_f``, optionally ``gap, eps_lower``). The benchmarks
keep their cells as those keywords (a map's attributes give them) and call through here.
"""
import inspect

#: The model's keywords among a cell's loose arguments.
PHYSICS = ("zeta", "eps", "amplitude", "gap", "eps_lower")


def call(function, noise, dt, inv_beta, delta, **kw):
    """``function(noise, dt, ...)`` (a map or escape cell) at ``(1/beta_f, delta) = (inv_beta,
    delta)``; ``kw`` holds ``zeta, eps`` (``amplitude`` 1 when left out), optionally ``gap,
    eps_lower``, and the cell's other arguments."""
    if "model" not in inspect.signature(function).parameters:
        return function(noise, dt, beta_f=1.0 / inv_beta, delta=delta, **kw)
    from vibroimpact.model import Model

    physics = {k: kw.pop(k) for k in PHYSICS if k in kw}
    model = Model.paper(physics.pop("zeta"), physics.pop("eps"), delta,
                        physics.pop("amplitude", 1.0), 1.0 / inv_beta, **physics)
    return function(noise, dt, model, **kw)
