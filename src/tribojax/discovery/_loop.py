"""Loop side of discovery: the Jenkins baseline and the loop effects (issue 6).

Baseline (`loop_baseline`): the Jenkins macroslip element (wu2015 Eq 1) driven through the
record's measured displacement from the first upward mean-crossing (as `fit_loop(...,
model="history")`), μN and K_d fitted as logarithms; the force samples from the first reversal on
are compared. Its physics knobs (null 0) are those of `tribojax._loop_models.loop_force`:

* "microslip" w: force (1 − w)·Jenkins + w·Mindlin (wu2015 Eq 2, same μN and K_d);
* "load_slope" β and "load_curve" γ: N(u) = N0(1 + βu/A + γ(u/A)²), μN ∝ N, K_d ∝ N^0.7616
  (wu2015 Eq 5);
* "viscous" c/c_ref: a force c·u̇, c_ref = (half peak-to-peak force)/(half peak-to-peak velocity);
* "backlash" ε and "log_gap" ln(g/A): a clearance of travel g and depth ε in series with the
  contact (force zero across the gap at ε = 1; `_loop_models`), A the record's half
  peak-to-peak displacement.

Effects (registered for `default_effects("loop")`, names as in the issues): `microslip`,
`viscous_damping`, `normal_load_variation`, `backlash`, and the measurement effect
`force_offset` (a constant added to the force); each moves one knob (or the offset) with a signed
strength, so the null is interior and the Rao score test applies. `backlash` has a nuisance, the
gap g, not identified under the null: a grid of g/A seeds the score (Davies: the largest score,
Bonferroni over the grid) and the refit starts, and the refit fits ln g jointly with ε (as
`stribeck` fits its v_s).

Noise (when the sidecar gives none) and its AR(1) ρ come from differences between cycles: the
steady loop's misfit repeats every period T while the noise does not, so d(t) = r(t) − r(t + T)
(r at t + T linearly interpolated, weight a on the later sample) is noise only. For AR(1) noise
(sd σ, lag-1 correlation ρ) var d = σ²(1 + P + 2Qρ) and cov(d_i, d_i+1) ≈ σ²(ρ(1 + P) +
Q(1 + ρ²)), P = (1 − a)² + a², Q = a(1 − a): ρ̂ solves that ratio = lag-1 autocorrelation of d
(on [0, 0.95]), σ̂ = 1.4826·MAD(d/√(1 + P + 2Qρ̂)). First differences within a cycle (the engine's
default) are biased up by the misfit's own slope at a few hundred samples per cycle. Records with
less than two fitted cycles fall back to the default.

Regions: the abscissa is the displacement u (m) and the segments are the branches (0 =
"unloading", u falling; 1 = "loading", u rising); each flagged region also carries "branch",
"u_min" and "u_max" (m).
"""

from __future__ import annotations

from typing import ClassVar

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._fit._loop import analyse_loop
from .._io._loop import HysteresisLoop
from .._plot import pyplot
from ._core import AbstractBaseline, AbstractEffect, DiscoveryData, EffectDesign, register_effect
from ._discover import DiscoveryReport, discover
from ._loop_models import (
    KD_LOAD_EXPONENT,
    LoopData,
    LoopSpec,
    loop_branch,
    loop_force,
    prepare_loop,
)
from ._regions import RHO_MAX, lag1, noise_estimate

BRANCH_NAMES = {0: "unloading", 1: "loading"}
_KNOBS = ("microslip", "load_slope", "viscous", "backlash", "log_gap", "load_curve",
          "kd_exponent")
GAP_GRID = tuple(np.geomspace(0.02, 1.2, 10).tolist())
"""Seeds of the backlash gap g as a fraction of the record's half peak-to-peak displacement A
(score grid and refit starts; the refit fits g itself)."""


class LoopBaseline(AbstractBaseline):
    """Jenkins element (μN in N, K_d in N/m; θ = their logs) driven by a loop record's
    displacement; knobs (w, β, c/c_ref, ε, ln(g/A)) as in the module docstring."""

    kind: ClassVar[str] = "loop"
    param_names: ClassVar[tuple[str, ...]] = ("mu_N", "K_d")
    param_units: ClassVar[tuple[str, ...]] = ("N", "N/m")
    knob_names: ClassVar[tuple[str, ...]] = _KNOBS
    record: LoopData
    x: Array  # record displacement at the fitted samples, m
    segment: Array  # branch per fitted sample: 0 unloading, 1 loading
    t: Array  # time of the fitted samples, s
    period: Array  # drive period T = 2π/ω from `analyse_loop`, s (inf for a history)
    theta0: Array
    noise: Array  # force-noise sd from the record (N), NaN when unknown (an array leaf, so
    # records of one length share a compiled fit)

    def knob_null(self):
        null = np.zeros(len(_KNOBS))
        null[_KNOBS.index("log_gap")] = np.log(0.1)  # irrelevant while ε = 0
        null[_KNOBS.index("kd_exponent")] = KD_LOAD_EXPONENT  # irrelevant while N(u) = N0
        return null

    def start(self):
        return np.asarray(self.theta0)

    def physical(self, theta):
        return jnp.exp(theta)

    def predict(self, theta, knobs):
        spec = LoopSpec(
            jnp.exp(theta[0]),
            jnp.exp(theta[1]),
            w=knobs[0],
            beta=knobs[1],
            c=knobs[2] * self.record.c_scale,
            depth=knobs[3],
            gap=self.record.A * jnp.exp(knobs[4]),
            gamma=knobs[5],
            kd_exponent=knobs[6],
        )
        return loop_force(spec, self.record, check=False)

    def noise_model(self, r):
        return cycle_noise(r, np.asarray(self.t), float(self.period), np.asarray(self.segment))

    def signals(self):
        return {"u (m)": np.asarray(self.x), "velocity (m/s)": np.asarray(self.record.v),
                "time (s)": np.asarray(self.t)}  # fmt: skip

    def region_info(self, region):
        lo, hi = sorted((region["start"], region["end"]))
        return {"branch": region["segment"], "u_min": lo, "u_max": hi}

    def data(self):
        return DiscoveryData(
            y=np.asarray(self.record.f),
            x=np.asarray(self.x),
            segment=np.asarray(self.segment, dtype=int),
            noise_std=None if np.isnan(float(self.noise)) else float(self.noise),
            x_label="u (m)",
            y_label="force (N)",
            segment_names=dict(BRANCH_NAMES),
        )


def history_start(loop: HysteresisLoop) -> tuple[float, float]:
    """Start (μN in N, K_d in N/m) for a history without whole cycles: μN = half the spread
    between the 1st and 99th percentiles of the force, K_d = μN/(0.05·A) (A = half ptp(u))."""
    mu_N = 0.5 * float(np.diff(np.percentile(loop.f, [1.0, 99.0]))[0])
    return mu_N, mu_N / (0.025 * float(np.ptp(loop.u)))


def loop_baseline(loop: HysteresisLoop) -> LoopBaseline:
    """The Jenkins baseline of a loop record, started from `analyse_loop`'s μN and wu2015 Eq 6
    K_d (a history, `periodic=False`: from `history_start`, with the noise from first
    differences). The force noise sd is the record's `noise_std` (sidecar) or None (estimated)."""
    data = prepare_loop(loop)
    if loop.periodic:
        a = analyse_loop(loop)
        period, start = 2.0 * np.pi / a.omega, (a.mu_N, a.K_d)
    else:  # no period: `cycle_noise` falls back to first differences
        period, start = np.inf, history_start(loop)
    idx = np.asarray(data.index)
    return LoopBaseline(
        record=data,
        x=jnp.asarray(loop.u[idx]),
        segment=jnp.asarray((loop_branch(loop)[idx] > 0).astype(int)),
        t=jnp.asarray(loop.t[idx]),
        period=jnp.asarray(period),
        theta0=jnp.log(jnp.array(start)),
        noise=jnp.asarray(np.nan if loop.noise_std is None else loop.noise_std),
    )


def cycle_noise(r, t, period, segment=None) -> tuple[float, float]:
    """(σ̂, ρ̂) of the noise in a periodic record's residual r(t) from differences between cycles
    (module docstring); falls back to `noise_estimate` with less than two cycles."""
    r, t = np.asarray(r, float), np.asarray(t, float)
    later = t + period
    inside = later <= t[-1]
    if t[-1] - t[0] < 2.0 * period or inside.sum() < 16:
        return noise_estimate(r, segment)
    j = np.clip(np.searchsorted(t, later[inside]) - 1, 0, t.size - 2)
    a = np.clip((later[inside] - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0)
    d = r[inside] - ((1.0 - a) * r[j] + a * r[j + 1])
    # AR(1) noise of sd σ: var d = σ²(1 + P + 2Qρ), cov(d_i, d_i+1) ≈ σ²(ρ(1 + P) + Q(1 + ρ²))
    # with P = (1 − a)² + a², Q = a(1 − a) (the interpolation correlates neighbouring copies)
    P, Q = (1.0 - a) ** 2 + a**2, a * (1.0 - a)
    grid = np.linspace(0.0, RHO_MAX, 951)
    var = 1.0 + P.mean() + 2.0 * Q.mean() * grid
    acf = (grid * (1.0 + P.mean()) + Q.mean() * (1.0 + grid**2)) / var
    rho = float(grid[np.argmin(np.abs(acf - lag1(d)))])
    dn = d / np.sqrt(1.0 + P + 2.0 * Q * rho)
    sigma = 1.4826 * float(np.median(np.abs(dn - np.median(dn))))
    return (sigma if sigma > 0 else float(np.std(dn))), rho


def _knob_design(baseline, knob, names, units, scale):
    gain = np.zeros((len(_KNOBS), 1))
    gain[_KNOBS.index(knob), 0] = 1.0
    return [EffectDesign(names, units, np.atleast_1d(np.asarray(scale, float)), knob_gain=gain)]


@register_effect
class Microslip(AbstractEffect):
    """Partial slip (Mindlin/Koh, wu2015 Eq 2): force (1 − w)·Jenkins + w·Mindlin; w = 0 null,
    w = 1 the full microslip law."""

    name: ClassVar[str] = "microslip"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "partial slip (Mindlin), weight w of the Mindlin law"

    def designs(self, baseline):
        return _knob_design(baseline, "microslip", ("w",), ("1",), 1.0)


@register_effect
class ViscousDamping(AbstractEffect):
    """A force c·u̇ (c in N·s/m) in parallel with the contact; c = 0 null."""

    name: ClassVar[str] = "viscous_damping"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "force proportional to velocity, c·du/dt"

    def designs(self, baseline):
        scale = float(baseline.record.c_scale)
        return _knob_design(baseline, "viscous", ("c",), ("N s/m",), scale)


@register_effect
class NormalLoadVariation(AbstractEffect):
    """Normal load varying with displacement, N(u) = N0(1 + β·u/A) or N0(1 + β·u/A + γ·(u/A)²)
    (`degrees` 1 and 2), μN ∝ N and K_d ∝ N^p with p = 0.7616 (wu2015 Eq 5) or p = 0 (a stiffness
    that does not follow the load, `kd_exponents`); every combination is refitted and the lower
    BIC kept; β = γ = 0 null, p a fixed nuisance of each design.

    The linear term is a tilted counter-face; γ a load that rises (or falls) towards both ends of
    the stroke (a curved or wavy face, a rocking fixture): it is even in u, so the score of the
    linear term alone does not see it (measured on independent loops with N ∝ 1 + γ(u/A)²). With
    p = 0.7616 only, a load gradient at constant stiffness (independent loops, β ≈ 0.18) left
    2.3 noise sd of misfit and a force offset was named first.
    """

    name: ClassVar[str] = "normal_load_variation"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "normal load varying with u: N0(1 + beta u/A + gamma (u/A)^2)"
    degrees: tuple = (1, 2)
    kd_exponents: tuple = (KD_LOAD_EXPONENT, 0.0)
    refit_starts: ClassVar[int] = 4  # every design is refitted (the score cannot choose)

    def designs(self, baseline):
        out = []
        for deg in self.degrees:
            gain = np.zeros((len(_KNOBS), deg))
            for j, knob in enumerate(("load_slope", "load_curve")[:deg]):
                gain[_KNOBS.index(knob), j] = 1.0
            names = ("beta", "gamma")[:deg]
            for p in self.kd_exponents:
                design = EffectDesign(names, ("1",) * deg, np.ones(deg), knob_gain=gain,
                                      knob_set={"kd_exponent": float(p)},
                                      nuisance={"degree": float(deg), "kd_exponent": float(p)})
                out.append(design)  # fmt: skip
        return out


@register_effect
class Backlash(AbstractEffect):
    """A clearance (dead zone) in series with the contact: after each reversal the force falls to
    zero and stays there while the drive crosses the gap g (m), then re-engages (the model in
    `_loop_models`). Strengths: the depth ε (—; 0 none, 1 a clean clearance) and the shift of
    ln g from its seed (g/A on `GAP_GRID`), fitted jointly; the fitted g is reported as the
    nuisance "gap_m"."""

    name: ClassVar[str] = "backlash"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "clearance at reversal: force held at zero across a gap g"
    refit_starts: ClassVar[int] = 2  # the score's best gap can sit far from the refit's

    def designs(self, baseline):
        A = float(baseline.record.A)
        gain = np.zeros((len(_KNOBS), 2))
        gain[_KNOBS.index("backlash"), 0] = gain[_KNOBS.index("log_gap"), 1] = 1.0
        return [EffectDesign(("depth", "log_gap_shift"), ("1", "1"), np.ones(2),
                             knob_gain=gain, knob_set={"log_gap": float(np.log(q))},
                             nuisance={"gap_m": q * A},
                             free=((1, "gap_m", lambda s, g0=q * A: g0 * np.exp(s)),))
                for q in GAP_GRID]  # fmt: skip


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
    plt = pyplot("loop discovery figure")
    if plt is None:
        return False
    u, y = report.x * 1e6, report.y
    k = np.arange(y.size)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), constrained_layout=True)
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
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True
