"""The effects of the friction law that several record models carry, each written once:
`Stribeck` (velocity weakening), `Viscous` (a viscous term) and `LoadDependence` (a normal load
that follows the drive). An instance names the record model it augments (`kind`); each kind's
module registers its instance in its place in that kind's candidate order. What differs between
record models (the knob, the strength's unit and scale, the nuisance grid, the refit starts) is
one row per kind; the designs are built by one code path through `knob_design`.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ._curve_model import BETA_START
from ._effects import AbstractEffect, knob_design
from ._loop_force import KD_LOAD_EXPONENT
from ._slip import VS_GRID

TABLE = "wang2022_table"

DELTA_START = 0.02  # Stribeck refit starts on a slip run: δ
VS_START_FACTORS = (1.0, 0.3, 3.0)  # ... and v_s in units of the record's peak slip speed
N_VS_GRID = 9  # Stribeck velocities on a friction curve's score grid, geometric over its |v|
SIGMA2_STARTS = (10.0, 100.0)  # viscous refit starts on a slip run, σ2 in units of the start C_τ
KAPPA_STARTS = (-0.3, 1.0)  # load-coupling refit starts on a slip run, κ per g


def record_slip_speed(t, slip) -> float:
    """Peak slip speed of a measured slip record, m/s: max |dx/dt| of the reading smoothed by a
    five-sample moving average (its noise enters the derivative divided by ≈ 5 sample steps)."""
    t, x = np.asarray(t, float), np.asarray(slip, float)
    if x.size < 7:
        return float(np.max(np.abs(np.gradient(x, t))))
    xs = np.convolve(x, np.ones(5) / 5.0, mode="valid")
    return float(np.max(np.abs(np.gradient(xs, t[2:-2]))))


class _OneKindEach(AbstractEffect):
    """An effect of the friction law with one form per record model: `kind` one of `NAMES`'s
    keys, its name there (the name a record kind's reports have always used)."""

    kind: str
    name: str
    NAMES: ClassVar[dict[str, str]] = {}

    def __init__(self, kind: str = "slip"):
        if kind not in self.NAMES:
            raise ValueError(
                f"kind = {kind!r}: {type(self).__name__} applies to {list(self.NAMES)} records"
            )
        self.kind, self.name = kind, self.NAMES[kind]


class Stribeck(_OneKindEach):
    """Velocity weakening of the friction law: the friction level falls from F_s at rest towards
    F_c as the sliding speed passes v_s, g(v) = F_c + (F_s − F_c)·exp(−|v/v_s|^β) (wang2022
    Eq 25). Strength 0 is no weakening; v_s (and β on a curve) are nuisances.

    - slip run (`kind` "slip"): strength δ = 1 − F_c/F_s, β = 2; v_s seeded on `VS_GRID` (the
      best by score) and fitted jointly with δ in the refit, which also starts from
      δ = `DELTA_START` at v_s = v_pk·`VS_START_FACTORS`, v_pk the record's own peak slip speed
      (`record_slip_speed`): a weakening changes the slip only where v is near v_s.
    - friction curve ("curve"): strength A = F_s − F_c in the curve's friction unit; v_s seeded by
      `N_VS_GRID` geometric points over half the record's |v| range, β from `BETA_START`, both
      fitted with A (three refit starts).
    - published table (`TABLE`): strength δ in units of 0.1; v_s on `VS_GRID`, not fitted (one
      nuisance counted in ΔBIC).
    """

    description: ClassVar[str] = "velocity weakening F_c + (F_s - F_c) exp(-|v/v_s|^beta)"
    NAMES: ClassVar[dict[str, str]] = dict.fromkeys(("slip", "curve", TABLE), "stribeck")

    @property
    def refit_starts(self) -> int:
        return 3 if self.kind == "curve" else 1

    def designs(self, baseline):
        kind = self.kind
        if kind == "curve":
            a = np.abs(np.asarray(baseline.v))
            grid, key = np.geomspace(0.5 * a.min(), 0.5 * a.max(), N_VS_GRID), "v_s"
            knobs = dict.fromkeys(("stribeck", "log10_v_s", "log_beta"), 1.0)
            names = ("F_s_minus_F_c", "log10_v_s_shift", "log_beta_shift")
            units, scale = (baseline.units[1], "1", "1"), [float(baseline.f_ref), 1.0, 1.0]
        elif kind == "slip":
            grid, key = VS_GRID, "v_s_m_per_s"
            knobs = dict.fromkeys(("stribeck", "log10_v_s"), 1.0)
            names, units, scale = ("delta", "log10_v_s_shift"), ("1", "1"), [1.0, 1.0]
        else:  # a table: v_s held at its grid point, one nuisance counted in ΔBIC
            grid, key = VS_GRID, "v_s_m_per_s"
            knobs, names, units, scale = {"stribeck": 0.1}, ("delta",), ("1",), 0.1
        v_pk = record_slip_speed(baseline.t, baseline.slip) if kind == "slip" else 0.0
        out = []
        for vs in grid:
            kw = {"knob_set": {"log10_v_s": np.log10(vs)}, "nuisance": {key: vs}}
            if kind == TABLE:
                kw["n_nuisance"] = 1
            else:
                kw["free"] = ((1, key, lambda u, v0=vs: v0 * 10.0**u),)
            if kind == "curve":
                kw["free"] += ((2, "beta", lambda u: BETA_START * np.exp(u)),)
            if kind == "slip":
                kw["starts"] = tuple(
                    (DELTA_START, float(np.log10(v_pk * c / vs)))
                    for c in VS_START_FACTORS
                    if v_pk > 0
                )
            out.append(knob_design(baseline, knobs, names, units, scale, **kw))
        return out


_VISCOUS = {  # kind: (name, knob, strength, unit, scale of the strength from the baseline)
    "slip": ("viscous_friction", "viscous", "sigma2", "N s/m", lambda b: float(b.sigma_ref)),
    "loop": ("viscous_damping", "viscous", "c", "N s/m", lambda b: float(b.record.c_scale)),
    "curve": ("viscous", "log_viscous_exponent", "log_delta", "1", lambda b: 1.0),
    TABLE: ("viscous_friction", "viscous", "sigma2_over_C_tau", "1", lambda b: 1.0),
}


class Viscous(_OneKindEach):
    """A viscous term in the friction force (LuGre σ2·v, wang2022 Eq 25), strength 0 none.

    - slip run ("viscous_friction"): σ2 (N·s/m, in units of the start C_τ). While the contact
      sticks, σ2·v is C_τ·ż, so the score barely sees it and the optimum lies far along that
      valley: the refit is made whatever the score (`score_gate` False) and also starts from
      σ2 = `SIGMA2_STARTS` × the start C_τ; the ΔBIC of the refit decides.
    - loop ("viscous_damping"): a force c·u̇ (N·s/m) in parallel with the contact.
    - friction curve ("viscous"): the curve's baseline has the linear term already; the effect is
      its shape, sgn(v)·σ2·v_ref·|v/v_ref|^δ, strength ln δ (0: linear).
    - published table ("viscous_friction"): σ2/C_τ.
    """

    NAMES: ClassVar[dict[str, str]] = {k: v[0] for k, v in _VISCOUS.items()}

    @property
    def description(self) -> str:
        return {
            "loop": "force proportional to velocity, c·du/dt",
            "curve": "power-law viscous friction sigma2 v_ref |v/v_ref|^delta",
        }.get(self.kind, "viscous friction sigma2 v (LuGre)")

    @property
    def score_gate(self) -> bool:
        return self.kind != "slip"

    def designs(self, baseline):
        _, knob, strength, unit, scale = _VISCOUS[self.kind]
        kw = {"starts": tuple((v,) for v in SIGMA2_STARTS)} if self.kind == "slip" else {}
        return [knob_design(baseline, [knob], (strength,), (unit,), scale(baseline), **kw)]


class LoadDependence(_OneKindEach):
    """A normal load that follows the drive, so the contact's friction limit (μN ∝ N) and its
    stiffness (wang2022 Eq 18 and wu2015 Eq 5: K ∝ N^p) follow it too. Named `load_coupling` on
    slip runs and tables and `normal_load_variation` on loops.

    - slip run, published table: N = N₀(1 + κa/g), a the stage acceleration (inertial load
      transfer), strength κ per g (in units of 0.1 on a table); the slip run's refit also starts
      from κ = `KAPPA_STARTS`: near m·a_max ≈ F_s the baseline's optimum can sit far from the
      coupled one (docs/discovery.md).
    - loop: N(u) = N₀(1 + β·u/A) or N₀(1 + β·u/A + γ·(u/A)²) (`degrees` 1 and 2), K_d ∝ N^p with
      p = 0.7616 (wu2015 Eq 5) or p = 0 (a stiffness that does not follow the load,
      `kd_exponents`); every combination is refitted and the lower BIC kept; p a fixed nuisance
      of each design. The linear term is a tilted counter-face; γ a load that rises (or falls)
      towards both ends of the stroke (a curved face, a rocking fixture): it is even in u, so the
      linear term's score does not see it (the records behind both: docs/discovery.md).
    """

    degrees: ClassVar[tuple] = (1, 2)
    kd_exponents: ClassVar[tuple] = (KD_LOAD_EXPONENT, 0.0)
    NAMES: ClassVar[dict[str, str]] = {
        "slip": "load_coupling",
        "loop": "normal_load_variation",
        TABLE: "load_coupling",
    }

    @property
    def description(self) -> str:
        if self.kind == "loop":
            return "normal load varying with u: N0(1 + beta u/A + gamma (u/A)^2)"
        return "normal load following the stage acceleration: N0(1 + kappa a/g)"

    @property
    def refit_starts(self) -> int:
        return len(self.degrees) * len(self.kd_exponents) if self.kind == "loop" else 1

    def designs(self, baseline):
        if self.kind != "loop":
            g = 1.0 if self.kind == "slip" else 0.1
            kw = {"starts": tuple((k,) for k in KAPPA_STARTS)} if self.kind == "slip" else {}
            return [
                knob_design(baseline, {"load_coupling": g}, ("kappa",), ("1 (per g)",), g, **kw)
            ]
        return [
            knob_design(
                baseline,
                ("load_slope", "load_curve")[:deg],
                ("beta", "gamma")[:deg],
                ("1",) * deg,
                np.ones(deg),
                knob_set={"kd_exponent": float(p)},
                nuisance={"degree": float(deg), "kd_exponent": float(p)},
            )
            for deg in self.degrees
            for p in self.kd_exponents
        ]
