"""Loop side of discovery: the effects of the loop model, registered for
`default_effects("loop")`, each described in its class.

The model is `tribojax._model.LoopBaseline` (the Jenkins element driven through the record's
measured displacement, wu2015 Eq 1; its knobs and their physics: `tribojax._model._loop_force`),
the same model that `fit_loop(model="history")` fits; its noise model is `cycle_noise`.

Regions: the abscissa is the displacement u (m) and the segments are the branches (0 =
"unloading", u falling; 1 = "loading", u rising); each flagged region also carries "branch",
"u_min" and "u_max" (m).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from .._io._loop import HysteresisLoop
from .._model import EffectDesign, knob_design, loop_baseline
from .._model._loop_force import MINDLIN_SHAPE
from .._plot import figure, save_figure
from ._core import AbstractEffect, register_effect
from ._discover import DiscoveryReport, discover
from ._friction_effects import LoadDependence, Viscous

GAP_GRID = tuple(np.geomspace(0.02, 1.2, 10).tolist())
"""Seeds of the backlash gap g as a fraction of the record's half peak-to-peak displacement A
(score grid and refit starts; the refit fits g itself)."""


@register_effect
class Microslip(AbstractEffect):
    """Partial slip (Mindlin/Koh, wu2015 Eq 2): force (1 − w)·Jenkins + w·bank, the bank's virgin
    curve μN[1 − (1 − x/(p·A0))^p]; w = 0 null, w = 1 the full microslip law. Two designs: the
    Mindlin law (p = 3/2, strength w) and p fitted with w (a shift of ln(p − 1), reported as the
    nuisance "shape"): a joint whose slip limits are spread otherwise than Mindlin's (e.g. an Iwan
    bank with uniformly spread limits, p = 2); both are refitted, the lower BIC kept."""

    name: ClassVar[str] = "microslip"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = ("partial slip: weight w of the Mindlin law, or of a law of "
                                  "fitted shape p")
    refit_starts: ClassVar[int] = 2  # both designs

    def designs(self, baseline):
        p0 = MINDLIN_SHAPE
        return [knob_design(baseline, ["microslip"], ("w",), ("1",), 1.0),
                knob_design(baseline, ("microslip", "log_shape"), ("w", "log_shape_shift"),
                            ("1", "1"), np.ones(2), nuisance={"shape": p0},
                            free=((1, "shape", lambda s: 1.0 + (p0 - 1.0) * np.exp(s)),))]


for _effect in (Viscous("loop"), LoadDependence("loop")):
    register_effect(_effect)  # the friction law's effects, written once (`_friction_effects`)


@register_effect
class Backlash(AbstractEffect):
    """A clearance (dead zone) in series with the contact: after each reversal the force falls to
    zero and stays there while the drive crosses the gap g (m), then re-engages (the model in
    `tribojax._model._loop_force`). Strengths: the depth ε (—; 0 none, 1 a clean clearance) and
    the shift of ln g from its seed (g/A on `GAP_GRID`), fitted jointly; the fitted g is
    reported as the nuisance "gap_m"."""

    name: ClassVar[str] = "backlash"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "clearance at reversal: force held at zero across a gap g"
    refit_starts: ClassVar[int] = 2  # the score's best gap can sit far from the refit's

    def designs(self, baseline):
        A = float(baseline.record.A)
        return [knob_design(baseline, ("backlash", "log_gap"), ("depth", "log_gap_shift"),
                            ("1", "1"), np.ones(2), knob_set={"log_gap": float(np.log(q))},
                            nuisance={"gap_m": q * A},
                            free=((1, "gap_m", lambda s, g0=q * A: g0 * np.exp(s)),))
                for q in GAP_GRID]  # fmt: skip


_BAND = {
    "self_energizing": ("energizing", "sigma",
                        "exponential (capstan) rise of the force to slip, exponent sigma"),
    "direction_asymmetry": ("asymmetry", "a",
                            "slip force muN(1 + a) sliding forward, muN(1 - a) backward"),
}  # fmt: skip
"""The band brake's effects: name -> (knob of the loop model, strength, description)."""


class BandBrakeEffect(AbstractEffect):
    """An effect of a band brake's loop (`tribojax.BandBrake`), `name` one of `_BAND`'s: one
    signed strength (0 the null) moving one knob of the loop model, a default candidate only on
    a band brake's records (`LoopBaseline.band_brake`). `self_energizing`: the capstan bend ψ_σ
    of the stick branch; `direction_asymmetry`: slip forces μN(1 ± a), zero force kept at zero
    (unlike `force_offset`); both in the module docstring of `tribojax._model._loop_force`."""

    name: str
    kind: ClassVar[str] = "loop"

    def __check_init__(self):
        if self.name not in _BAND:
            raise ValueError(f"name = {self.name!r}: a band brake effect is one of {sorted(_BAND)}")

    @property
    def description(self) -> str:
        return _BAND[self.name][2]

    def applies(self, baseline):
        return baseline.band_brake

    def designs(self, baseline):
        knob, strength, _ = _BAND[self.name]
        return [knob_design(baseline, [knob], (strength,), ("1",), 1.0)]


for _name in _BAND:
    register_effect(BandBrakeEffect(_name))


@register_effect
class ForceOffset(AbstractEffect):
    """A constant offset f0 (N) of the force reading (a load-cell zero error): additive, f0 = 0
    null."""

    name: ClassVar[str] = "force_offset"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "constant offset of the force reading"

    def designs(self, baseline):
        scale = 0.5 * float(np.ptp(np.asarray(baseline.record.f)))
        ones = np.ones((np.asarray(baseline.record.f).size, 1)) * scale
        return [EffectDesign(("f0",), ("N",), np.array([scale]), basis=ones, columns=ones)]


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
    ax.set(xlabel="sample", ylabel="residual (N)",
           title="residuals; shaded: flagged (orange loading, green unloading)")  # fmt: skip
    ax.legend(fontsize=8)
    fig.suptitle(f"discovery: effect = {report.effect}")
    save_figure(fig, path, dpi=110)
    return True
