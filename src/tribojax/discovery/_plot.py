"""The discovery figure: data, baseline, augmented model, residuals before/after, regions."""

from __future__ import annotations

import numpy as np

from .._plot import figure, save_figure


def plot_discovery(report, path) -> bool:
    """Write the figure of a `DiscoveryReport` to `path` (PNG). False if matplotlib is missing.

    Top: data, baseline and final (augmented) model against the record's abscissa. Bottom:
    residuals before and after; flagged regions shaded. When the abscissa is not monotonic
    (loops), the bottom panel uses the sample index and the top panel marks flagged samples.
    """
    fig = figure("discovery figure", figsize=(8, 6.5))
    if fig is None:
        return False
    x, y = np.asarray(report.x), np.asarray(report.y)
    monotonic = bool(np.all(np.diff(x) > 0))
    ax1, ax2 = fig.subplots(2, 1, sharex=monotonic)
    ax1.plot(x, y, ".", ms=2, color="0.4", label="data")
    ax1.plot(x, report.baseline_y, "-", lw=1, color="C0", label="baseline")
    label = "augmented: " + ", ".join(report.effects) if report.effects else "final (= baseline)"
    ax1.plot(x, report.final_y, "--", lw=1, color="C3", label=label)
    ax1.set_ylabel(report.labels.get("y", "y"))
    ax1.legend(fontsize=8)
    xr = x if monotonic else np.arange(x.size)
    ax2.plot(xr, y - report.baseline_y, "-", lw=0.8, color="C0", label="residual, baseline")
    ax2.plot(xr, y - report.final_y, "-", lw=0.8, color="C3", label="residual, augmented")
    for rg in report.regions:
        a, b = rg["i0"], rg["i1"] - 1
        ax2.axvspan(xr[a], xr[b], color="gold", alpha=0.3, lw=0)
        if monotonic:
            ax1.axvspan(xr[a], xr[b], color="gold", alpha=0.3, lw=0)
        else:
            ax1.plot(x[a : b + 1], y[a : b + 1], "-", color="gold", lw=3, alpha=0.6)
    ax2.set_xlabel(report.labels.get("x", "x") if monotonic else "sample")
    ax2.set_ylabel("residual")
    ax2.legend(fontsize=8)
    ax1.set_title(
        f"discovery: {report.effect}; rmse {report.baseline_rmse:.3g} → {report.final_rmse:.3g}"
        f" (flagged regions shaded)",
        fontsize=10,
    )
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    return True


def plot_correction(report, path) -> bool:
    """Figure of the flexible correction of a remaining misfit (`report.misfit["correction"]`):
    final residual against the signal the correction is a function of, with the fitted linear
    spline. Writes `path` (PNG); False if matplotlib is missing or there is no correction."""
    corr = report.misfit.get("correction")
    if not corr:
        return False
    fig = figure("discovery correction figure", figsize=(6.5, 4))
    if fig is None:
        return False
    s = np.asarray(report.signals[corr["signal"]])
    ax = fig.subplots()
    ax.plot(s, report.y - report.final_y, ".", ms=2, color="0.5", label="final residual")
    ax.plot(
        corr["knots"],
        corr["values"],
        "o-",
        color="C3",
        lw=1.5,
        label=f"linear-spline correction: closes {100 * corr['gap_closed']:.0f} % of the excess²",
    )
    ax.set_xlabel(corr["signal"])
    ax.set_ylabel(f"residual ({report.labels.get('y_unit', '')})")
    ax.set_title(f"verdict: {report.verdict}; where the missing term sits", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    return True
