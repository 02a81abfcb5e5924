"""The fit of a record model with its effects (`fit_model`) and alone (`fit_record`): the
solver, start policy and statistics that `fit`, `predict` and `discover` share (held out:
`_heldout`)."""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._checks import runtime_message
from .._fit._engine import FAILED_RESIDUAL, least_squares_fit, value_and_jacobian
from .._fit._result import fit_statistics, thrown
from .._fit._solver import CRAWL_STEPS, LevenbergMarquardt, restart_factors
from .._limits import MAX_STEPS as MAX_STEPS
from .._parallel import in_parallel
from .._precision import ensure_x64
from .._results import RESULTS
from ._base import K_MAX, AbstractBaseline
from ._record_fit import RecordFit, _Physical, record_scale
from ._residual import _names, _padded, evaluate, padded_residual

GAIN_TOL = 1e-2  # converged: a Gauss–Newton step would lower the cost by < 0.01 residual variances
NOISE_TOL = 1.0  # stationary: a rejected step promised < 1 residual variance (evaluation noise)
PROBE_STEPS = 8  # steps after which a start above a cost reached elsewhere is abandoned
CRAWL_FRACTION = 0.01  # a baseline start whose cost fell < 1 % in `CRAWL_STEPS` steps: crawling
SOLVER = LevenbergMarquardt.record(
    1e-8, 1e-10, gain_tol=GAIN_TOL, noise_tol=NOISE_TOL, max_rejections=12, padded=K_MAX
)


def fit_model(
    baseline,
    designs=(),
    theta0=None,
    y=None,
    scale=1.0,
    effects=(),
    max_steps=MAX_STEPS,
    sigma_known=False,
    noise_consistent=None,
    weights=None,
    restarts=3,
    ceiling=np.inf,
    abandon_above=np.inf,
    stop_crawl=False,
    floor=1.0,
):
    """Fit [θ_b, s] of `baseline` with the effects' `designs`, minimising ‖(model − y)/scale‖².

    Solver `LevenbergMarquardt.record`; the variables are scaled by the start Jacobian's column
    norms (Marquardt's scaling, so the damping is relative to the curvature). Converged when the
    predicted decrease of a Gauss–Newton step gᵀ(JᵀJ)⁻¹g at the optimum is below `GAIN_TOL`
    residual variances (s² = cost/(n − p), at least `floor`), or, as "stationary" (successful,
    with a message), when no trial step lowered the cost (a rejected step had promised less than
    `NOISE_TOL` residual variances, or 12 rejections in a row). A trial point where the model is
    not finite counts as a rejected step. A stationary stop whose Gauss–Newton step still
    promises at least `NOISE_TOL` residual variances (in a curved valley the trust region shrinks
    below the steps that would descend) goes on from where it stopped with the variables
    rescaled there and the trust region reset (up to `restarts` times, while each lowers the
    cost by more than `NOISE_TOL` residual variances; kept when it lowers the cost, also when it
    then ran out of steps). No restart for a stop above
    `ceiling` − `NOISE_TOL` s²: a refit passes the current model's cost, which its start from zero
    new strengths reaches, so a start stopped above it has failed. A restart runs with
    `baseline.more_steps()` (the stalls it mends came from ODE solves out of steps).

    `abandon_above`: a cost (RSS in units of `scale`) reached elsewhere (the current model's,
    another start's); a start still above it after `PROBE_STEPS` steps is abandoned (result
    `nonlinear_max_steps_reached` after fewer steps than `max_steps`, and a message saying so).
    `stop_crawl`: stop a start that crawls far from any minimum (the solver's `crawl` stop with
    `CRAWL_FRACTION`: the cost fell by less than 1 % over `CRAWL_STEPS` steps while a
    Gauss–Newton step still promises more than half of it); the same result and a message.
    `floor`: the least s² of the stops, units of `scale`² (1: `scale` is about the noise sd; 0:
    the stops count in residual variances whatever the unit, as `polish` asks).

    Args:
        theta0: start [θ_b, s] (default `baseline.start()` and zero strengths); y: the data
            (default the record's); scale: the residual unit (output units).
        sigma_known: `scale` is the noise sd (statistics in its units) rather than a unit.
        noise_consistent: the record's noise verdict for the statistics (see `fit_statistics`).
        weights: 0/1 per sample: fit the samples of weight 1 only (a held-out check,
            `heldout_residual`); `prediction` is then the model at every sample.
    Returns:
        `FitResult` with the fitted `model`, `prediction` (output units), `residuals` (in units of
        `scale`), `theta_covariance`, the `effects` and `designs`, and `result`: successful,
        `model_failed_at_start` (not finite at the start), `model_failed` (not finite at the
        optimum, a check inside the model failed, or its solver reported a failure),
        `nonlinear_max_steps_reached`.
    """
    ensure_x64()
    designs = tuple(designs)
    y = np.asarray(baseline.data().y if y is None else y, dtype=float)
    x0, args = _padded(baseline, designs, theta0, y, scale, weights)
    p, n = len(baseline.param_names), y.shape[0]
    npar = p + sum(d.k for d in designs)
    stats = _Statistics(baseline, designs, tuple(effects), float(scale), sigma_known, n)
    try:
        args, d = _scaled_start(x0, args, max_steps)
        res = _solve(x0 / d, args, p, max_steps, abandon_above, stop_crawl, floor)
    except _StartNotFinite:
        return stats.failed(
            x0[:npar], RESULTS.model_failed_at_start, "the model is not finite at the start values"
        )
    except eqx.EquinoxRuntimeError as err:  # a check inside the model: not a trial rejection
        message = f"the model raised inside the fit: {runtime_message(err)[:300]}"
        return stats.failed(x0[:npar], RESULTS.model_failed, message)
    x = (d * res.theta)[:npar]
    r, J = res.residuals[:n], (res.jacobian / d)[:n, :npar]
    broken = _broken_at_stop(r, J, float(args.bad))
    if broken:
        return stats.failed(x0[:npar], RESULTS.model_failed, broken, res.steps)
    cost = float(r @ r)
    gain = _gain_left(r, J)
    s2 = max(cost / max(n - npar, 1), floor) or 1.0
    message = _stop_message(res, cost, gain / s2, max_steps, abandon_above)
    short = res.converged and gain >= NOISE_TOL * s2 and cost < ceiling - NOISE_TOL * s2
    if short and restarts > 0:
        # stopped by rejections far from a minimum: go on rescaled here (a nuisance shift's
        # column was zero at the start, or the valley curved away) with the model's larger
        # solver budget, if any
        wider = baseline.more_steps() or baseline
        again = fit_model(
            wider,
            designs,
            x,
            y,
            scale,
            effects,
            max_steps,
            sigma_known,
            noise_consistent,
            weights,
            restarts - 1,
            cost,
            floor=floor,
        )
        if again.rss < cost:  # kept also when it ran out of steps still descending
            return dataclasses.replace(again, steps=again.steps + res.steps, model=baseline)
    prediction = y + scale * r
    if weights is not None:  # the samples left out are predicted, not fitted
        prediction = evaluate(baseline, x[:p], designs, x[p:])
        noise_consistent = False if noise_consistent is None else noise_consistent
    if noise_consistent is None and baseline.noise_gate:
        noise_consistent = baseline.noise_test(scale * r, npar)[0]
    return stats.at(
        x, r, J, res.result, res.steps, message, noise_consistent, prediction, gain / s2
    )


class _StartNotFinite(Exception):
    """The model is not finite at the start values."""


def _scaled_start(x0, args, max_steps):
    """The padded residual's args with the failed-point cost and Marquardt's variable scaling
    (1/column norms of the start Jacobian, `d`). The start's linearisation is
    the fit's own compiled solve (d = 1 there)."""
    r0, J0 = (
        np.asarray(v)
        for v in value_and_jacobian(padded_residual, x0, args, solver=SOLVER, max_steps=max_steps)
    )
    if not np.all(np.isfinite(r0)):
        raise _StartNotFinite
    bad = max(FAILED_RESIDUAL, 10.0 * float(np.max(np.abs(r0))))  # a failed trial: 100x the cost
    with np.errstate(over="ignore"):  # an absurd start (a value of 1e300): inf, d = 0
        norms = np.linalg.norm(J0, axis=0)
    d = np.where(norms > 0, 1.0 / np.where(norms > 0, norms, 1.0), 1.0)
    new = (jnp.asarray(bad, dtype=jnp.float64), jnp.asarray(d, dtype=jnp.float64))
    return eqx.tree_at(lambda t: (t.bad, t.d), args, new), d


def _solve(u0, args, p, max_steps, abandon_above, stop_crawl, floor=1.0):
    """The record solver (`SOLVER`) from the scaled start `u0`, with the probe and crawl stops."""
    return least_squares_fit(
        padded_residual,
        u0,
        args,
        names=tuple(f"u{i}" for i in range(p + K_MAX)),
        jac="fwd",
        solver=SOLVER,
        max_steps=max_steps,
        bar=(min(PROBE_STEPS, max_steps), abandon_above),
        crawl=CRAWL_FRACTION if stop_crawl else 0.0,
        floor=floor,
        throw=False,
    )


def _broken_at_stop(r, J, bad) -> str:
    """Why the model cannot be judged at the stop ("" when it can)."""
    if np.all(r == bad):
        return "the model is not finite at the optimum"
    g, JTJ = J.T @ r, J.T @ J
    if not (np.all(np.isfinite(JTJ)) and np.all(np.isfinite(g)) and np.isfinite(float(r @ r))):
        return "the model's Jacobian is not finite at the optimum"
    return ""


def _gain_left(r, J) -> float:
    """The decrease of ‖r‖² a Gauss–Newton step still predicts, gᵀ(JᵀJ)⁻¹g."""
    g = J.T @ r
    return float(g @ np.linalg.lstsq(J.T @ J, g, rcond=1e-12)[0])


def _stop_message(res, cost, gain_s2, max_steps, abandon_above):
    """The message of the solver's stop: abandoned or crawling (the budget's early stops), out
    of steps, stationary short of `GAIN_TOL`, or "" at a minimum."""
    if res.result == RESULTS.nonlinear_max_steps_reached and res.steps < max_steps:
        if cost > abandon_above:
            return (
                f"abandoned: after {res.steps} steps its cost {cost:.6g} was above "
                f"{abandon_above:.6g}, reached elsewhere"
            )
        return (
            f"crawling: after {res.steps} steps its cost fell by less than "
            f"{CRAWL_FRACTION:.0%} in {CRAWL_STEPS} steps, far from a minimum"
        )
    if res.result == RESULTS.nonlinear_max_steps_reached:
        return f"no convergence in max_steps = {max_steps} steps"
    if res.converged and gain_s2 >= GAIN_TOL:
        return f"stationary: no descent step (predicted gain {gain_s2:.3g} s²)"
    return "" if res.converged else res.message


@dataclasses.dataclass(frozen=True)
class _Statistics:
    """The `RecordFit` of a record model's fit at its stop, or of a failed one."""

    baseline: AbstractBaseline
    designs: tuple
    effects: tuple
    scale: float
    sigma_known: bool
    n: int

    def _extra(self):
        scales = [np.asarray(d.strength_scale, dtype=np.float64) for d in self.designs]
        return dict(
            names=_names(self.baseline, self.designs),
            transform=_Physical(self.baseline, np.concatenate([np.zeros(0), *scales])),
            sigma_known=self.sigma_known,
            result_type=RecordFit,
            model=self.baseline,
            effects=self.effects,
            designs=self.designs,
            scale=self.scale,
        )

    def at(self, x, r, J, result, steps, message, noise_consistent, prediction, gain_left):
        return fit_statistics(
            x,
            r,
            J,
            result=result,
            steps=steps,
            message=message,
            noise_consistent=noise_consistent,
            prediction=prediction,
            gain_left=gain_left,
            **self._extra(),
        )

    def failed(self, x, result, message, steps=0):
        n, npar = self.n, x.size
        return fit_statistics(
            x,
            np.full(n, np.nan),
            np.full((n, npar), np.nan),
            result=result,
            steps=steps,
            message=message,
            prediction=np.full(n, np.nan),
            **self._extra(),
        )


def fit_record(
    baseline,
    starts=None,
    *,
    scale=None,
    max_steps=MAX_STEPS,
    sigma_known=None,
    restarts=True,
    throw=False,
):
    """Fit a record model alone (no effects): the fit that `fit` reports and `discover` starts
    from. From every one of `starts` (θ; default `baseline.starts()`: the slip model's cost has
    separate minima in C_τ), and the best kept (`_kept`): the lowest cost among the fits that
    converged away from a bound of the parameters (`baseline.at_bound`), fits within `COST_TIE`
    residual variances of it counting as a tie that goes to the earlier start; else the first
    that converged; else the lowest cost. When the fit kept stopped short of a minimum (a
    stationary stop whose Gauss–Newton step still promises `NOISE_TOL` residual variances or more:
    the trust region collapsed under the ODE's evaluation noise or at a kink) and `restarts`, it
    is fitted again from the points around its stop with each parameter ×(1 ± 1 %)
    (`restart_factors`, the chain fit's restarts), with `baseline.more_steps()`, and the best of
    all is kept by the same rule. A later start still above the first one's cost (a restart: the
    kept fit's) after `PROBE_STEPS` steps is abandoned (`fit_model`'s `abandon_above`); one that
    crawls far from any minimum is stopped (`stop_crawl`; the records behind these rules:
    docs/discovery.md).
    `scale`: the residual unit (default the record's noise sd, else the first-difference estimate
    `noise_estimate` of the data, else its sd); `sigma_known` (default: the record states its
    noise) makes the statistics use the stated noise when the residual is consistent with it.
    `throw`: raise `FitError` when no start succeeded (default: return the failed fit, `result`
    says why)."""
    data = baseline.data()
    y = np.asarray(data.y, dtype=float)
    scale = record_scale(baseline) if scale is None else scale
    known = bool(data.noise_std) if sigma_known is None else sigma_known

    def call(th, above=np.inf, model=baseline):
        return lambda: fit_model(
            model,
            (),
            np.asarray(th, dtype=float),
            y,
            scale,
            max_steps=max_steps,
            sigma_known=known,
            abandon_above=above,
            stop_crawl=True,
        )

    thetas = list(baseline.starts() if starts is None else starts)
    first = in_parallel([call(thetas[0])])[0]
    above = first.rss if np.isfinite(first.rss) else np.inf  # a cost reached, converged or not
    fits = [first, *in_parallel([call(th, above) for th in thetas[1:]])]
    best = _kept(baseline, fits)
    if restarts:
        best = restarted_around(baseline, best, call)
    return thrown(best, throw)


def restarted_around(baseline, fit, call, ceiling=np.inf):
    """`fit`, or where it stalled (`_stalled`) below `ceiling` − `NOISE_TOL` s² away from a
    bound of the record model, the best by `_kept` of it and the fits from the points around its
    stop (`_around`), each run by `call(θ, abandon_above, model)` (a thunk) with
    `baseline.more_steps()`: the rule of `fit_record` and of discovery's effect refits."""
    if not _stalled(fit) or baseline.at_bound(fit.theta[: _p(baseline)]):
        return fit
    n = np.asarray(fit.residuals).size
    if not fit.rss < ceiling - NOISE_TOL * max(fit.rss / max(n - fit.theta.size, 1), 1.0):
        return fit  # no lower than the cost the refit starts from: it failed, not stalled
    wider = baseline.more_steps() or baseline
    more = in_parallel([call(th, fit.rss, wider) for th in _around(baseline, fit)])
    more = [dataclasses.replace(f, model=baseline) for f in more]
    return _kept(baseline, [fit, *more])


COST_TIE = NOISE_TOL  # fits whose costs differ by less (residual variances) are a tie


def _p(baseline) -> int:
    return len(baseline.param_names)


def _stalled(fit) -> bool:
    """Converged as stationary, short of a minimum (`NOISE_TOL` or more still promised)."""
    return bool(fit.converged) and (fit.gain_left or 0.0) >= NOISE_TOL


def _kept(baseline, fits):
    """The lowest cost of the fits that converged away from a bound, fits within `COST_TIE`
    residual variances (s² = cost/(n − p), at least 1) of it a tie going to the earlier one;
    else the first that converged (a lower stop at a bound is not compared); else the lowest
    cost."""
    p = _p(baseline)
    ok = [f for f in fits if f.converged and not baseline.at_bound(f.theta[:p])]
    if ok:
        low = min(f.rss for f in ok)
        n = np.asarray(ok[0].residuals).size
        s2 = max(low / max(n - p, 1), 1.0)
        return next(f for f in ok if f.rss <= low + COST_TIE * s2)
    converged = [f for f in fits if f.converged]
    return converged[0] if converged else min(fits, key=lambda f: f.rss)


def _around(baseline, fit) -> list:
    """Start points around a fit's stop: its parameters ×(1 ± `RESTART_STEP`) in the sign
    patterns of `restart_factors`, as θ (`baseline.theta_of`), and the effects' strengths and
    shifts after them ×(1 ± `RESTART_STEP`) likewise; none where the model cannot map values
    back or a moved value leaves its range."""
    p = _p(baseline)
    values = np.asarray(fit.values[:p], dtype=float)
    extra = np.asarray(fit.theta, dtype=float)[p:]
    points = []
    for factors in restart_factors(p + extra.size):
        try:
            theta = np.asarray(baseline.theta_of(values * factors[:p]), dtype=float)
        except (NotImplementedError, ValueError):
            continue
        points.append(np.concatenate([theta, extra * factors[p:]]))
    return points
