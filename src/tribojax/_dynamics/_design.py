"""Differentiable design quantities of a friction-damped structure, and the 2-DOF benchmark.

Every quantity is a JAX function of the `FrictionSystem` pytree (μ, N, K_d, M, C, K, forcing are
leaves), so `jax.grad` / `equinox.filter_grad` give its derivatives. They follow from the implicit
function theorem through the MHB solution (optimistix's implicit adjoint of `solve_hbm`):
dX/dp = −(∂R/∂X)⁻¹ ∂R/∂p, never from unrolled Newton iterations.

* `amplitude_at`: first-harmonic amplitude of one DOF at a given ω;
* `resonance_peak`: (ω*, a*) where da/dω = 0, a second root-find on g(ω) = ∂a/∂ω, itself
  differentiated implicitly: dω*/dp = −g_p / g_ω, and da*/dp = ∂a/∂p (envelope theorem);
* `peak_on_grid`: a vmappable peak search (natural continuation along an ω grid, then
  `resonance_peak`) for design curves over many normal loads.
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


def _newton(tol=1e-10):
    return optx.Newton(rtol=tol, atol=tol)


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


def resonance_peak(system: FrictionSystem, omega_guess, dof: int = 0, X0=None, *,
                   bracket=None, tol: float = 1e-9, max_steps: int = 40) -> Peak:  # fmt: skip
    """The resonance peak of `dof` near ω = omega_guess (rad/s): root of ∂a/∂ω by Newton.

    X0: the MHB coefficients near the peak (default the linear solution; give them from a
    continuation for strongly nonlinear cases). `bracket` (lo, hi): the peak must lie inside,
    otherwise the result is `nonlinear_divergence` at the guess. Derivatives of `Peak.omega` and
    `Peak.amplitude` by the implicit function theorem (module docstring).
    """
    w0 = jnp.asarray(omega_guess, dtype=jnp.float64)
    sol = optx.root_find(_slope, _newton(tol), w0, (system, dof, X0), max_steps=max_steps,
                         throw=False)  # fmt: skip
    ok = (sol.result == optx.RESULTS.successful) & jnp.isfinite(sol.value)
    if bracket is not None:
        ok = ok & (sol.value >= bracket[0]) & (sol.value <= bracket[1])
    code = RESULTS.where(sol.result == optx.RESULTS.successful, RESULTS.nonlinear_divergence,
                         RESULTS.promote(sol.result))  # fmt: skip
    omega = jnp.where(ok, sol.value, w0)
    result = RESULTS.where(ok, RESULTS.successful, code)
    return Peak(omega=omega, amplitude=amplitude_at(system, omega, dof, X0), result=result)


def peak_on_grid(system: FrictionSystem, omegas, dof: int = 0) -> Peak:
    """Resonance peak of `dof` from a grid of frequencies (rad/s, ascending, spanning the peak):
    natural continuation along the grid (each solve started from the previous solution), the
    largest amplitude refined by `resonance_peak`. Fixed work, so it vmaps over systems."""
    omegas = jnp.asarray(omegas, dtype=jnp.float64)
    solver = optx.Dogleg(rtol=1e-9, atol=1e-9)

    def body(X, w):
        sol = _solve(system, w, X, solver, 100)
        return sol.X, (sol.X, system.amplitude(sol.X)[dof])

    X0 = system.linear_solution(omegas[0]) * 0.0
    _, (Xs, amps) = jax.lax.scan(body, X0, omegas)
    i = jnp.argmax(amps)
    n = omegas.shape[0]
    lo, hi = omegas[jnp.maximum(i - 1, 0)], omegas[jnp.minimum(i + 1, n - 1)]
    return resonance_peak(system, omegas[i], dof, jax.lax.stop_gradient(Xs[i]), bracket=(lo, hi))


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


def minimise_peak(make_system, p0, omegas, dof: int = 0, *, rtol: float = 1e-6,
                  max_steps: int = 60) -> PeakDesign:  # fmt: skip
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
    sol = optx.minimise(_log_peak, optx.BFGS(rtol=rtol, atol=rtol), jnp.log(p0), args,
                        max_steps=max_steps, throw=False)  # fmt: skip
    p = jnp.exp(sol.value)
    peak = peak_on_grid(make_system(p), args[1], dof)
    return PeakDesign(params=p, peak=peak, result=RESULTS.promote(sol.result),
                      steps=sol.stats["num_steps"])  # fmt: skip
