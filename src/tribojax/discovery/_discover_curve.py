"""Curve side of discovery: `discover_curve` on a friction curve and its figure; the curve
model's effects are `tribojax._model._effects_curve`'s.
"""

from __future__ import annotations

import numpy as np

from .._io._friction_curve import FrictionCurve
from .._model import curve_baseline, default_effects
from .._plot import figure, save_figure
from ._discover import DiscoveryReport, discover


def discover_curve(curve: FrictionCurve, effects=None, **kw) -> DiscoveryReport:
    """`discover(curve_baseline(curve), effects, **kw)`: the Coulomb + viscous baseline and the
    curve effects (`stribeck`, `asymmetry`, `viscous`, or `effects`) on a friction curve. A curve
    of one direction is not offered `asymmetry` (a level in one direction is F_c itself)."""
    base = curve_baseline(curve)
    if effects is None:
        both = len(np.unique(np.sign(np.asarray(base.v)))) == 2
        effects = [e for e in default_effects("curve") if both or e.name != "asymmetry"]
    return discover(base, effects=effects, **kw)


def plot_curve_discovery(report: DiscoveryReport, curve: FrictionCurve, path) -> bool:
    """Figure of a curve discovery: |friction| against |velocity| per direction (points with their
    standard errors, the Coulomb + viscous baseline, the augmented model), and the residuals
    before and after in units of each point's standard error, flagged regions shaded. PNG at
    `path`; False (nothing written) without matplotlib."""
    fig = figure("curve discovery figure", figsize=(12, 4.5), constrained_layout=True)
    if fig is None:
        return False
    base = curve_baseline(curve)
    w = np.asarray(base.weight)
    v, f = np.asarray(base.v), np.asarray(base.f)
    err = float(base.sigma_bar) / w
    vu, fu = base.units
    axes = fig.subplots(1, 2)
    ax = axes[0]
    label = " + ".join(report.effects) if report.effects else "none added"
    for sign, mk in ((1, "o"), (-1, "s")):
        k = np.sign(v) == sign
        c = "C1" if sign > 0 else "C2"
        name = "positive" if sign > 0 else "negative"
        ax.errorbar(
            np.abs(v[k]), np.abs(f[k]), yerr=err[k], fmt=mk, ms=3, color=c, label=f"data, {name}"
        )
        ax.plot(np.abs(v[k]), np.abs(report.baseline_y[k] / w[k]), "-", color=c, lw=0.8, alpha=0.6)
        ax.plot(np.abs(v[k]), np.abs(report.final_y[k] / w[k]), "--", color=c, lw=1.2)
    ax.plot([], [], "k-", lw=0.8, alpha=0.6, label="baseline (Coulomb + viscous)")
    ax.plot([], [], "k--", lw=1.2, label=f"augmented ({label})")
    ax.set(xlabel=f"|velocity| ({vu})", ylabel=f"|friction| ({fu})", title="steady friction")
    ax.legend(fontsize=8)
    ax = axes[1]
    for rg in report.regions:
        ax.axvspan(rg["start"], rg["end"], color="gold", alpha=0.3, lw=0)
    unit = float(base.sigma_bar)
    ax.plot(v, (report.y - report.baseline_y) / unit, "C0o-", ms=3, lw=0.6, label="baseline")
    ax.plot(v, (report.y - report.final_y) / unit, "C3s-", ms=3, lw=0.6, label="augmented")
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set(
        xlabel=f"velocity ({vu})",
        ylabel="residual / standard error",
        title="residuals; shaded: flagged regions",
    )
    ax.legend(fontsize=8)
    fig.suptitle(f"discovery: effect = {report.effect}, verdict = {report.verdict}")
    save_figure(fig, path, dpi=110)
    return True
