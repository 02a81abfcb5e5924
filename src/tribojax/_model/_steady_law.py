"""Fits to steady friction curves (the LuGre steady law) and to friction transients.

Steady law (wang2022 Eq 25 at constant velocity; the Stribeck curve of Canudas de Wit et al.):

    F(v) = sgn(v)·[F_c + (F_s − F_c)·exp(−|v/v_s|^β)] + σ2·v (+ T0)

fitted per direction (a curve's points of one velocity sign) or jointly over both directions
with a direction asymmetry T0, a constant force (torque) that adds to the friction in both
directions (a load such as gravity on the driven mass, or a sensor offset): the friction
magnitudes then differ by 2·T0 between the directions. Each point is weighted by the standard
error of its mean (`FrictionCurve.friction_error`). The LuGre dynamic parameters σ0 and σ1 are
then fitted to a transient with the steady law held fixed (`fit_transient`).
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._fit._engine import least_squares_fit
from .._fit._measures import nrmse
from .._fit._result import FitResult, thrown
from .._fit._solver import LevenbergMarquardt
from .._friction._lugre import LuGre, stribeck_curve
from .._io._friction_curve import FrictionCurve, FrictionTransient
from .._limits import STEADY_STARTS

# the noise-floor LM (docs/fitting.md, "Why some fit rules are set where they are")
_SOLVER = LevenbergMarquardt.noise_floor(1e-10, 1e-12)

STEADY_NAMES = ("F_c", "F_s", "v_s", "beta", "sigma2")


class _StribeckResiduals(eqx.Module):
    """(steady law − measured friction)/its standard error; θ = log(F_c, F_s, v_s, β, σ2)
    [+ T0/sd(f) when `joint`] (wang2022 Eq 25 at constant velocity)."""

    joint: bool = eqx.field(static=True)

    def __call__(self, theta, args):
        v, f, err = args
        p = jnp.exp(theta[:5])
        model = jnp.sign(v) * stribeck_curve(v, p[0], p[1], p[2], p[3]) + p[4] * v
        if self.joint:
            model = model + theta[5] * jnp.std(f)
        return (model - f) / err


def _steady_start(v, f, beta=2.0, v_factor=1.0) -> np.ndarray:
    a, s = np.abs(v), np.abs(f)
    order = np.argsort(a)
    F_c = float(np.min(s))
    F_s = float(max(s[order[0]], 1.05 * F_c))
    v_s = v_factor * float(max(a[np.argmin(s)] / 2.0, a[order[0]]))
    top = order[-max(3, len(a) // 4) :]
    slope = np.polyfit(a[top], s[top], 1)[0] if len(top) > 1 else 0.0
    sigma2 = float(max(slope, 1e-3 * F_c / a.max()))
    return np.log([F_c, F_s, v_s, beta, sigma2])


def fit_steady_curve(
    curve: FrictionCurve, *, direction=None, max_steps: int = 2000, throw: bool = True
) -> FitResult:
    """Fit the LuGre steady law to a friction curve (see the module docstring).

    Args:
        curve: a `FrictionCurve` (any consistent units; the parameters take the curve's units:
            F_c, F_s, T0 in the friction unit, v_s in the velocity unit, σ2 in friction per
            velocity unit, β dimensionless).
        direction: +1 or −1 fits the points of that velocity sign alone; None fits both
            directions with the asymmetry T0.
        max_steps: LM budget of each start (the noise-floor LM, `_SOLVER`; a step costs
            microseconds). Fitted from each of `STEADY_STARTS`; the lowest misfit of the
            converged fits is kept (of all, if none converged).
        throw: raise `FitError` if the fit does not converge (False: return it flagged).
    Returns:
        FitResult with names (F_c, F_s, v_s, beta, sigma2) [+ T0]; positive parameters fitted
        as logarithms, standard errors from the per-point scatter (inflated by the residual if
        the reduced χ² exceeds the noise limit, then `noise_consistent` is False);
        `fixed` holds the direction and the units.
    """
    if direction not in (None, 1, -1):
        raise ValueError(f"direction must be +1, -1 or None (both), got {direction!r}")
    c = curve if direction is None else curve.direction(direction)
    if len(c.velocity) < 5 + (direction is None):
        raise ValueError(f"{curve.source}: {len(c.velocity)} points are too few for this fit")
    v, f, err = (jnp.asarray(x) for x in (c.velocity, c.friction, c.friction_error))
    joint = direction is None
    scale = float(np.std(c.friction))  # θ of T0 in units of the friction's sd
    T0 = []
    if joint:
        pos, neg = np.abs(c.friction[c.velocity > 0]), np.abs(c.friction[c.velocity < 0])
        if not (pos.size and neg.size):
            raise ValueError(f"{curve.source}: a joint fit needs points in both directions")
        T0 = [0.5 * (np.median(pos) - np.median(neg)) / scale]
    names = STEADY_NAMES + (("T0",) if joint else ())

    def tr(theta):  # T0 in the friction unit
        out = jnp.exp(theta[:5])
        return jnp.concatenate([out, theta[5:] * scale]) if joint else out

    fits = [
        least_squares_fit(
            _StribeckResiduals(joint),
            jnp.asarray(np.append(_steady_start(np.asarray(v), np.asarray(f), b, k), T0)),
            (v, f, err),
            names=names,
            transform=tr,
            sigma_known=True,
            max_steps=max_steps,
            jac="fwd",
            solver=_SOLVER,
            throw=False,
        )
        for b, k in STEADY_STARTS
    ]
    kept = [ft for ft in fits if ft.converged] or fits
    fit = min(kept, key=lambda ft: float(np.sum(np.square(ft.residuals))))
    fixed = {"direction": "both" if joint else int(direction), **c.units}
    return thrown(dataclasses.replace(fit, fixed=fixed), throw)


class _TransientResiduals(eqx.Module):
    """LuGre (α = 1) stepped exactly at each interval's mean velocity; θ = log(σ0, σ1)."""

    def __call__(self, theta, args):
        law, T0, v, h, f, moving, err = args  # moving: indices of the fitted samples
        el = dataclasses.replace(law, sigma0=jnp.exp(theta[0]), sigma1=jnp.exp(theta[1]))
        vm = 0.5 * (v[1:] + v[:-1])

        def step(z, inp):
            vel, dt = inp
            z = el.constant_velocity_step(z, vel, dt)
            return z, el.force(z, vel)

        _, force = jax.lax.scan(step, el.initial_state(), (vm, h))
        model = jnp.concatenate([jnp.zeros(1), force]) + T0
        return ((model - f) / err)[moving]


def _transient_args(tr: FrictionTransient, p: dict, curve_error=None):
    """The residuals' args from the steady law's parameters `p` by name (T0: 0 if absent)."""
    law = LuGre(1.0, 0.0, p["sigma2"], p["F_c"], p["F_s"], p["v_s"], 1.0, p["beta"])
    T0 = float(p.get("T0", 0.0))
    moving = jnp.asarray(np.flatnonzero(tr.velocity != 0.0))  # at rest the drive is off
    err = curve_error if curve_error is not None else float(np.std(tr.friction[tr.velocity != 0]))
    return (
        law,
        T0,
        jnp.asarray(tr.velocity),
        jnp.asarray(np.diff(tr.t)),
        jnp.asarray(tr.friction),
        moving,
        err,
    )


def fit_transient(
    tr: FrictionTransient,
    steady: FitResult,
    *,
    sigma=None,
    start=(1.0, 1e-3),
    max_steps: int = 300,
    throw: bool = True,
) -> FitResult:
    """Fit LuGre's bristle stiffness σ0 and damping σ1 to a start–stop transient, the steady
    law (and asymmetry T0) fixed from `fit_steady_curve`.

    The bristle state is stepped exactly over each sample interval at the interval's mean
    measured velocity (`LuGre.constant_velocity_step`, α = 1) from rest; only samples where the
    measured velocity is non-zero are fitted (the drive is switched off at rest and reads 0).
    sigma: the friction noise (default: the standard deviation of the moving samples' friction).
    start: (σ0, σ1) in the record's units (friction per angle or length, and per velocity).
    throw: raise `FitError` if the fit does not converge (False: return it flagged).
    Returns FitResult with names (sigma0, sigma1), fitted as logarithms; the sampling of the
    record bounds what can be resolved (standard errors and `unidentifiable` say so).
    """
    law = dict(zip(steady.names, steady.values.tolist()))
    fit = least_squares_fit(
        _TransientResiduals(),
        jnp.log(jnp.asarray(start)),
        _transient_args(tr, law, sigma),
        names=("sigma0", "sigma1"),
        transform=jnp.exp,
        sigma_known=sigma is not None,
        max_steps=max_steps,
        jac="fwd",
        solver=_SOLVER,
        throw=False,
    )
    return thrown(dataclasses.replace(fit, fixed={"steady": law}), throw)


def transient_nrmse(fit: FitResult, tr: FrictionTransient) -> float:
    """NRMSE of a `fit_transient` result over the record's moving samples."""
    args = _transient_args(tr, fit.fixed["steady"], 1.0)
    r = np.asarray(_TransientResiduals()(jnp.asarray(fit.theta), args))
    return nrmse(r, tr.friction[tr.velocity != 0])
