"""Differentiable design quantities of a friction-damped structure, and the 2-DOF benchmark.

Every quantity is a JAX function of the `FrictionSystem` pytree, differentiable as `solve_hbm`
(implicit function theorem, dX/dp = −(∂R/∂X)⁻¹ ∂R/∂p).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._friction._elastic2d import ElasticDryFriction2D
from .._presets import FRF_2DOF
from .._results import RESULTS
from ._mhb import FrictionSystem, _solve
from ._structure import DryFrictionContact2D, Excitation, Structure


def frf_2dof_system(F, *, H: int | None = None, n_time: int | None = None) -> FrictionSystem:
    """The 2-DOF elastic dry-friction benchmark at forcing level F (N): M = I, K = diag(12, 21),
    C = diag(2·0.05·√12, 2·0.1·√100), contact k_t = 5, k_n = 21, μ = 0.85 (DOF 0 tangential,
    DOF 1 normal), static force (0, 100) N, cosine force (1, 0.1)·F; harmonics 0…H (default 8)."""
    b = FRF_2DOF
    structure = Structure(b["M"], np.diag(b["C_diag"]), b["K"])
    contact = DryFrictionContact2D(ElasticDryFriction2D(b["k_t"], b["k_n"], b["mu"]), 0, 1)
    F = jnp.asarray(F, dtype=jnp.float64)
    ex = Excitation(2, static=b["static"], cosine=F * jnp.asarray(b["direction"]))
    H = b["H"] if H is None else H
    return FrictionSystem(structure, [contact], ex, H=H, n_time=n_time)


def amplitude_at(system: FrictionSystem, omega, dof: int = 0, X0=None, *, solver=None):
    """First-harmonic amplitude (m) of `dof` at ω (rad/s); NaN-free, check `solve_hbm` for
    convergence. Differentiable in every leaf of `system` and in ω (implicit function theorem)."""
    solver = optx.Dogleg(rtol=1e-10, atol=1e-10) if solver is None else solver
    sol = _solve(system, jnp.asarray(omega, dtype=jnp.float64), X0, solver, 100)
    return system.amplitude(sol.X)[dof]


def _slope(omega, args):
    system, dof, X0 = args
    return jax.grad(amplitude_at, argnums=1)(system, omega, dof, X0)


class Peak(eqx.Module):
    """A resonance peak: omega (rad/s), amplitude (m), result (`RESULTS`)."""

    omega: jax.Array
    amplitude: jax.Array
    result: RESULTS


def resonance_peak(
    system: FrictionSystem,
    omega_guess,
    dof: int = 0,
    X0=None,
    *,
    bracket=None,
    tol: float = 1e-9,
    max_steps: int = 40,
) -> Peak:
    """The resonance peak of `dof` near ω = omega_guess (rad/s): root of ∂a/∂ω by Newton.

    X0: the MHB coefficients near the peak (default the linear solution; give them from a
    continuation for strongly nonlinear cases). `bracket` (lo, hi): the peak must lie inside,
    otherwise the result is `nonlinear_divergence` at the guess. Derivatives: dω*/dp = −g_p/g_ω
    with g = ∂a/∂ω (implicit function theorem) and da*/dp = ∂a/∂p (envelope theorem).
    """
    w0 = jnp.asarray(omega_guess, dtype=jnp.float64)
    solver = optx.Newton(rtol=tol, atol=tol)
    sol = optx.root_find(_slope, solver, w0, (system, dof, X0), max_steps=max_steps, throw=False)
    ok = (sol.result == optx.RESULTS.successful) & jnp.isfinite(sol.value)
    if bracket is not None:
        ok = ok & (sol.value >= bracket[0]) & (sol.value <= bracket[1])
    code = RESULTS.where(
        sol.result == optx.RESULTS.successful,
        RESULTS.nonlinear_divergence,
        RESULTS.promote(sol.result),
    )
    omega = jnp.where(ok, sol.value, w0)
    result = RESULTS.where(ok, RESULTS.successful, code)
    return Peak(omega=omega, amplitude=amplitude_at(system, omega, dof, X0), result=result)


def _amp_slope(system, omega, X0, dof, solver):
    """(X, ∂a/∂ω, ok) at ω: the MHB solution from X0 and the slope of the amplitude a (forward
    mode through the implicit function theorem, dX/dω = −(∂R/∂X)⁻¹ ∂R/∂ω)."""

    def solve(w):
        sol = _solve(system, w, X0, solver, 100)
        return sol.X, sol.result == RESULTS.successful

    (X, ok), (dX, _) = eqx.filter_jvp(solve, (omega,), (jnp.ones_like(omega),))
    i, j = system.index(1), system.index(1, True)
    a = jnp.hypot(X[dof, i], X[dof, j])
    g = (X[dof, i] * dX[dof, i] + X[dof, j] * dX[dof, j]) / jnp.where(a > 0, a, 1.0)
    return X, g, ok


def peak_on_grid(
    system: FrictionSystem, omegas, dof: int = 0, *, tol: float = 1e-9, refine_steps: int = 16
) -> Peak:
    """Resonance peak of `dof` from a grid of frequencies (rad/s, ascending, spanning the peak).

    Natural continuation along the grid (each solve started from the previous solution); around
    the largest amplitude, the root of g = ∂a/∂ω inside the two neighbouring grid points by
    `refine_steps` (static) steps of regula falsi with the Illinois modification (Dowell & Jarratt
    1971; bracketing, so it cannot leave the peak's interval; g by forward-mode implicit
    differentiation of the MHB solution). Fixed work per system, so it vmaps over systems (for
    hundreds of systems: docs/structures.md). `result` is successful when every solve converged,
    g changes sign across the interval, and the last Newton correction |g/g_ω| is <= tol·ω;
    otherwise `nonlinear_divergence` (the best point is still returned; a peak on a kink of a(ω)
    has no stationary point: docs/structures.md). Derivatives: as `resonance_peak`'s.
    """
    omegas = jnp.asarray(omegas, dtype=jnp.float64)
    # every array leaf cut from differentiation for the search itself
    frozen = jax.tree.map(lambda v: jax.lax.stop_gradient(v) if eqx.is_array(v) else v, system)
    solver = optx.Dogleg(rtol=tol, atol=tol)

    def body(X, w):
        sol = _solve(frozen, w, X, solver, 100)
        return sol.X, (sol.X, frozen.amplitude(sol.X)[dof], sol.result == RESULTS.successful)

    X0 = frozen.linear_solution(omegas[0]) * 0.0
    _, (Xs, amps, oks) = jax.lax.scan(body, X0, omegas)
    i = jnp.argmax(amps)
    n = omegas.shape[0]
    inner = (i > 0) & (i < n - 1)
    lo, hi = omegas[jnp.maximum(i - 1, 0)], omegas[jnp.minimum(i + 1, n - 1)]
    fine = oks[jnp.maximum(i - 1, 0)] & oks[i] & oks[jnp.minimum(i + 1, n - 1)]
    _, g_lo, ok_lo = _amp_slope(frozen, lo, Xs[jnp.maximum(i - 1, 0)], dof, solver)
    _, g_hi, ok_hi = _amp_slope(frozen, hi, Xs[jnp.minimum(i + 1, n - 1)], dof, solver)
    bracketed = inner & fine & ok_lo & ok_hi & (g_lo > 0) & (g_hi < 0)

    def illinois(c, _):
        lo, g_lo, hi, g_hi, side, X, ok = c
        den = g_lo - g_hi
        w = lo + g_lo * (hi - lo) / jnp.where(den != 0, den, 1.0)
        w = jnp.where((w > lo) & (w < hi), w, 0.5 * (lo + hi))
        X, g, ok_w = _amp_slope(frozen, w, X, dof, solver)
        up = g > 0  # the peak lies above w
        g_hi = jnp.where(up & (side > 0), 0.5 * g_hi, g_hi)  # Illinois: halve the kept end
        g_lo = jnp.where(~up & (side < 0), 0.5 * g_lo, g_lo)
        lo, g_lo = jnp.where(up, w, lo), jnp.where(up, g, g_lo)
        hi, g_hi = jnp.where(up, hi, w), jnp.where(up, g_hi, g)
        return (lo, g_lo, hi, g_hi, jnp.where(up, 1, -1), X, ok & ok_w), w

    init = (lo, g_lo, hi, g_hi, jnp.asarray(0), Xs[i], jnp.asarray(True))
    (*_, X_last, ok_all), ws = jax.lax.scan(illinois, init, None, length=refine_steps)
    w_star = jnp.where(bracketed, ws[-1], omegas[i])
    X_star = jax.lax.stop_gradient(jnp.where(bracketed, X_last, Xs[i]))
    # g and g_ω at ω*: success test (Newton correction) and the IFT derivative of ω*
    g_star = _slope(w_star, (system, dof, X_star))
    g_w = jax.jvp(lambda w: _slope(w, (frozen, dof, X_star)), (w_star,), (jnp.ones(()),))[1]
    g_w = jax.lax.stop_gradient(g_w)
    newton = jax.lax.stop_gradient(g_star) / jnp.where(g_w != 0, g_w, -1.0)
    ok = bracketed & ok_all & (g_w < 0) & (jnp.abs(newton) <= tol * w_star)
    omega = w_star - jnp.where(ok, (g_star - jax.lax.stop_gradient(g_star)) / g_w, 0.0)
    amplitude = amplitude_at(system, w_star, dof, X_star)
    result = RESULTS.where(ok, RESULTS.successful, RESULTS.nonlinear_divergence)
    return Peak(omega=omega, amplitude=amplitude, result=result)


class PeakDesign(eqx.Module):
    """A minimised resonance peak: params (the optimum, in the units of `make_system`'s
    argument), peak (`Peak` there), result (`RESULTS`), steps (optimiser steps)."""

    params: jax.Array
    peak: Peak
    result: RESULTS
    steps: jax.Array


def _log_peak(log_p, args):
    make_system, omegas, dof = args
    return jnp.log(peak_on_grid(make_system(jnp.exp(log_p)), omegas, dof).amplitude)


def minimise_peak(
    make_system, p0, omegas, dof: int = 0, *, rtol: float = 1e-6, max_steps: int = 60
) -> PeakDesign:
    """Gradient-based design: the positive parameters p (e.g. [N] or [N, K_d]) minimising the
    resonant amplitude of `dof`, by BFGS (optimistix) on log p with the implicit-function-theorem
    gradient of `peak_on_grid(make_system(p), omegas)`.

    make_system(p) builds the `FrictionSystem` with JAX operations; p0 (> 0) the start; omegas
    the frequency grid (rad/s) spanning the peak for every p visited.
    """
    p0 = jnp.atleast_1d(jnp.asarray(p0, dtype=jnp.float64))
    if not isinstance(p0, jax.core.Tracer) and not bool(jnp.all(p0 > 0)):
        raise ValueError(f"p0 = {np.asarray(p0)} must be > 0 (log-parametrised)")
    args = (make_system, jnp.asarray(omegas, dtype=jnp.float64), dof)
    sol = optx.minimise(
        _log_peak,
        optx.BFGS(rtol=rtol, atol=rtol),
        jnp.log(p0),
        args,
        max_steps=max_steps,
        throw=False,
    )
    p = jnp.exp(sol.value)
    peak = peak_on_grid(make_system(p), args[1], dof)
    return PeakDesign(
        params=p, peak=peak, result=RESULTS.promote(sol.result), steps=sol.stats["num_steps"]
    )
