"""The slip model's effects: the additive ones (`sensor_drift`, `position_error`, `vibration`),
then the friction law's knobs of the one pre-slip element (`load_coupling`, `stribeck`,
`viscous_friction`: `_friction_effects`, written once for every record kind); the model and its
knobs are `tribojax._model.SlipBaseline`'s."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ._base import EffectDesign
from ._effects import AbstractEffect
from ._effects_friction import LoadDependence, Stribeck, Viscous
from ._fit import record_scale
from ._modes import golden_max, oscillator
from ._slip import KNOBS, N_ODE_KNOBS, ZETA_MAX, stage_travel

ZETA_AT_BOUND = 0.98  # a refitted mode with ζ ≥ this × ZETA_MAX is at its bound (`reject`)


def _unit_rms(col):
    rms = float(np.sqrt(np.mean(col**2)))
    return col / rms if rms > 0 else col


class SensorDrift(AbstractEffect):
    """Smooth additive drift of the slip reading: a Legendre series in time, c₀P₀(s) + … +
    c_dP_d(s), s = scaled time ∈ [−1, 1], of degree d ∈ `degrees` (a grid chosen by the score:
    3 for a polynomial or thermal drift; a wandering, random-walk-like drift needs more terms:
    degree d resolves wanderings slower than about T/d)."""

    name: ClassVar[str] = "sensor_drift"
    kind: ClassVar[str] = "slip"
    degrees: tuple = (3, 6, 9)
    # every degree is refitted: at a large misfit the score saturates (S → n) for all of them
    # and cannot choose; the lowest BIC among the refits is kept
    refit_starts: ClassVar[int] = 3

    def designs(self, baseline):
        t = np.asarray(baseline.t)
        s = 2 * (t - t[0]) / (t[-1] - t[0]) - 1
        ys = record_scale(baseline)
        out = []
        for deg in self.degrees:
            k = deg + 1
            out.append(
                EffectDesign(
                    tuple(f"c{i}" for i in range(k)),
                    ("m",) * k,
                    np.full(k, ys),
                    nuisance={"degree": float(deg)},
                    basis=np.polynomial.legendre.legvander(s, deg) * ys,
                )
            )
        return out


class PositionError(AbstractEffect):
    """Reading error that grows with stage travel x_s(t) (fibre bending, Abbe and cosine
    errors): ε·x_s, or ε·x_s + ε₂·x_s² (`degrees` 1 and 2, both refitted, the lower BIC kept):
    the first two Taylor terms of a smooth error that is zero at the start (why the second:
    docs/discovery.md)."""

    name: ClassVar[str] = "position_error"
    kind: ClassVar[str] = "slip"
    degrees: tuple = (1, 2)
    refit_starts: ClassVar[int] = 2  # every degree is refitted (the score cannot choose)

    def designs(self, baseline):
        _, x = stage_travel(baseline.t, baseline.accel)
        ys = record_scale(baseline)
        rms = float(np.sqrt(np.mean(x**2))) or 1.0
        u = x / rms
        out = []
        for deg in self.degrees:
            names, units = ("epsilon", "epsilon2")[:deg], ("m/m", "m/m^2")[:deg]
            out.append(
                EffectDesign(
                    names,
                    units,
                    ys / rms ** np.arange(1, deg + 1),
                    nuisance={"degree": float(deg)},
                    basis=np.stack([u**j * ys for j in range(1, deg + 1)], 1),
                )
            )
        return out


class Vibration(AbstractEffect):
    """A lightly damped structural mode excited by the stage acceleration, seen in the reading.

    Additive A₁q_s + A₂q̇/ω (two signed amplitudes set the phase), q of q̈ + 2ζωq̇ + ω²q = −a(t)
    and q_s = q (the full response, `static` 1) or q + a/ω² (its dynamic part, `static` 0: the
    quasi-static deflection −a/ω² compensated, e.g. by a feed-forward; `SlipBaseline._mode`);
    q̇ is also the response to the jerk. Natural frequency and damping ratio seeded by a grid
    (default 40 frequencies between 3/T and 0.4 × the sampling rate, capped at 500 Hz,
    × ζ ∈ {0.01, 0.03, 0.1} × both forms) refined around the best grid point by golden-section
    searches on the score (log f within one grid step, then log ζ within a factor 3), then
    fitted jointly with the amplitudes in the refit (knobs `mode_*`). Why both forms:
    docs/discovery.md, "Why each rule is set where it is".
    """

    name: ClassVar[str] = "vibration"
    kind: ClassVar[str] = "slip"
    zetas: tuple = (0.01, 0.03, 0.1)
    statics: tuple = (1.0, 0.0)
    n_freq: int = 40
    refit_starts: ClassVar[int] = 2  # the best design by score, and the best of the other form

    def design(self, baseline, f, z, static=1.0):
        return self._designs(baseline, [(f, z)], (static,))[0]

    def _designs(self, baseline, pairs, statics):
        """Designs for every (f, z) pair in each static form (the oscillator runs once)."""
        ys = record_scale(baseline)
        f, z = np.asarray(pairs, dtype=float).reshape(-1, 2).T
        qs = np.asarray(oscillator(baseline.t, baseline.accel, 2 * np.pi * f, z))
        a = np.asarray(baseline.accel)
        gain = np.zeros((len(KNOBS), 4))
        for j, (kn, g) in enumerate(zip(KNOBS[N_ODE_KNOBS:], (ys, ys, 1.0, 1.0))):
            gain[KNOBS.index(kn), j] = g
        out = []
        for static, (q, fi, zi) in ((s, x) for s in statics for x in zip(qs, f, z)):
            q0 = q[:, 0] + (1.0 - static) * a / (2 * np.pi * fi) ** 2
            out.append(
                EffectDesign(
                    ("A_q", "A_qdot", "log_f_shift", "logit_zeta_shift"),
                    ("m", "m", "1", "1"),
                    np.array([ys, ys, 1.0, 1.0]),
                    knob_gain=gain,
                    knob_set={
                        "mode_log_f": np.log(fi),
                        "mode_logit_zeta": _logit(zi),
                        "mode_static": static,
                    },
                    columns=np.stack(
                        [_unit_rms(q0) * ys, _unit_rms(q[:, 1]) * ys, 0 * q0, 0 * q0], 1
                    ),
                    nuisance={"f_Hz": float(fi), "zeta": float(zi), "static": static},
                    free=(
                        (2, "f_Hz", lambda u, f0=fi: f0 * np.exp(u)),
                        (3, "zeta", lambda u, z0=zi: _zeta(_logit(z0) + u)),
                    ),
                )
            )
        return out

    def reject(self, nuisance):
        """A refit whose damping ratio ends at `ZETA_MAX` is a low-pass of the acceleration,
        not a lightly damped mode (docs/discovery.md)."""
        if nuisance.get("zeta", 0.0) >= ZETA_AT_BOUND * ZETA_MAX:
            return (
                f"not a mode: the damping ratio {nuisance['zeta']:.3g} ends at its bound "
                f"{ZETA_MAX:g} (a low-pass of the acceleration)"
            )
        return None

    def frequencies(self, baseline):
        t = np.asarray(baseline.t)
        fs = (t.size - 1) / (t[-1] - t[0])
        return np.geomspace(3.0 / (t[-1] - t[0]), min(0.4 * fs, 500.0), self.n_freq)

    def designs(self, baseline):
        pairs = [(f, z) for f in self.frequencies(baseline) for z in self.zetas]
        return self._designs(baseline, pairs, self.statics)

    def refine(self, baseline, design, score):
        f0, z0 = design.nuisance["f_Hz"], design.nuisance["zeta"]
        st = design.nuisance["static"]
        step = float(np.log(self.frequencies(baseline)[1] / self.frequencies(baseline)[0]))
        lf, _ = golden_max(
            lambda u: score(self.design(baseline, np.exp(u), z0, st)),
            np.log(f0) - step,
            np.log(f0) + step,
        )
        lz, _ = golden_max(
            lambda u: score(self.design(baseline, np.exp(lf), np.exp(u), st)),
            np.log(z0 / 3),
            np.log(min(3 * z0, 0.8 * ZETA_MAX)),
            iters=12,
        )
        return self.design(baseline, np.exp(lf), np.exp(lz), st)


def _logit(zeta):
    return float(np.log(zeta / (ZETA_MAX - zeta)))


def _zeta(u):
    return float(ZETA_MAX / (1.0 + np.exp(-u)))


SLIP_EFFECTS = (
    SensorDrift,
    PositionError,
    Vibration,
    LoadDependence("slip"),
    Stribeck("slip"),
    Viscous("slip"),
)
"""The slip model's effects in candidate order: the additive ones, then the friction law's."""
