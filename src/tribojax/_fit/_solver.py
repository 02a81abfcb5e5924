"""Levenberg–Marquardt with statistical stops, for residuals computed through an ODE solve."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx

from ._engine import FAILED_RESIDUAL, gauss_newton_step, report_step


def quiet(**kwargs):
    """optimistix's `verbose` hook, silent (progress goes through `report_step`)."""


class NoiseFloorLM(optx.AbstractGaussNewton):
    """Levenberg–Marquardt (optimistix's damped-Newton descent and classical trust region, with
    the textbook cutoffs 0.25/0.75) with two statistical stops.

    1. After an accepted step, stop when the Gauss–Newton step still left from it is below
       `step_tol` standard errors in every parameter (scale s² = RSS/(n − p), as the fit's
       uncertainty model): further steps cannot move the estimate by a statistically visible
       amount. Not tried while a residual equals `FAILED_RESIDUAL`.
    2. After `max_rejections` consecutive rejected steps. A residual computed by an adaptive ODE
       solver depends on the parameters with jumps of the order of the solver tolerance, so near
       the optimum the trust region can shrink under that noise floor with every step rejected,
       which plain LM never recognises as termination.
    Both stops report success to optimistix; pass `optimum_tol` to `least_squares_fit` to have a
    stop with more than that many standard errors of Gauss–Newton step left reported as
    `RESULTS.short_of_optimum`. Optimistix's own Cauchy test (`rtol`, `atol`) still applies.
    Each step is reported to `least_squares_fit`'s `progress` callable (a jax.debug.callback).
    """

    rtol: float
    atol: float
    norm: object
    descent: optx.DampedNewtonDescent
    search: optx.ClassicalTrustRegion
    verbose: object
    max_rejections: int = eqx.field(static=True)
    step_tol: float = eqx.field(static=True)

    def __init__(self, rtol, atol, max_rejections=6, step_tol=0.05):
        self.rtol = rtol
        self.atol = atol
        self.norm = optx.max_norm
        self.descent = optx.DampedNewtonDescent()
        # Textbook trust-region update (Nocedal & Wright, Alg. 4.1: shrink below ρ = 0.25, grow
        # above 0.75) instead of optimistix's 0.01/0.99: with residuals from an ODE solve ρ
        # rarely exceeds 0.99, the region never grew and LM crept along flat valleys.
        self.search = optx.ClassicalTrustRegion(high_cutoff=0.75, low_cutoff=0.25)
        self.verbose = quiet
        self.max_rejections = max_rejections
        self.step_tol = step_tol

    def terminate(self, fn, y, args, options, state, tags):
        stalled = state.num_steps_since_acceptance >= self.max_rejections
        r = state.f_info.residual
        fresh = (state.num_steps_since_acceptance == 0) & (state.num_accepted_steps > 0)
        usable = jnp.all(r != FAILED_RESIDUAL)  # no failed rows
        test = fresh & ~state.first_step & usable
        gn = jax.lax.cond(
            test,
            lambda: jnp.max(jnp.abs(gauss_newton_step(r, state.f_info.jac.as_matrix()))),
            lambda: jnp.asarray(jnp.inf, dtype=r.dtype),
        )
        shown = ~state.first_step
        jax.debug.callback(report_step, shown, fresh, state.num_steps, 0.5 * jnp.sum(r**2), gn)
        small = test & (gn < self.step_tol)
        return state.terminate | stalled | small, state.result
