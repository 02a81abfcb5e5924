"""The loop model: a friction element driven through a loop record's measured displacement.

`LoopBaseline` is the Jenkins macroslip element (wu2015 Eq 1; `element="mindlin"`: the Mindlin
microslip law, wu2015 Eq 2, as an Iwan bank) driven through the record's displacement from the
first upward mean-crossing, μN and K_d fitted as logarithms, compared with the force from the
first reversal on (`prepare_loop`); its physics knobs are those of `loop_force` (module docstring
of `_loop_force`). `fit_loop(model="history")` and `discover` fit this one model.

Noise (when the sidecar gives none) and its AR(1) ρ come from differences between cycles
(`cycle_noise`): the steady loop's misfit repeats every period T while the noise does not, so
d(t) = r(t) − r(t + T) (r at t + T linearly interpolated, weight a on the later sample) is noise
only. For AR(1) noise (sd σ, lag-1 correlation ρ) var d = σ²(1 + P + 2Qρ) and cov(d_i, d_i+1) ≈
σ²(ρ(1 + P) + Q(1 + ρ²)), P = (1 − a)² + a², Q = a(1 − a): ρ̂ solves that ratio = lag-1
autocorrelation of d (on [0, 0.95]), σ̂ = 1.4826·MAD(d/√(1 + P + 2Qρ̂)). Records with less than
two fitted cycles fall back to first differences.
"""

from __future__ import annotations

import dataclasses
from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._checks import check_range
from .._export import cached_jit
from .._fit._engine import least_squares_fit
from .._fit._noise import RHO_MAX, lag1, noise_estimate
from .._fit._result import FitResult, thrown
from .._io._hysteresis_loop import HysteresisLoop
from ._base import AbstractBaseline, RecordData
from ._fit import MAX_STEPS, fit_record
from ._loop_analysis import _ELEMENTS, _loop_phase, analyse_loop
from ._loop_force import (
    KD_LOAD_EXPONENT,
    MINDLIN_SHAPE,
    LoopData,
    LoopSpec,
    loop_branch,
    loop_force,
    prepare_loop,
)
from ._residual import evaluate

BRANCH_NAMES = {0: "unloading", 1: "loading"}
LOOP_KNOBS = (
    "microslip",
    "load_slope",
    "viscous",
    "backlash",
    "log_gap",
    "load_curve",
    "kd_exponent",
    "energizing",
    "asymmetry",
    "log_shape",
)


class LoopBaseline(AbstractBaseline):
    """Jenkins element (μN in N, K_d in N/m; θ = their logs) driven by a loop record's
    displacement; knobs (w, β, c/c_ref, ε, ln(g/A), γ, p, σ, a, ln(shape − 1)) as in
    `loop_force`'s module docstring."""

    kind: ClassVar[str] = "loop"
    param_names: ClassVar[tuple[str, ...]] = ("mu_N", "K_d")
    param_units: ClassVar[tuple[str, ...]] = ("N", "N/m")
    knob_names: ClassVar[tuple[str, ...]] = LOOP_KNOBS
    record: LoopData
    x: Array  # record displacement at the fitted samples, m
    segment: Array  # branch per fitted sample: 0 unloading, 1 loading
    t: Array  # time of the fitted samples, s
    period: Array  # drive period T = 2π/ω from `analyse_loop`, s (inf for a history)
    theta0: Array
    noise: Array  # force-noise sd from the record (N), NaN when unknown (an array leaf, so
    # records of one length share a compiled fit)
    element: str = eqx.field(static=True, default="jenkins")  # or "mindlin" (w = 1)
    # a band brake's record (it carries a band tension): the band's effects are candidates
    band_brake: bool = eqx.field(static=True, default=False)
    # the Mindlin bank is computed; False (`for_knobs`: a Jenkins model whose microslip weight
    # w stays 0) drops it: its sliders then carry no force, and one element costs ~1/70 of it
    bank: bool = eqx.field(static=True, default=True)

    def knob_null(self):
        null = np.zeros(len(LOOP_KNOBS))
        null[LOOP_KNOBS.index("log_gap")] = np.log(0.1)  # irrelevant while ε = 0
        null[LOOP_KNOBS.index("kd_exponent")] = KD_LOAD_EXPONENT  # irrelevant while N(u) = N0
        null[LOOP_KNOBS.index("log_shape")] = np.log(MINDLIN_SHAPE - 1.0)  # Mindlin's law
        null[0] = 1.0 if self.element == "mindlin" else 0.0  # the microslip weight w
        return null

    def for_knobs(self, moved):
        if self.element == "jenkins" and not moved[LOOP_KNOBS.index("microslip")]:
            return dataclasses.replace(self, bank=False)
        return self

    def start(self):
        return np.asarray(self.theta0)

    def physical(self, theta):
        return jnp.exp(theta)

    def theta_of(self, values):
        return np.log(np.asarray(values, dtype=float))

    def param_ranges(self):
        """μN and K_d > 0 (θ is their log)."""
        return ((0.0, np.inf), (0.0, np.inf))

    def options(self):
        if self.record.loaded:  # a model fitted from a loaded start predicts from one
            return {"element": self.element, "initial": "measured"}
        return {"element": self.element}

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
            energizing=knobs[7],
            asymmetry=knobs[8],
            shape=1.0 + jnp.exp(knobs[9]),
        )
        return loop_force(spec, self.record, microslip=self.bank, check=False)

    def noise_model(self, r):
        return cycle_noise(r, np.asarray(self.t), float(self.period), np.asarray(self.segment))

    def folds(self):
        """Alternate cycles of a periodic record with at least two (fit on the even cycles,
        score on the odd ones and back: each fold sees every phase, and so a reversal); else
        the default blocks."""
        t, period = np.asarray(self.t), float(self.period)
        if np.isfinite(period) and t[-1] - t[0] >= 1.5 * period:
            return (np.floor((t - t[0]) / period).astype(int)) % 2
        return super().folds()

    def signals(self):
        return {
            "u (m)": np.asarray(self.x),
            "velocity (m/s)": np.asarray(self.record.v),
            "time (s)": np.asarray(self.t),
        }

    def region_info(self, region):
        lo, hi = sorted((region["start"], region["end"]))
        return {"branch": region["segment"], "u_min": lo, "u_max": hi}

    def data(self):
        return RecordData(
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


def loop_baseline(
    loop: HysteresisLoop,
    element: str = "jenkins",
    start=None,
    noise_std=None,
    initial: str = "rest",
) -> LoopBaseline:
    """The model of a loop record (Jenkins, or `element="mindlin"`), started from `start` (μN in
    N, K_d in N/m) or `analyse_loop`'s μN and wu2015 Eq 6 K_d (a history, `periodic=False`:
    `history_start`, the noise from first differences). The force noise sd is `noise_std`, else
    the record's (sidecar), else None (estimated). `initial`: the element starts at "rest" or
    "measured", in the state that carries the record's first measured force (`prepare_loop`)."""
    if element not in ("jenkins", "mindlin"):
        raise ValueError(f"element must be one of ['jenkins', 'mindlin'], got {element!r}")
    data = prepare_loop(loop, initial)
    if loop.periodic:
        a = analyse_loop(loop)
        period, guess = 2.0 * np.pi / a.omega, (a.mu_N, a.K_d)
    else:  # no period: `cycle_noise` falls back to first differences
        period, guess = np.inf, history_start(loop)
    start = guess if start is None else start
    noise = loop.noise_std if noise_std is None else noise_std
    idx = np.asarray(data.index)
    return LoopBaseline(
        record=data,
        x=jnp.asarray(loop.u[idx]),
        segment=jnp.asarray((loop_branch(loop)[idx] > 0).astype(int)),
        t=jnp.asarray(loop.t[idx]),
        period=jnp.asarray(period),
        theta0=jnp.log(jnp.array(start)),
        noise=jnp.asarray(np.nan if noise is None else float(noise)),
        element=element,
        band_brake=loop.band_tension is not None,
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
    P, Q = (1.0 - a) ** 2 + a**2, a * (1.0 - a)
    grid = np.linspace(0.0, RHO_MAX, 951)
    var = 1.0 + P.mean() + 2.0 * Q.mean() * grid
    acf = (grid * (1.0 + P.mean()) + Q.mean() * (1.0 + grid**2)) / var
    rho = float(grid[np.argmin(np.abs(acf - lag1(d)))])
    dn = d / np.sqrt(1.0 + P + 2.0 * Q * rho)
    sigma = 1.4826 * float(np.median(np.abs(dn - np.median(dn))))
    return (sigma if sigma > 0 else float(np.std(dn))), rho


def fit_loop(
    loop: HysteresisLoop,
    element: str = "jenkins",
    *,
    sigma=None,
    window: float = 0.05,
    model: str = "history",
    max_steps=None,
    start=None,
    throw: bool = True,
) -> FitResult:
    """Least-squares fit of μN (N) and K_d (N/m) of a Jenkins or Mindlin element to a loop.

    model="history" (default, as `tribojax fit`): the loop model `LoopBaseline` (the element
    driven through the measured displacement from rest at the first upward mean-crossing of u;
    the samples before the first reversal after it, the virgin loading, are not fitted), the
    same model, residual and solver as `discover`'s loop baseline (`fit_record`). Works for any
    history.
    model="steady": wu2015's steady loop (Eq 1 or 2) at the measured u, on the branch given by
    the phase of u's first harmonic, amplitude A = half the peak-to-peak u (a periodic record).

    Parameters as logarithms, started from `analyse_loop`'s μN and Eq 6 K_d (or `start`, a dict
    {"mu_N": N, "K_d": N/m}); standard errors by the delta method. Only the product μN is
    identifiable from a loop; without gross slip (Jenkins Ā ≤ 1) μN is only bounded below, and
    its standard error is then inf with a `message` saying so.

    Args:
        sigma: force noise sd, N (None: the loop's `noise_std` if set, else estimated).
        window: `analyse_loop`'s slope window; max_steps: the LM step budget (default
            `MAX_STEPS` of the loop model, the budget `discover` uses; 500 for "steady").
    Returns:
        FitResult with names ("mu_N", "K_d"); `result` (`tribojax.RESULTS`) says whether the fit
        succeeded (a failure raises `tribojax.FitError` instead unless `throw=False`).
    """
    if element not in _ELEMENTS:
        raise ValueError(f"element must be one of {sorted(_ELEMENTS)}, got {element!r}")
    if model not in ("steady", "history"):
        raise ValueError(f"model must be 'steady' or 'history', got {model!r}")
    analysis = analyse_loop(loop, window=window)
    if sigma is not None:
        sigma = float(check_range(sigma, "sigma", 0.0, unit="N"))
    given = dict(start or {})
    unknown = set(given) - {"mu_N", "K_d"}
    if unknown:
        raise ValueError(f"start has unknown key(s) {sorted(unknown)}; allowed ['mu_N', 'K_d']")
    init = {"mu_N": analysis.mu_N, "K_d": analysis.K_d, **given}
    for key, value in init.items():
        check_range(value, f"start[{key!r}]", 0.0, np.inf)
    theta0 = np.log([init["mu_N"], init["K_d"]])
    if model == "history":
        base = loop_baseline(loop, element, (init["mu_N"], init["K_d"]), noise_std=sigma)
        if base.record.f.shape[0] <= 2:
            raise ValueError(
                f"{loop.source}: {base.record.f.shape[0]} samples are too few to fit mu_N and K_d"
            )
        fit = fit_record(base, [theta0], max_steps=max_steps or MAX_STEPS)
    else:
        fit = _fit_steady(loop, _ELEMENTS[element], analysis, theta0, sigma, max_steps or 500)
    A_fit = 0.5 * float(np.ptp(loop.u)) * fit.values[1] / fit.values[0]
    if element == "jenkins" and A_fit <= 1.0 + 1e-3:
        # no slip in the fitted Jenkins loop: μN is only bounded below by the peak force
        std, cov, corr = fit.std_errors.copy(), fit.covariance.copy(), fit.correlation.copy()
        std[0], cov[0, :], cov[:, 0] = np.inf, np.inf, np.inf
        corr[0, :], corr[:, 0] = np.nan, np.nan
        corr[0, 0] = 1.0
        msg = (
            f"mu_N is only bounded below (>= {fit.values[0]:.6g} N): the fitted Jenkins loop "
            f"does not slip (A_bar = {A_fit:.4g} <= 1)"
        )
        fit = dataclasses.replace(
            fit, std_errors=std, covariance=cov, correlation=corr, message=msg
        )
    return thrown(fit, throw)


def _fit_steady(loop, cls, analysis, theta0, sigma, max_steps):
    sigma = loop.noise_std if sigma is None else sigma
    args = _steady_args(loop, analysis, 1.0 if sigma is None else sigma)
    if args[1].shape[0] <= 2:
        raise ValueError(
            f"{loop.source}: {args[1].shape[0]} samples are too few to fit mu_N and K_d"
        )
    return least_squares_fit(
        _SteadyLoopResiduals(cls),
        jnp.asarray(theta0),
        args,
        names=("mu_N", "K_d"),
        transform=jnp.exp,
        sigma_known=sigma is not None,
        max_steps=max_steps,
        jac="fwd",
        throw=False,
    )


def _steady_args(loop, analysis, scale):
    A = jnp.asarray(0.5 * (float(loop.u.max()) - float(loop.u.min())))
    direction = jnp.asarray(_loop_phase(loop, analysis))
    return jnp.asarray(loop.u), jnp.asarray(loop.f), A, direction, jnp.asarray(scale)


class _SteadyLoopResiduals(eqx.Module):
    """(steady-loop force − measured force)/σ; θ = log(μN, K_d) (wu2015 Eq 1 or 2)."""

    cls: type = eqx.field(static=True)

    def __call__(self, theta, args):
        u, f, A, direction, scale = args
        el = self.cls(jnp.exp(theta[0]), 1.0, jnp.exp(theta[1]))  # only the product μN enters
        return (el.steady_force(u, A, direction) - f) / scale


def loop_residuals(loop: HysteresisLoop, element: str, mu_N, K_d, *, model="steady"):
    """Model − measured force (N) of a Jenkins or Mindlin element with μN (N), K_d (N/m) on
    `loop`, as `fit_loop` computes it (steady loop, or the loop model from the first reversal:
    the residuals then cover the last samples only). Used to judge a fit made on a reduced
    record (`decimate_record`) on every sample of the original."""
    if element not in _ELEMENTS:
        raise ValueError(f"element must be one of {sorted(_ELEMENTS)}, got {element!r}")
    theta = np.log([mu_N, K_d])
    if model == "history":
        base = loop_baseline(loop, element, (mu_N, K_d))
        return evaluate(base, theta) - np.asarray(base.record.f)
    args = _steady_args(loop, analyse_loop(loop), 1.0)
    return np.asarray(_evaluate(_SteadyLoopResiduals(_ELEMENTS[element]), jnp.asarray(theta), args))


@cached_jit
def _evaluate(fn, theta, args):
    return fn(theta, args)
