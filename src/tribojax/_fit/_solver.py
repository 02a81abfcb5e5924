"""The one Levenberg–Marquardt solver of tribojax, its stopping rules as fields.

Every fit in the library runs on `LevenbergMarquardt` (an optimistix Gauss–Newton solver with a
damped-Newton descent and a trust region). Its configurations:

- `LevenbergMarquardt(rtol, atol)`: optimistix's own Levenberg–Marquardt (QR solves, trust-region
  cutoffs 0.01/0.99), for smooth residuals (tables, closed forms).
- `LevenbergMarquardt.noise_floor(rtol, atol)`: residuals through an adaptive ODE solve (slip-free
  histories, curves, the wang2022 chain).
- `LevenbergMarquardt.record(...)`: the fit of a record model with its effects (`fit_model`).

Stops (each off when None), besides optimistix's Cauchy test on `rtol`, `atol`:

- `options["budget"]` (an integer array, given by `least_squares_fit`): that many steps, then
  `nonlinear_max_steps_reached` — optimistix's `max_steps` as a run-time value, so one compiled
  solve serves every budget, a budget of one step included (the start's linearisation).
- `options["bar"]` (probe, limit), run-time values given with the budget: after `probe` steps,
  a cost ‖r‖² still above `limit` stops the solve as `nonlinear_max_steps_reached` (a start
  that has not come below a cost already reached elsewhere is abandoned; `fit_model`).
- `options["crawl"]` (a fraction f, run-time, 0 = off; `RelativeTrustRegion` only): a solve whose
  cost fell by less than f of itself over the last `CRAWL_STEPS` steps while the Gauss–Newton
  gain gᵀ(JᵀJ)⁻¹g still promises more than half of it stops as `nonlinear_max_steps_reached`:
  far from any minimum, the steps no longer get what the linearisation promises (`fit_record`).

- `step_tol`: after an accepted step, the Gauss–Newton step still left is below `step_tol`
  standard errors in every parameter (s² = RSS/(n − p)); not tried while a residual equals
  `FAILED_RESIDUAL`.
- `gain_tol`: after an accepted step, the Gauss–Newton gain gᵀ(JᵀJ)⁻¹g < `gain_tol`·s²
  (s² = RSS/(n − p), at least `options["floor"]`, default 1): converged.
- `noise_tol`: after a rejected step whose predicted gain was < `noise_tol`·s²: the improvement
  left is below the evaluation noise of an adaptive ODE solve (stationary).
- `max_rejections`: that many rejected steps in a row (the trust region shrank under the
  evaluation noise, which plain LM never recognises as termination).
`padded`: the residual ends with that many rows holding padded parameters (`fit_model`), which
n and p of s² leave out.
"""

from __future__ import annotations

import contextlib
import itertools
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx

# Residual (in units of the uncertainty) of a row where the model could not be evaluated (ODE
# budget, failed load balance, all-plastic contact): far above any real misfit, so that LM
# rejects the trial point.
FAILED_RESIDUAL = 1e6


RESTART_STEP = 1e-2  # a stalled fit restarts from points moved by ±1 % per free parameter
RESTART_SIGNS = ((1, 1, 1), (-1, -1, -1), (1, -1, 1), (-1, 1, -1))  # cycled over the parameters


def restart_factors(p: int) -> list:
    """The factors 1 + `RESTART_STEP`·sign of p parameters around which a stalled fit restarts,
    one array per pattern of `RESTART_SIGNS` (parameter k takes sign k mod 3): the restarts of
    the chain fit and of a record model's fit."""
    return [
        1.0 + RESTART_STEP * np.array([signs[k % len(signs)] for k in range(p)], dtype=float)
        for signs in RESTART_SIGNS
    ]


def gauss_newton_step(r, J):
    """The Gauss–Newton step −(JᵀJ)⁺Jᵀr from θ, in units of θ's standard errors; traceable.

    Standard errors from s²(JᵀJ)⁺ with s² = rᵀr/(n − p) (the residual scale estimated from the
    fit). Entries ≪ 1: the step still left is far below the statistical uncertainty. Directions
    with singular values below 1e-14 of the largest are dropped; a zero standard error gives inf.
    """
    r, J = jnp.asarray(r), jnp.asarray(J)
    u, sv, vt = jnp.linalg.svd(J, full_matrices=False)
    keep = sv > sv[0] * 1e-14
    inv = jnp.where(keep, 1.0 / jnp.where(keep, sv, 1.0), 0.0)
    step = -(vt.T @ ((u.T @ r) * inv))
    se = jnp.sqrt(jnp.sum((vt * inv[:, None]) ** 2, axis=0))
    n, p = J.shape
    s = jnp.maximum(jnp.sqrt(r @ r / max(n - p, 1)), 1e-300)
    return jnp.where(se > 0, step / jnp.where(se > 0, se * s, 1.0), jnp.inf)


# Progress of a running fit: a solver with `report=True` reports each step through
# `report_step` (a jax.debug.callback) on the channel the solve was given as an argument
# (`options["channel"]`, a run-time number: the compiled solve does not depend on the callable).
# Each open channel is one fit's `least_squares_fit(progress=...)`: fits running side by side
# (threads) report to their own callables.
_CHANNELS: dict[int, tuple] = {}
_NEXT_CHANNEL = itertools.count(1)


@contextlib.contextmanager
def progress_channel(progress):
    """The channel number of `progress` (a callable taking one line) while the block runs;
    0 (no channel) for None."""
    if progress is None:
        yield 0
        return
    channel = next(_NEXT_CHANNEL)
    _CHANNELS[channel] = (progress, time.perf_counter())
    try:
        yield channel
    finally:
        del _CHANNELS[channel]


def report_step(channel, shown, accepted, steps, cost, gn_step):
    """Host side of a solver step on `channel`: steps taken, ½‖r‖² at the last accepted point
    and, after an accepted step, the Gauss–Newton step left (max over parameters, in standard
    errors). Under `jax.vmap` the batch is summarised (most steps, summed cost, largest step
    left)."""
    target = _CHANNELS.get(int(np.max(channel)))
    if target is not None and np.any(shown):
        progress, t0 = target
        gn = f"Gauss-Newton step {np.max(gn_step):.2g} std errors"
        gn = gn if np.all(accepted) else "step rejected"
        progress(
            f"LM: {np.max(steps)} steps, cost {np.sum(cost):.8g}, {gn}, "
            f"{time.perf_counter() - t0:.1f} s"
        )


def quiet(**kwargs):
    """optimistix's `verbose` hook, silent (progress goes through `report_step`)."""


CRAWL_STEPS = 16  # the window of the `crawl` stop (steps)


class _RegionState(eqx.Module):
    step_size: jax.Array
    tried_gain: jax.Array  # ‖r‖² − ‖r + J·Δy‖² of the step just tried (Δy = y_eval − y)
    steps: jax.Array  # steps taken (the `crawl` stop's clock)
    marks: jax.Array  # ‖r‖² of the accepted point CRAWL_STEPS steps ago and 2·CRAWL_STEPS ago


class RelativeTrustRegion(optx.ClassicalTrustRegion):
    """Trust-region update of a radius in units of the Gauss–Newton step length
    (`optx.IndirectDampedNewtonDescent`), capped at 1: a rejection then shrinks the step at once
    instead of first undoing earlier growth (docs/fitting.md). Its state also keeps the decrease of
    ‖r‖² that the linearisation predicted for the step just tried, which `LevenbergMarquardt`'s
    `noise_tol` stop reads after a rejection. Every `CRAWL_STEPS` steps it also marks the cost
    reached, which the `crawl` stop reads."""

    def init(self, y, f_info_struct):
        one = jnp.array(1.0)
        return _RegionState(
            one, jnp.full_like(one, jnp.inf), jnp.array(0), jnp.full(2, jnp.inf, dtype=one.dtype)
        )

    def step(self, first_step, y, y_eval, f_info, f_eval_info, state):
        size, accept, result, _ = super().step(first_step, y, y_eval, f_info, f_eval_info, state)
        size = jnp.minimum(size, 1.0)
        r = f_info.residual
        tried = r @ r - jnp.sum(
            (r + f_info.jac.mv(jax.tree_util.tree_map(lambda a, b: a - b, y_eval, y))) ** 2
        )
        steps = jnp.where(first_step, 0, state.steps + 1)
        mark = ~first_step & (steps % CRAWL_STEPS == 0)
        marks = jnp.where(mark, jnp.stack([r @ r, state.marks[0]]), state.marks)
        return size, accept, result, _RegionState(size, tried, steps, marks)


class LevenbergMarquardt(optx.AbstractGaussNewton):
    """Levenberg–Marquardt with the statistical stops of the module docstring as fields."""

    rtol: float
    atol: float
    norm: object
    descent: object
    search: optx.ClassicalTrustRegion
    verbose: object
    step_tol: float | None = eqx.field(static=True, default=None)
    gain_tol: float | None = eqx.field(static=True, default=None)
    noise_tol: float | None = eqx.field(static=True, default=None)
    max_rejections: int | None = eqx.field(static=True, default=None)
    padded: int = eqx.field(static=True, default=0)
    report: bool = eqx.field(static=True, default=False)

    def __init__(
        self,
        rtol,
        atol,
        *,
        descent=None,
        search=None,
        step_tol=None,
        gain_tol=None,
        noise_tol=None,
        max_rejections=None,
        padded=0,
        report=False,
    ):
        self.rtol, self.atol, self.norm = rtol, atol, optx.max_norm
        self.descent = optx.DampedNewtonDescent(lx.QR()) if descent is None else descent
        self.search = optx.ClassicalTrustRegion() if search is None else search
        self.verbose = quiet
        self.step_tol, self.gain_tol, self.noise_tol = step_tol, gain_tol, noise_tol
        self.max_rejections, self.padded, self.report = max_rejections, padded, report

    @classmethod
    def noise_floor(cls, rtol, atol, max_rejections=6, step_tol=0.05, report=False):
        """For residuals through an adaptive ODE solve: textbook trust-region cutoffs (Nocedal &
        Wright, Alg. 4.1: shrink below ρ = 0.25, grow above 0.75; docs/fitting.md), the
        `step_tol` and `max_rejections` stops; with `report=True` each step is reported to
        `least_squares_fit(progress=...)` (a host callback: the solve is then not kept in the
        compilation cache, hence off by default)."""
        return cls(
            rtol,
            atol,
            descent=optx.DampedNewtonDescent(),
            search=optx.ClassicalTrustRegion(high_cutoff=0.75, low_cutoff=0.25),
            step_tol=step_tol,
            max_rejections=max_rejections,
            report=report,
        )

    @classmethod
    def record(cls, rtol, atol, *, gain_tol, noise_tol, max_rejections, padded):
        """For a record model with its effects (`fit_model`): radius in Gauss–Newton step
        lengths (cutoffs 0.25/0.75, growth 2 as MINPACK), the `gain_tol` and `noise_tol` stops."""
        search = RelativeTrustRegion(high_cutoff=0.75, low_cutoff=0.25, high_constant=2.0)
        return cls(
            rtol,
            atol,
            descent=optx.IndirectDampedNewtonDescent(),
            search=search,
            gain_tol=gain_tol,
            noise_tol=noise_tol,
            max_rejections=max_rejections,
            padded=padded,
        )

    def terminate(self, fn, y, args, options, state, tags):
        r, jac = state.f_info.residual, state.f_info.jac
        crawling = False
        since = state.num_steps_since_acceptance
        stop = state.terminate
        if self.max_rejections is not None:
            stop = stop | (since >= self.max_rejections)
        if self.step_tol is not None:
            fresh = (since == 0) & (state.num_accepted_steps > 0)
            test = fresh & ~state.first_step & jnp.all(r != FAILED_RESIDUAL)
            gn = jax.lax.cond(
                test,
                lambda: jnp.max(jnp.abs(gauss_newton_step(r, jac.as_matrix()))),
                lambda: jnp.asarray(jnp.inf, dtype=r.dtype),
            )
            if self.report:
                cost = 0.5 * jnp.sum(r**2)
                channel = (options or {}).get("channel", 0)
                jax.debug.callback(
                    report_step, channel, ~state.first_step, fresh, state.num_steps, cost, gn
                )
            stop = stop | (test & (gn < self.step_tol))
        if self.gain_tol is not None:
            J = jac.as_matrix()
            k = self.padded
            held = jnp.sum(jnp.diagonal(J[r.size - k :, J.shape[1] - k :]) != 0) if k else 0
            n, p = r.size - k, J.shape[1] - held
            floor = (options or {}).get("floor", 1.0)
            s2 = jnp.maximum(r @ r / jnp.maximum(n - p, 1), floor)
            gain = jnp.sum((jnp.linalg.qr(J)[0].T @ r) ** 2)
            # after a rejection: the decrease the rejected step promised (`RelativeTrustRegion`)
            rejected = state.search_state.tried_gain
            test = jnp.where(since == 0, gain < self.gain_tol * s2, rejected < self.noise_tol * s2)
            stop = stop | (~state.first_step & test)
            crawl = (options or {}).get("crawl")
            if crawl is not None and isinstance(state.search_state, _RegionState):
                clock, (now, before) = state.search_state.steps, state.search_state.marks
                crawling = (
                    (crawl > 0)
                    & (clock % CRAWL_STEPS == 0)
                    & (gain > 0.5 * (r @ r))
                    & (before - now < crawl * before)
                )
        budget = (options or {}).get("budget")
        if budget is not None:  # the step budget as a run-time value (`least_squares_fit`)
            spent = state.num_steps >= budget
            probe, limit = (options or {}).get("bar", (budget, jnp.inf))
            spent = spent | (~state.first_step & (state.num_steps >= probe) & (r @ r > limit))
            spent = spent | (~state.first_step & crawling)
            ran_out = spent & ~stop & (state.result == optx.RESULTS.successful)
            result = optx.RESULTS.where(
                ran_out, optx.RESULTS.nonlinear_max_steps_reached, state.result
            )
            return stop | spent, result
        return stop, state.result
