"""Loop side of discovery: `discover_loop` on a hysteresis loop or history and its figure; the
loop model's effects are `tribojax._model._effects_loop`'s.

Regions: the abscissa is the displacement u (m) and the segments are the branches (0 =
"unloading", u falling; 1 = "loading", u rising); each flagged region also carries "branch",
"u_min" and "u_max" (m).
"""

from __future__ import annotations

import numpy as np

from .._io._hysteresis_loop import HysteresisLoop
from .._model import loop_baseline
from .._plot import figure, save_figure
from ._discover import DiscoveryReport, discover


def discover_loop(loop: HysteresisLoop, effects=None, **kw) -> DiscoveryReport:
    """`discover(loop_baseline(loop), effects, **kw)`: the Jenkins baseline and the loop effects
    (or `effects`) on a loop record; each region carries "branch", "u_min", "u_max" (m)."""
    if not isinstance(loop, HysteresisLoop):
        raise ValueError(f"loop must be a HysteresisLoop record, got {type(loop).__name__}")
    return discover(loop_baseline(loop), effects=effects, **kw)


def plot_loop_discovery(report: DiscoveryReport, path) -> bool:
    """Figure of a loop discovery: force against displacement (data, Jenkins baseline, augmented
    model), and the residuals before and after against sample number with the flagged regions
    shaded (one colour per branch). PNG at `path`; False (nothing written) without matplotlib."""
    fig = figure("loop discovery figure", figsize=(12, 4.5), constrained_layout=True)
    if fig is None:
        return False
    u, y = report.x * 1e6, report.y
    k = np.arange(y.size)
    axes = fig.subplots(1, 2)
    ax = axes[0]
    ax.plot(u, y, ".", ms=2, color="0.5", label="data")
    ax.plot(u, report.baseline_y, "C0-", lw=1, label="baseline (Jenkins)")
    label = " + ".join(report.effects) if report.effects else "none added"
    ax.plot(u, report.final_y, "C3-", lw=1, label=f"augmented ({label})")
    ax.set(xlabel="u (µm)", ylabel="force (N)", title="loop")
    ax.legend(fontsize=8)
    ax = axes[1]
    colours = {"loading": "C1", "unloading": "C2"}
    for rg in report.regions:
        ax.axvspan(rg["i0"], rg["i1"] - 1, color=colours.get(rg["branch"], "C4"), alpha=0.2, lw=0)
    before, after = report.baseline_rmse, report.final_rmse
    ax.plot(k, y - report.baseline_y, "C0.", ms=2, label=f"before: RMS {before:.3g} N")
    ax.plot(k, y - report.final_y, "C3.", ms=2, label=f"after: RMS {after:.3g} N")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(
        xlabel="sample",
        ylabel="residual (N)",
        title="residuals; shaded: flagged (orange loading, green unloading)",
    )
    ax.legend(fontsize=8)
    fig.suptitle(f"discovery: effect = {report.effect}")
    save_figure(fig, path, dpi=110)
    return True
