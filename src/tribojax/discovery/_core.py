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

    def region_info(self, region: dict) -> dict:
        """Extra keys for a flagged region (e.g. a loop's branch and displacement range);
        default none."""
        return {}

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

    def refine(self, baseline: AbstractBaseline, design: EffectDesign, score) -> EffectDesign:
        """Optionally improve the best grid design's nuisance values; `score(design) -> float` is
        the Rao statistic at the current fit. Default: no refinement."""
        return design


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


@eqx.filter_jit
def _value_and_jac(baseline, theta_b, knobs):
    """predict and its forward-mode Jacobians ∂/∂θ_b (n, p), ∂/∂knobs (n, n_knobs): one pass.

    The only compiled function of a fit (one compile per baseline type and record shape): the
    effect strengths enter through `knobs` (a fixed-length vector) and additive columns, which
    the fit applies outside the compiled code.
    """

    def f(tb, kn):
        out = baseline.predict(tb, kn)
        return out, out

    (jb, jk), value = jax.jacfwd(f, argnums=(0, 1), has_aux=True)(theta_b, knobs)
    return value, jb, jk


@dataclasses.dataclass(frozen=True)
class _State:
    """A fitted (baseline + active designs) model."""

    names: tuple[str, ...]  # effect names, in order added
    designs: tuple[EffectDesign, ...]
    theta: np.ndarray  # [θ_b, s]
    yhat: np.ndarray
    rss: float  # in units of `scale`²
    cov: np.ndarray  # covariance of [θ_b, s] (scaled units, s² = RSS/(n - p))
    jac: np.ndarray  # ∂yhat/∂[θ_b, s] / scale at the optimum
    converged: bool
    steps: int
    message: str


def _pack(baseline, designs):
    """Knob base vector, knob gain (n_knobs, k) and additive basis (n, k) of active designs."""
    names = baseline.knob_names
    n = baseline.data().y.shape[0]
    k = sum(d.k for d in designs)
    if k > K_MAX:
        raise ValueError(f"{k} effect strengths in one model: more than K_MAX = {K_MAX}")
    gain = np.zeros((len(names), k))
    base = np.asarray(baseline.knob_null(), dtype=float).copy()
    basis = np.zeros((n, k))
    j = 0
    for d in designs:
        if d.knob_gain is not None:
            gain[:, j : j + d.k] = d.knob_gain
        for key, value in d.knob_set.items():
            base[names.index(key)] = value
        if d.basis is not None:
            basis[:, j : j + d.k] = d.basis
        j += d.k
    return base, gain, basis


def _evaluate(baseline, packed, x):
    """Model samples and Jacobian (n, p + k) of the augmented model at x = [θ_b, s]."""
    base, gain, basis = packed
    p = len(baseline.param_names)
    tb, s = x[:p], x[p:]
    try:
        value, jb, jk = _value_and_jac(baseline, jnp.asarray(tb), jnp.asarray(base + gain @ s))
        value = np.asarray(value)  # blocks: a runtime check inside the model raises here
    except eqx.EquinoxRuntimeError:
        # a check inside the model (e.g. a linear solve of the implicit ODE step meeting NaN at
        # a nonsensical trial point) — the trial is rejected like a non-finite one
        n = baseline.data().y.shape[0]
        return np.full(n, np.nan), np.full((n, p + s.size), np.nan)
    model = np.asarray(value) + basis @ s
    J = np.concatenate([np.asarray(jb), np.asarray(jk) @ gain + basis], axis=1)
    return model, J


def _fit(baseline, designs, theta0, y, scale, names=(), max_steps=100) -> _State:
    """Levenberg–Marquardt (Marquardt's diagonal scaling) on (model − y)/scale.

    A plain NumPy loop around one compiled value-and-Jacobian call per trial point: each
    augmented model reuses the same compiled code, where an optimistix solve would compile
    once per combination of effects. Converged when the predicted decrease of a Gauss–Newton
    step gᵀ(JᵀJ)⁻¹g is below 0.01 residual variances (s² = cost/(n − p), at least 1), or when not
    even a step of damping 1e12 lowers the cost (a local minimum of the cost as evaluated; the
    message then gives the predicted gain); a non-finite trial counts as a rejected step. Not
    converged: non-finite start, or `max_steps` reached.
    """
    ensure_x64()
    packed = _pack(baseline, designs)
    x = np.asarray(theta0, dtype=float)
    n, npar = y.shape[0], x.size

    def ev(xx):
        m, J = _evaluate(baseline, packed, xx)
        r = (m - y) / scale
        ok = np.all(np.isfinite(r)) and np.all(np.isfinite(J))
        return m, r, J / scale, ok

    m, r, J, ok = ev(x)
    steps, message, converged = 0, "", False
    if not ok:
        message = "the model is not finite at the start values"
    cost, lam = float(r @ r), 1e-3
    if ok and npar == 0:
        converged = True  # nothing to fit
    while ok and not converged and steps < max_steps:
        A, g = J.T @ J, J.T @ r
        # predicted decrease of a full Gauss–Newton step, against the residual variance
        pred = float(g @ np.linalg.lstsq(A, g, rcond=1e-12)[0])
        s2 = max(cost / max(n - npar, 1), 1.0)
        if pred < 1e-2 * s2:
            converged = True
            break
        steps += 1
        dg = np.maximum(np.diag(A), 1e-12 * max(np.max(np.diag(A)), 1e-300))
        while True:
            dx = -np.linalg.solve(A + lam * np.diag(dg), g)
            mn, rn, Jn, okn = ev(x + dx)
            cn = float(rn @ rn) if okn else np.inf
            if cn < cost:  # strict: a step that does not lower the cost is rejected
                break
            lam *= 4.0
            if lam > 1e12:
                break
        if not cn < cost:
            # not even a tiny step along −g descends: a local minimum of the cost as evaluated
            # (ODE evaluation noise, or a kink of the model where contacts start sliding)
            converged = True
            message = f"stationary: no descent step (predicted gain {pred / s2:.3g} s²)"
            break
        x, m, r, J, cost = x + dx, mn, rn, Jn, cn
        lam = max(lam / 3.0, 1e-12)
    if ok and not converged and not message:
        message = f"no convergence in max_steps = {max_steps} steps"
    p = len(baseline.param_names)
    if converged and not baseline.solver_ok(
        jnp.asarray(x[:p]), jnp.asarray(packed[0] + packed[1] @ x[p:])
    ):
        converged, message = False, "the model's solver reported a failure at the optimum"
    cov = np.linalg.pinv(J.T @ J) * cost / max(n - npar, 1) if ok else np.full((npar,) * 2, np.inf)
    return _State(
        names=tuple(names),
        designs=tuple(designs),
        theta=x,
        yhat=m,
        rss=cost if ok else np.inf,
        cov=cov,
        jac=J,
        converged=bool(converged),
        steps=steps,
        message=message,
    )


def _columns(baseline, state: _State, design: EffectDesign, knob_cache: dict) -> np.ndarray:
    """∂y/∂s of `design` added to the fitted `state` (n, k), output units."""
    base, gain, _ = _pack(baseline, state.designs)
    p = len(baseline.param_names)
    knobs = base + gain @ state.theta[p:]
    for key, value in design.knob_set.items():
        knobs[baseline.knob_names.index(key)] = value
    cols = np.zeros((baseline.data().y.shape[0], design.k))
    if design.knob_gain is not None and np.any(design.knob_gain):
        key = tuple(np.round(knobs, 12))
        if key not in knob_cache:
            try:
                out = _value_and_jac(baseline, jnp.asarray(state.theta[:p]), jnp.asarray(knobs))
                knob_cache[key] = np.asarray(out[2])
            except eqx.EquinoxRuntimeError:
                knob_cache[key] = np.full((cols.shape[0], knobs.size), np.nan)
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
