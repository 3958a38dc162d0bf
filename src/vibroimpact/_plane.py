"""The two parameters a dataset's map runs over, read from its ``axes`` attribute: one reader
for the layers that need it (the orbits at a map's cells, the predictors of P, the figures),
none of which may import another's."""
import json

import numpy as np

__all__ = ["DEFAULT_PLANE", "dataset_axes"]

#: The plane of a map that names none: the paper's Fig. 15 (1/beta_f, delta).
DEFAULT_PLANE = ("inv_beta", "delta")


def dataset_axes(ds):
    """``(x, y)``: ``ds.attrs["axes"]`` (a list, JSON text of one, or names separated by
    spaces), else `DEFAULT_PLANE`; ValueError unless it names two different parameters."""
    axes = ds.attrs.get("axes")
    if axes is None:
        return DEFAULT_PLANE
    if isinstance(axes, (bytes, str)):
        text = axes.decode() if isinstance(axes, bytes) else axes
        if text.lstrip().startswith("["):
            try:
                axes = json.loads(text)
            except ValueError:
                raise ValueError(f"attrs['axes'] must be JSON text, got {text!r}") from None
        else:
            axes = text.split()
    axes = tuple(str(a) for a in np.atleast_1d(axes))
    if len(axes) != 2 or axes[0] == axes[1]:
        raise ValueError(f"attrs['axes'] must name two different parameters, got {axes!r}")
    return axes
