"""The one optional-matplotlib guard: every figure of the package goes through `pyplot`."""

from __future__ import annotations

import os
import threading
from pathlib import Path

MISSING = "matplotlib is not installed: {what} skipped (pip install 'tribojax[plot]')"
_PRELOAD: list[threading.Thread] = []


def preload_pyplot() -> None:
    """Start importing matplotlib (Agg backend) on a background thread, once per process: a
    command that ends in a figure then does not wait for the import after its computation (the
    import overlaps the compiled work, which runs without the GIL). Silent when matplotlib is
    missing: `pyplot` says so where a figure is asked for."""
    if _PRELOAD:
        return

    def load():
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot  # noqa: F401
        except Exception:  # reported by `pyplot` where a figure is asked for
            pass

    thread = threading.Thread(target=load, name="tribojax-pyplot", daemon=True)
    _PRELOAD.append(thread)
    thread.start()


def pyplot(what: str = "figure", *, files: bool = True):
    """`matplotlib.pyplot`, or None after printing one standard message when it is missing.

    Args:
        what: what is skipped without matplotlib, for the message ("figure", "bar chart").
        files: select the non-interactive Agg backend (the figure is only written to a file).
    """
    for thread in _PRELOAD:  # an import begun by `preload_pyplot` ends first
        thread.join()
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
