"""The friction-curve model: steady friction against velocity (a `FrictionCurve`), the
record model that `discover` (its effects: `_effects_curve`) and a saved steady-law fit
(`tribojax.fitted_model`) share.

Baseline (`curve_baseline`): Coulomb friction plus linear viscous friction, both directions,

    F(v) = sgn(v)·F_c + σ2·v,

F_c > 0 fitted as a logarithm, σ2 signed. Its physics knobs (null in brackets) are the terms of
the LuGre steady law (Canudas de Wit et al. 1995; wang2022 Eq 25 at constant velocity) and of a
power-law viscous term:

    F(v) = sgn(v)·[F_c + A·exp(−|v/v_s|^β)] + sgn(v)·σ2·v_ref·|v/v_ref|^δ + T0

* "stribeck" A/f_ref [0]: the static excess F_s − F_c (friction unit) over f_ref = median |F|;
* "log10_v_s" [log10(v_ref/10)], "log_beta" [ln 1.5]: the Stribeck velocity and exponent,
  nuisance values (they do nothing while A = 0);
* "asymmetry" T0/f_ref [0]: a level that adds to the friction in both directions, so the magnitudes
  differ by 2·T0 between them (a load such as gravity on the driven mass, a torque offset, or
  Coulomb levels F_c ± T0 that differ with the direction: the same model);
* "log_viscous_exponent" ln δ [0]: δ = 1 is the baseline's linear viscous term; δ < 1 a
  shear-thinning lubricant film, δ > 1 a rise steeper than linear.
v_ref is the largest |v| of the record, so σ2 keeps its meaning (the slope at |v| = v_ref).

Noise: each point's standard error of the mean, σ_i = scatter/√samples
(`FrictionCurve.friction_error`), the weights of `tribojax.fit_steady_curve`. The engine takes
one noise level, so the record is compared in weighted form: y_i = F_i·σ̄/σ_i with
σ̄ = rms(σ_i), the noise of every y_i is then σ̄ and a residual r_i·σ_i/σ̄ is in the friction
unit. The points are independent measurements: AR(1) ρ = 0. Abscissa: the velocity; segments:
0 = "negative", 1 = "positive" direction (windows never straddle the reversal).
"""

from __future__ import annotations

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .._friction._lugre import stribeck_curve
from .._io._friction_curve import FrictionCurve
from ._base import AbstractBaseline, RecordData

CURVE_KNOBS = ("stribeck", "log10_v_s", "log_beta", "asymmetry", "log_viscous_exponent")
DIRECTION_NAMES = {0: "negative", 1: "positive"}
BETA_START = 1.5  # Stribeck exponent the refit starts from (between exponential and Gaussian)


class CurveBaseline(AbstractBaseline):
    """Coulomb + linear viscous friction (F_c in the friction unit, σ2 in friction per velocity
    unit; θ = (ln(F_c/f_ref), σ2·v_ref/f_ref)) of a friction curve; knobs as in the module
    docstring."""

    kind: ClassVar[str] = "curve"
    param_names: ClassVar[tuple[str, ...]] = ("F_c", "sigma2")
    knob_names: ClassVar[tuple[str, ...]] = CURVE_KNOBS
    v: Array  # velocity of each point (velocity unit), no zeros
    f: Array  # mean friction of each point (friction unit)
    weight: Array  # σ̄/σ_i per point
    sigma_bar: Array  # rms of the per-point standard errors (friction unit)
    v_ref: Array  # largest |v| (velocity unit)
    f_ref: Array  # median |F| (friction unit)
    theta0: Array
    units: tuple = eqx.field(static=True)  # (velocity unit, friction unit)
    unit_of_params: tuple = eqx.field(static=True)  # units of F_c and σ2 (from the record's)

    @property
    def param_units(self):
        return self.unit_of_params

    def param_ranges(self):
        """F_c > 0 (θ₀ is its log), σ2 any real (`physical`)."""
        return ((0.0, np.inf), (-np.inf, np.inf))

    def knob_null(self):
        return np.array([0.0, np.log10(float(self.v_ref) / 10.0), np.log(BETA_START), 0.0, 0.0])

    def start(self):
        return np.asarray(self.theta0)

    def physical(self, theta):
        return jnp.stack([self.f_ref * jnp.exp(theta[0]), theta[1] * self.f_ref / self.v_ref])

    def theta_of(self, values):
        F_c, sigma2 = (float(v) for v in values)
        return np.array([np.log(F_c / float(self.f_ref)), sigma2 * float(self.v_ref / self.f_ref)])

    def friction(self, theta, knobs):
        """The model friction at the record's velocities (friction unit), before weighting."""
        F_c, sigma2 = self.physical(theta)
        A, log10_vs, log_beta, T0, log_delta = (knobs[i] for i in range(5))
        A, T0 = A * self.f_ref, T0 * self.f_ref  # knobs in units of f_ref
        g = stribeck_curve(self.v, F_c, F_c + A, 10.0**log10_vs, jnp.exp(log_beta))
        s = jnp.sign(self.v)
        visc = sigma2 * self.v_ref * (jnp.abs(self.v) / self.v_ref) ** jnp.exp(log_delta)
        return s * g + s * visc + T0

    def predict(self, theta, knobs):
        return self.friction(theta, knobs) * self.weight

    def noise_model(self, r):
        return float(self.sigma_bar), 0.0  # independent points of known standard error

    def folds(self):
        """Alternate points in order of velocity (independent points: each fold spans the
        whole velocity range)."""
        rank = np.argsort(np.argsort(np.asarray(self.v)))
        return rank % 2

    def signals(self):
        vu = self.units[0]
        v = np.asarray(self.v)
        return {f"velocity ({vu})": v, f"|velocity| ({vu})": np.abs(v)}

    def data(self):
        vu, fu = self.units
        return RecordData(
            y=np.asarray(self.f * self.weight),
            x=np.asarray(self.v),
            segment=(np.asarray(self.v) > 0).astype(int),
            noise_std=float(self.sigma_bar),
            x_label=f"velocity ({vu})",
            y_label=f"friction, weighted ({fu})",
            segment_names=dict(DIRECTION_NAMES),
        )


def curve_baseline(curve: FrictionCurve) -> CurveBaseline:
    """The Coulomb + viscous baseline of a friction curve, started from the weighted linear
    least-squares fit of F = sgn(v)·F_c + σ2·v. ValueError for a point at zero velocity (its
    direction is unknown) or fewer than 4 points."""
    if not isinstance(curve, FrictionCurve):
        raise ValueError(f"curve must be a FrictionCurve record, got {type(curve).__name__}")
    v, f = np.asarray(curve.velocity, float), np.asarray(curve.friction, float)
    zero = np.flatnonzero(v == 0.0)
    if zero.size:
        raise ValueError(f"{curve.source}: velocity[{zero[0]}] = 0; every point needs a direction")
    if v.size < 4:
        raise ValueError(f"{curve.source}: {v.size} points; curve discovery needs at least 4")
    order = np.argsort(v)
    v, f, err = v[order], f[order], np.asarray(curve.friction_error, float)[order]
    sigma_bar = float(np.sqrt(np.mean(err**2)))
    v_ref, f_ref = float(np.max(np.abs(v))), float(np.median(np.abs(f)))
    design = np.stack([np.sign(v), v], axis=1) / err[:, None]
    F_c, sigma2 = np.linalg.lstsq(design, f / err, rcond=None)[0]
    F_c = F_c if F_c > 0 else f_ref  # a curve whose level does not follow the direction
    theta0 = np.array([np.log(F_c / f_ref), sigma2 * v_ref / f_ref])
    vu, fu = curve.units["velocity_unit"], curve.units["friction_unit"]
    return CurveBaseline(
        v=jnp.asarray(v),
        f=jnp.asarray(f),
        weight=jnp.asarray(sigma_bar / err),
        sigma_bar=jnp.asarray(sigma_bar),
        v_ref=jnp.asarray(v_ref),
        f_ref=jnp.asarray(f_ref),
        theta0=jnp.asarray(theta0),
        units=(vu, fu),
        unit_of_params=(fu, f"{fu} per {vu}"),
    )
