"""Discovery engine: baseline fit, score tests, augmented refits, greedy selection (issue 6).

See the package docstring (`tribojax.discovery`) for the contract a baseline and an effect fulfil.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._precision import ensure_x64
from ._regions import ar1_inflation, noise_estimate

K_MAX = 8  # padded number of effect strengths in one fit (one compiled fit per record shape)
DELTA_BIC_THRESHOLD = -10.0  # "very strong" evidence (Kass & Raftery 1995)
ALPHA = 0.01  # family-wise level of the score tests (Bonferroni over grid points and candidates)


@dataclasses.dataclass(frozen=True)
class DiscoveryData:
    """What a baseline compares with: observed samples and where they sit.

    y: observed samples (output units, e.g. m of slip or N of force), shape (n,).
    x: abscissa of each sample for regions and plots (e.g. time in s, displacement in m).
    segment: integer label per sample; windows never straddle a change of label (0 for one
        record; loop branches 0/1, ...). Sample order is the order of the record.
    noise_std: noise sd of y in output units from the sidecar, or None (estimated then).
    x_label, y_label: axis labels with units.
    segment_names: optional names of the labels (e.g. {0: "falling", 1: "rising"}).
    """

    y: np.ndarray
    x: np.ndarray
    segment: np.ndarray
    noise_std: float | None
    x_label: str
    y_label: str
    segment_names: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class EffectDesign:
    """One effect at one nuisance setting, in the affine form the engine fits.

    With strengths s (k,), the augmented model is
        y = baseline.predict(θ_b, knobs) + basis @ s,   knobs = knob_null ⊕ knob_set + knob_gain @ s
    so s = 0 is the null (an interior point: strengths are signed). Nonlinear nuisance parameters
    (frequencies, velocity scales) are fixed per design; an effect returns one design per point
    of its grid.

    strength_names / strength_units: names and units of the physical strengths.
    strength_scale: physical strength per unit of s (k,), for reporting (s is O(1) in fits).
    knob_gain: (n_knobs, k) or None — how s moves the baseline's physics knobs.
    knob_set: {knob name: value} — nuisance knobs fixed while the effect is active.
    basis: (n, k) additive columns in output units per unit s, or None.
    nuisance: {name: value} reported with the result; n_nuisance counts them in ΔBIC.
    """

    strength_names: tuple[str, ...]
    strength_units: tuple[str, ...]
    strength_scale: np.ndarray
    knob_gain: np.ndarray | None = None
    knob_set: dict = dataclasses.field(default_factory=dict)
    basis: np.ndarray | None = None
    nuisance: dict = dataclasses.field(default_factory=dict)
    n_nuisance: int = 0

    @property
    def k(self) -> int:
        return len(self.strength_names)


class AbstractBaseline(eqx.Module):
    """A baseline model of one record, with physics knobs that effects may move.

    Concrete baselines are equinox Modules holding the record's arrays (so one compiled fit
    serves every record of the same shape). θ is unconstrained (e.g. log of positive values).
    """

    kind: eqx.AbstractClassVar[str]  # "slip" or "loop"
    param_names: eqx.AbstractClassVar[tuple[str, ...]]
    param_units: eqx.AbstractClassVar[tuple[str, ...]]
    knob_names: eqx.AbstractClassVar[tuple[str, ...]]

    @abc.abstractmethod
    def knob_null(self) -> np.ndarray:
        """Knob values under which every effect vanishes (the baseline physics)."""

    @abc.abstractmethod
    def start(self) -> np.ndarray:
        """Start θ for the baseline fit (unconstrained)."""

    @abc.abstractmethod
    def physical(self, theta):
        """θ → physical parameters (JAX, differentiable)."""

    @abc.abstractmethod
    def predict(self, theta, knobs):
        """Model samples (output units), shape (n,), at θ and knob vector `knobs` (JAX)."""

    @abc.abstractmethod
    def data(self) -> DiscoveryData:
        """The observed record."""

    def noise_model(self, r) -> tuple[float, float]:
        """(σ̂, AR(1) ρ̂) of the noise in the baseline residual `r` (output units). Default:
        `noise_estimate` (first differences within segments); a baseline may override it with a
        record-specific estimator (e.g. differences between loop cycles)."""
        return noise_estimate(r, self.data().segment)

    def solver_ok(self, theta, knobs) -> bool:
        """False when the model could not be evaluated (e.g. ODE failure); default True."""
        return True


class AbstractEffect(eqx.Module):
    """A named candidate effect: how it augments a baseline of its `kind`, per nuisance setting."""

    name: eqx.AbstractClassVar[str]
    kind: eqx.AbstractClassVar[str]
    description: ClassVar[str] = ""

    @abc.abstractmethod
    def designs(self, baseline: AbstractBaseline) -> list[EffectDesign]:
        """One `EffectDesign` per nuisance grid point (a single one when there is no nuisance)."""


_REGISTRY: dict[str, dict[str, type]] = {}


def register_effect(cls):
    """Class decorator: make `cls` (an AbstractEffect with a no-argument constructor) part of
    `default_effects(cls.kind)`. Registering a name twice replaces the earlier class."""
    if not (isinstance(cls, type) and issubclass(cls, AbstractEffect)):
        raise TypeError(f"register_effect expects an AbstractEffect subclass, got {cls!r}")
    _REGISTRY.setdefault(cls.kind, {})[cls.name] = cls
    return cls


def default_effects(kind: str) -> list[AbstractEffect]:
    """Instances of the registered effects of `kind` ("slip" or "loop"), in registration order."""
    if kind not in _REGISTRY:
        raise ValueError(f"kind = {kind!r}: no effects registered; known: {sorted(_REGISTRY)}")
    return [cls() for cls in _REGISTRY[kind].values()]


# ---------------------------------------------------------------- compiled pieces


def _model(theta, args):
    baseline, gain, knob_base, basis, mask, p = args
    tb, s = theta[:p], theta[p:] * mask
    return baseline.predict(tb, knob_base + gain @ s) + basis @ s


def _residual(theta, args):
    (baseline, gain, knob_base, basis, mask, p), y, scale = args
    return (_model(theta, (baseline, gain, knob_base, basis, mask, p)) - y) / scale


_jac_residual = eqx.filter_jit(jax.jacfwd(_residual))


@eqx.filter_jit
def _jac_parts(baseline, theta_b, knobs):
    """∂predict/∂θ_b (n, p) and ∂predict/∂knobs (n, n_knobs), forward mode."""
    return jax.jacfwd(baseline.predict, argnums=(0, 1))(theta_b, knobs)


_predict = eqx.filter_jit(lambda baseline, theta_b, knobs: baseline.predict(theta_b, knobs))


@dataclasses.dataclass(frozen=True)
class _State:
    """A fitted (baseline + active designs) model."""

    names: tuple[str, ...]  # effect names, in order added
    designs: tuple[EffectDesign, ...]
    theta: np.ndarray  # [θ_b, s (K_MAX, zero-padded)]
    yhat: np.ndarray
    rss: float  # in units of `scale`²
    cov: np.ndarray  # covariance of [θ_b, s_active] (scaled units, s² = RSS/(n - p))
    converged: bool
    steps: int
    message: str


def _pack(baseline, designs):
    names = baseline.knob_names
    n = baseline.data().y.shape[0]
    gain = np.zeros((len(names), K_MAX))
    base = np.asarray(baseline.knob_null(), dtype=float).copy()
    basis = np.zeros((n, K_MAX))
    mask = np.zeros(K_MAX)
    j = 0
    for d in designs:
        if j + d.k > K_MAX:
            raise ValueError(f"more than K_MAX = {K_MAX} effect strengths in one model")
        if d.knob_gain is not None:
            gain[:, j : j + d.k] = d.knob_gain
        for key, value in d.knob_set.items():
            base[names.index(key)] = value
        if d.basis is not None:
            basis[:, j : j + d.k] = d.basis
        mask[j : j + d.k] = 1.0
        j += d.k
    p = len(baseline.param_names)
    return (baseline, jnp.asarray(gain), jnp.asarray(base), jnp.asarray(basis), jnp.asarray(mask),
            p), j  # fmt: skip


def _fit(baseline, designs, theta0, y, scale, names=(), max_steps=200) -> _State:
    ensure_x64()
    spec, k = _pack(baseline, designs)
    p = spec[-1]
    args = (spec, jnp.asarray(y), jnp.asarray(float(scale)))
    sol = optx.least_squares(
        _residual,
        optx.LevenbergMarquardt(rtol=1e-8, atol=1e-8),
        jnp.asarray(theta0, dtype=jnp.float64),
        args,
        options=dict(jac="fwd"),
        max_steps=max_steps,
        throw=False,
    )
    theta = np.asarray(sol.value)
    r = np.asarray(_residual(sol.value, args))
    J = np.asarray(_jac_residual(sol.value, args))[:, : p + k]
    n = y.shape[0]
    rss = float(r @ r)
    finite = np.all(np.isfinite(r)) and np.all(np.isfinite(J))
    if finite:
        cov = np.linalg.pinv(J.T @ J) * rss / max(n - p - k, 1)
    else:
        cov = np.full((p + k, p + k), np.inf)
    knobs = spec[2] + spec[1] @ (jnp.asarray(theta[p:]) * spec[4])
    ok = bool(sol.result == optx.RESULTS.successful) and finite
    ok = ok and bool(baseline.solver_ok(jnp.asarray(theta[:p]), knobs))
    message = "" if ok else (str(optx.RESULTS[sol.result]) or "model evaluation failed")
    return _State(
        names=tuple(names),
        designs=tuple(designs),
        theta=theta,
        yhat=np.asarray(y) + r * scale,
        rss=rss if finite else np.inf,
        cov=cov,
        converged=ok,
        steps=int(sol.stats["num_steps"]),
        message=message,
    )


def _columns(baseline, state: _State, design: EffectDesign, knob_cache: dict) -> np.ndarray:
    """∂y/∂s of `design` added to the fitted `state` (n, k), output units."""
    spec, _ = _pack(baseline, state.designs)
    p = spec[-1]
    base_knobs = np.asarray(spec[2] + spec[1] @ (jnp.asarray(state.theta[p:]) * spec[4]))
    knobs = base_knobs.copy()
    for key, value in design.knob_set.items():
        knobs[baseline.knob_names.index(key)] = value
    cols = np.zeros((baseline.data().y.shape[0], design.k))
    if design.knob_gain is not None and np.any(design.knob_gain):
        key = tuple(np.round(knobs, 12))
        if key not in knob_cache:
            knob_cache[key] = np.asarray(
                _jac_parts(baseline, jnp.asarray(state.theta[:p]), jnp.asarray(knobs))[1]
            )
        cols = cols + knob_cache[key] @ design.knob_gain
    if design.basis is not None:
        cols = cols + design.basis
    return cols


def _score(r, J_cur, cols):
    """Rao score (LM) statistic n·‖P r‖²/‖r‖² for the new columns after projecting out the
    current model's Jacobian; returns (S, rank)."""
    q, _ = np.linalg.qr(J_cur)
    c = cols - q @ (q.T @ cols)
    if not np.all(np.isfinite(c)):
        return 0.0, 0
    u, sv, _ = np.linalg.svd(c, full_matrices=False)
    rank = int(np.sum(sv > sv[0] * 1e-9)) if sv.size and sv[0] > 0 else 0
    if rank == 0:
        return 0.0, 0
    proj = u[:, :rank].T @ r
    return float(r.size * (proj @ proj) / (r @ r)), rank


def _delta_bic(rss1, rss0, n, dk, rho):
    """ΔBIC of the augmented vs the current model, Gaussian errors with unknown variance and an
    AR(1) variance inflation c = (1+ρ)/(1−ρ) of the log-likelihood ratio (ρ from the
    augmented model's residuals)."""
    c = ar1_inflation(rho)
    return float(n * np.log(rss1 / rss0) / c + dk * np.log(n))
