"""The one optional-matplotlib guard: every figure of the package goes through `pyplot`."""

from __future__ import annotations

import os
from pathlib import Path

MISSING = "matplotlib is not installed: {what} skipped (pip install 'tribojax[plot]')"


def pyplot(what: str = "figure", *, files: bool = True):
    """`matplotlib.pyplot`, or None after printing one standard message when it is missing.

    Args:
        what: what is skipped without matplotlib, for the message ("figure", "bar chart").
        files: select the non-interactive Agg backend (the figure is only written to a file).
    """
    try:
        import matplotlib

        if files:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(MISSING.format(what=what))
        return None
    return plt


def save_figure(fig, path, *, dpi: int = 120) -> None:
    """Write `fig` to `path` (PNG) through a temporary file beside it, then close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp" + path.suffix)
    try:
        fig.savefig(tmp, dpi=dpi)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
        plt.close(fig)
