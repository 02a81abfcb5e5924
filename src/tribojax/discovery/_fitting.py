"""The discovery fit: baseline + effect strengths by `least_squares_fit`, score columns, ΔBIC.

Every fit minimises ‖(model − y)/scale‖² over x = [θ_b, s] with the effect strengths s padded to
`K_MAX` (inactive ones masked out of the model and held at 0), through one module-level residual
function (`_residual`), so the compiled solve is shared by every combination of effects on one
record shape. The solver is optimistix Levenberg–Marquardt with the discovery stops
(`_DiscoveryLM`); statistics use the active columns of the returned Jacobian only.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._checks import runtime_message
from .._fit._engine import FAILED_RESIDUAL, fit_statistics, least_squares_fit, value_and_jacobian
from .._fit._solver import quiet
from .._precision import ensure_x64
from ._core import K_MAX, AbstractBaseline, EffectDesign
from ._parallel import in_parallel
from ._regions import ar1_inflation


def _predict_jac(baseline, theta_b, knobs):
    """predict and its forward-mode Jacobians ∂/∂θ_b (n, p), ∂/∂knobs (n, n_knobs): one pass."""
    return baseline.value_and_jacobians(theta_b, knobs)




class _Padded(eqx.Module):
    """Everything the residual needs, with the effect strengths padded to `K_MAX` (array leaves
    only, so one compiled solve serves every combination of effects on one record shape)."""

    baseline: AbstractBaseline
    base: jax.Array  # knob vector at s = 0 (n_knobs,)
    gain: jax.Array  # ∂knobs/∂s (n_knobs, K_MAX)
    basis: jax.Array  # additive columns (n, K_MAX), output units per unit s
    mask: jax.Array  # 1 for the active strengths (K_MAX,)
    y: jax.Array  # observed samples (n,)
    scale: jax.Array  # residual unit (output units)
    bad: jax.Array  # residual of every row where the model is not finite
    d: jax.Array  # variable scaling: x = d·u (p + K_MAX,)


def _residual_and_jac(x, a: _Padded):
    """Residual [(model − y)/scale, held strengths] and its Jacobian ∂/∂x at x = [θ_b, s].

    Inactive strengths are masked out of the model and held at 0 by a row each (residual s,
    Jacobian 1), so the normal matrix stays regular. A model that is not finite gives `a.bad` in
    every row and a zero Jacobian: the trial is rejected as a rise of the cost.
    """
    p = x.size - K_MAX
    hold = 1.0 - a.mask
    s = x[p:] * a.mask
    value, jb, jk = _predict_jac(a.baseline, x[:p], a.base + a.gain @ s)
    r = (value + a.basis @ s - a.y) / a.scale
    J = jnp.concatenate([jb, (jk @ a.gain + a.basis) * a.mask[None, :]], axis=1) / a.scale
    ok = jnp.all(jnp.isfinite(r)) & jnp.all(jnp.isfinite(J))
    r = jnp.concatenate([jnp.where(ok, r, a.bad), hold * x[p:]])
    J_hold = jnp.concatenate([jnp.zeros((K_MAX, p)), jnp.diag(hold)], axis=1)
    return r, jnp.concatenate([jnp.where(ok, J, 0.0), J_hold], axis=0)



@eqx.filter_custom_jvp
def _residual(u, a):
    """The residual function of every discovery fit, in scaled variables u = x/d (module level:
    the solve compiles once per record shape)."""
    return _residual_and_jac(a.d * u, a)[0]


@_residual.def_jvp
def _residual_jvp(primals, tangents):
    # the Jacobian from one forward pass over (θ_b, knobs), not over the K_MAX padded strengths:
    # optimistix's linearisation and the statistics then cost one `_predict_jac` per point
    u, a = primals
    r, J = _residual_and_jac(a.d * u, a)
    tu = tangents[0]
    return r, (jnp.zeros_like(r) if tu is None else (J * a.d[None, :]) @ tu)


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
    """Knob base vector, knob gain (n_knobs, K_MAX) and additive basis (n, K_MAX) of the active
    designs (their k strengths first, zero columns after)."""
    names = baseline.knob_names
    n = baseline.data().y.shape[0]
    k = sum(d.k for d in designs)
    if k > K_MAX:
        raise ValueError(f"{k} effect strengths in one model: more than K_MAX = {K_MAX}")
    gain = np.zeros((len(names), K_MAX))
    base = np.asarray(baseline.knob_null(), dtype=float).copy()
    basis = np.zeros((n, K_MAX))
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


GAIN_TOL = 1e-2  # converged: a Gauss–Newton step would lower the cost by < 0.01 residual variances
NOISE_TOL = 1.0  # stationary: a rejected step promised < 1 residual variance (evaluation noise)


class _RelativeTrustRegion(optx.ClassicalTrustRegion):
    """Trust-region update (cutoffs 0.25/0.75 as `NoiseFloorLM`, growth 2 as MINPACK) of a radius
    in units of the Gauss–Newton step length (`optx.IndirectDampedNewtonDescent`), capped at 1: a
    rejection then shrinks the step at once instead of first undoing earlier growth. Growth 3.5
    (optimistix's default) alternated accepted and rejected steps along the curved valley of a
    Stribeck refit (32 steps against 19)."""

    def step(self, first_step, y, y_eval, f_info, f_eval_info, state):
        size, accept, result, state = super().step(first_step, y, y_eval, f_info, f_eval_info,
                                                   state)  # fmt: skip
        size = jnp.minimum(size, 1.0)
        return size, accept, result, eqx.tree_at(lambda st: st.step_size, state, size)


class _DiscoveryLM(optx.AbstractGaussNewton):
    """Levenberg–Marquardt (trust region in Gauss–Newton step lengths) with the discovery stops,
    s² = RSS/(n − p) (at least 1; n and p without the held strengths): after an accepted step,
    the Gauss–Newton gain gᵀ(JᵀJ)⁻¹g < `GAIN_TOL`·s² (converged); after a rejected step whose
    predicted gain was < `NOISE_TOL`·s² (the improvement left is below one residual variance,
    the size of the ODE evaluation noise: stationary); `max_rejections` rejections in a row;
    optimistix's Cauchy test (`rtol`, `atol`)."""

    rtol: float
    atol: float
    norm: object
    descent: optx.IndirectDampedNewtonDescent
    search: _RelativeTrustRegion
    verbose: object
    max_rejections: int = eqx.field(static=True)

    def __init__(self, rtol, atol, max_rejections=12):
        self.rtol, self.atol, self.norm = rtol, atol, optx.max_norm
        self.descent = optx.IndirectDampedNewtonDescent()
        self.search = _RelativeTrustRegion(high_cutoff=0.75, low_cutoff=0.25, high_constant=2.0)
        self.verbose = quiet
        self.max_rejections = max_rejections

    def terminate(self, fn, y, args, options, state, tags):
        r, jac = state.f_info.residual, state.f_info.jac
        J = jac.as_matrix()
        n, p = r.size - K_MAX, J.shape[1] - K_MAX + jnp.sum(args.mask)
        s2 = jnp.maximum(r @ r / jnp.maximum(n - p, 1), 1.0)
        gn = jnp.sum((jnp.linalg.qr(J)[0].T @ r) ** 2)
        # the step just rejected: a rejection shrank the radius by `low_constant`
        radius = state.search_state.step_size / self.search.low_constant
        step, _ = self.descent.step(radius, state.descent_state)
        rejected = r @ r - jnp.sum((r + jac.mv(step)) ** 2)
        fresh = state.num_steps_since_acceptance == 0
        done = ~state.first_step & jnp.where(fresh, gn < GAIN_TOL * s2, rejected < NOISE_TOL * s2)
        stalled = state.num_steps_since_acceptance >= self.max_rejections
        return state.terminate | stalled | done, state.result


_SOLVER = _DiscoveryLM(rtol=1e-8, atol=1e-10)


MAX_STEPS = 128  # step budget of every discovery fit (accepted and rejected; one compile)


def _fit(baseline, designs, theta0, y, scale, names=(), max_steps=MAX_STEPS) -> _State:
    """Fit [θ_b, s] minimising ‖(model − y)/scale‖² with `least_squares_fit` (`_DiscoveryLM`).

    The strengths are padded to `K_MAX` (`_residual`), so the compiled solve is shared by every
    combination of effects on the same record shape; statistics use the active columns only.
    The variables are scaled by the start Jacobian's column norms (Marquardt's scaling, so the
    damping is relative to the curvature). Converged when the predicted decrease of a
    Gauss–Newton step gᵀ(JᵀJ)⁻¹g at the optimum is below `GAIN_TOL` residual variances
    (s² = cost/(n − p), at least 1), or, as "stationary", when the solver stopped because no
    trial step lowered the cost (a local minimum of the cost as evaluated: ODE evaluation noise,
    or a kink where contacts start sliding; the message gives the predicted gain). A trial
    point where the model is not finite counts as a rejected step. Not converged: a model that
    is not finite at the start, a solver failure, or `max_steps` (accepted and rejected steps).
    """
    ensure_x64()
    base, gain, basis = _pack(baseline, designs)
    p, k, n = len(baseline.param_names), sum(d.k for d in designs), y.shape[0]
    npar = p + k
    x0 = np.zeros(p + K_MAX)
    x0[:npar] = np.asarray(theta0, dtype=float)
    arrays = (base, gain, basis, np.arange(K_MAX) < k, y, scale, np.inf, np.ones(p + K_MAX))
    args = _Padded(baseline, *(jnp.asarray(v, dtype=jnp.float64) for v in arrays))

    def failed(message, steps=0):
        return _State(tuple(names), tuple(designs), x0[:npar], np.full(n, np.nan), np.inf,
                      np.full((npar,) * 2, np.inf), np.full((n, npar), np.nan), False, steps,
                      message)  # fmt: skip

    try:
        # d = 1 here: u = x; the engine's statistics reuse this compile
        r0, J0 = (np.asarray(v) for v in value_and_jacobian(_residual, jnp.asarray(x0), args))
        if not np.all(np.isfinite(r0)):
            return failed("the model is not finite at the start values")
        # a failed trial point costs more than the start (100x)
        bad = max(FAILED_RESIDUAL, 10.0 * float(np.max(np.abs(r0))))
        norms = np.linalg.norm(J0, axis=0)
        d = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
        new = (jnp.asarray(bad, dtype=jnp.float64), jnp.asarray(d, dtype=jnp.float64))
        args = eqx.tree_at(lambda t: (t.bad, t.d), args, new)
        res = least_squares_fit(_residual, x0 / d, args, names=(*baseline.param_names,
                                *(f"s{i}" for i in range(K_MAX))), jac="fwd",
                                solver=_SOLVER, max_steps=max_steps)  # fmt: skip
    except eqx.EquinoxRuntimeError as err:  # a check inside the model: not a trial rejection
        return failed(f"the model raised inside the fit: {runtime_message(err)[:300]}")
    x = (d * res.theta)[:npar]
    r, J = res.residuals[:n], (res.jacobian / d)[:n, :npar]
    if np.all(r == bad):
        return failed("the model is not finite at the optimum", res.steps)
    cost = float(r @ r)
    g, JTJ = J.T @ r, J.T @ J
    if not (np.all(np.isfinite(JTJ)) and np.all(np.isfinite(g)) and np.isfinite(cost)):
        # (measured: an independent drift record where a refit ended at a point whose
        # Jacobian overflowed, and the statistics' least squares raised LinAlgError)
        return failed("the model's Jacobian is not finite at the optimum", res.steps)
    pred = float(g @ np.linalg.lstsq(JTJ, g, rcond=1e-12)[0])
    s2 = max(cost / max(n - npar, 1), 1.0)
    converged, message = res.converged, ""
    if not res.converged:
        message = (f"no convergence in max_steps = {max_steps} steps" if res.steps >= max_steps
                   else res.message)  # fmt: skip
    elif pred >= GAIN_TOL * s2:
        message = f"stationary: no descent step (predicted gain {pred / s2:.3g} s²)"
    knobs = jnp.asarray(base + gain[:, :k] @ x[p:])
    if converged and not baseline.solver_ok(jnp.asarray(x[:p]), knobs):
        converged, message = False, "the model's solver reported a failure at the optimum"
    return _State(
        names=tuple(names),
        designs=tuple(designs),
        theta=x,
        yhat=y + scale * r,
        rss=cost,
        cov=fit_statistics(x, r, J, names=[""] * npar, transform=lambda t: t, sigma_known=False,
                           result=res.result, steps=res.steps).covariance,  # fmt: skip
        jac=J,
        converged=bool(converged),
        steps=res.steps,
        message=message,
    )


def _knob_jacobian(baseline, theta_b, knobs) -> np.ndarray:
    """∂y/∂knobs (n, n_knobs) at (θ_b, knobs), output units: the fit's own compiled residual
    Jacobian (`value_and_jacobian(_residual, ...)`) with the knobs as the padded strengths, K_MAX
    knobs per call, so scoring compiles no second copy of the model and its Jacobian. NaN
    columns where the model is not finite or a check inside it fails."""
    p, m = len(theta_b), len(knobs)
    n = baseline.data().y.shape[0]
    x = jnp.asarray(np.concatenate([theta_b, np.zeros(K_MAX)]), dtype=jnp.float64)
    out = np.empty((n, m))
    for j in range(0, m, K_MAX):
        k = min(K_MAX, m - j)
        gain = np.zeros((m, K_MAX))
        gain[j : j + k, :k] = np.eye(k)
        arrays = (knobs, gain, np.zeros((n, K_MAX)), np.arange(K_MAX) < k, np.zeros(n), 1.0,
                  np.inf, np.ones(p + K_MAX))  # fmt: skip
        args = _Padded(baseline, *(jnp.asarray(v, dtype=jnp.float64) for v in arrays))
        try:
            r, J = (np.asarray(v) for v in value_and_jacobian(_residual, x, args))
        except eqx.EquinoxRuntimeError:  # a check inside the model failed
            out[:, j : j + k] = np.nan
            continue
        out[:, j : j + k] = J[:n, p : p + k] if np.all(np.isfinite(r[:n])) else np.nan
    return out


def _design_knobs(baseline, state: _State, design: EffectDesign):
    """The knob vector at which `design`'s columns need ∂y/∂knobs (None: they do not)."""
    if design.columns is not None or design.knob_gain is None or not np.any(design.knob_gain):
        return None
    base, gain, _ = _pack(baseline, state.designs)
    p = len(baseline.param_names)
    knobs = base + gain[:, : state.theta.size - p] @ state.theta[p:]
    for key, value in design.knob_set.items():
        knobs[baseline.knob_names.index(key)] = value
    return knobs


def _knob_key(knobs):
    return tuple(np.round(knobs, 12))


def prefetch_columns(baseline, state: _State, designs, knob_cache: dict) -> None:
    """Fill `knob_cache` with the knob Jacobians that `_columns` of `designs` will need,
    computed side by side (`in_parallel`; e.g. one per Stribeck grid v_s)."""
    p = len(baseline.param_names)
    todo = {}
    for d in designs:
        knobs = _design_knobs(baseline, state, d)
        if knobs is not None and _knob_key(knobs) not in knob_cache:
            todo[_knob_key(knobs)] = knobs
    results = in_parallel([lambda k=k: _knob_jacobian(baseline, state.theta[:p], k)
                           for k in todo.values()])  # fmt: skip
    knob_cache.update(zip(todo, results))


def _columns(baseline, state: _State, design: EffectDesign, knob_cache: dict) -> np.ndarray:
    """∂y/∂s of `design` added to the fitted `state` (n, k), output units."""
    if design.columns is not None:
        return np.asarray(design.columns)
    p, n = len(baseline.param_names), baseline.data().y.shape[0]
    cols = np.zeros((n, design.k))
    knobs = _design_knobs(baseline, state, design)
    if knobs is not None:
        key = _knob_key(knobs)
        if key not in knob_cache:
            knob_cache[key] = _knob_jacobian(baseline, state.theta[:p], knobs)
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
