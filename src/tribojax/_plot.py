"""The one optional-matplotlib guard: every figure of the package goes through `figure`.

Figures are explicit `matplotlib.figure.Figure` objects, never pyplot ones: the user's backend
and pyplot state (current figure, open-figure list) are untouched.
"""

from __future__ import annotations

import os
from pathlib import Path

MISSING = "matplotlib is not installed: {what} skipped (pip install 'tribojax[plot]')"


def figure(what: str = "figure", **kwargs):
    """A new `matplotlib.figure.Figure(**kwargs)`, or None after printing one standard message
    when matplotlib is missing. No pyplot: the figure is not registered with the user's backend.

    Args:
        what: what is skipped without matplotlib, for the message ("figure", "bar chart").
        **kwargs: passed to `Figure` (figsize, constrained_layout, ...).
    """
    try:
        import matplotlib  # first: the package itself says whether matplotlib is there
        import matplotlib.figure
    except ImportError:
        print(MISSING.format(what=what))
        return None
    return matplotlib.figure.Figure(**kwargs)


def save_figure(fig, path, *, dpi: int = 120) -> None:
    """Write `fig` to `path` (PNG) through a temporary file beside it (its own `savefig`: Agg
    for PNG, whatever the user's backend; pyplot is not involved)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp" + path.suffix)
    try:
        fig.savefig(tmp, dpi=dpi)
        os.replace(tmp, path)
    except OSError as err:  # e.g. a full disk: name the file meant, not the temporary one
        raise OSError(err.errno, err.strerror or str(err), str(path)) from err
    finally:
        tmp.unlink(missing_ok=True)
