"""The loop model's effects (`default_effects("loop")`), each described in its class.

The model is `tribojax._model.LoopBaseline` (the Jenkins element driven through the record's
measured displacement, wu2015 Eq 1; its knobs and their physics: `tribojax._model._loop_force`),
the same model that `fit_loop(model="history")` fits; its noise model is `cycle_noise`.

Regions: the abscissa is the displacement u (m) and the segments are the branches (0 =
"unloading", u falling; 1 = "loading", u rising); each flagged region also carries "branch",
"u_min" and "u_max" (m).
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from ._base import EffectDesign
from ._effects import AbstractEffect, knob_design
from ._effects_friction import LoadDependence, Viscous
from ._loop_force import MINDLIN_SHAPE

GAP_GRID = tuple(np.geomspace(0.02, 1.2, 10).tolist())
"""Seeds of the backlash gap g as a fraction of the record's half peak-to-peak displacement A
(score grid and refit starts; the refit fits g itself)."""


class Microslip(AbstractEffect):
    """Partial slip (Mindlin/Koh, wu2015 Eq 2): force (1 − w)·Jenkins + w·bank, the bank's virgin
    curve μN[1 − (1 − x/(p·A0))^p]; w = 0 null, w = 1 the full microslip law. Two designs: the
    Mindlin law (p = 3/2, strength w) and p fitted with w (a shift of ln(p − 1), reported as the
    nuisance "shape"): a joint whose slip limits are spread otherwise than Mindlin's (e.g. an Iwan
    bank with uniformly spread limits, p = 2); both are refitted, the lower BIC kept."""

    name: ClassVar[str] = "microslip"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = (
        "partial slip: weight w of the Mindlin law, or of a law of fitted shape p"
    )
    refit_starts: ClassVar[int] = 2  # both designs

    def designs(self, baseline):
        p0 = MINDLIN_SHAPE
        return [
            knob_design(baseline, ["microslip"], ("w",), ("1",), 1.0),
            knob_design(
                baseline,
                ("microslip", "log_shape"),
                ("w", "log_shape_shift"),
                ("1", "1"),
                np.ones(2),
                nuisance={"shape": p0},
                free=((1, "shape", lambda s: 1.0 + (p0 - 1.0) * np.exp(s)),),
            ),
        ]


class Backlash(AbstractEffect):
    """A clearance (dead zone) in series with the contact: after each reversal the force falls to
    zero and stays there while the drive crosses the gap g (m), then re-engages (the model in
    `tribojax._model._loop_force`). Strengths: the depth ε (—; 0 none, 1 a clean clearance) and
    the shift of ln g from its seed (g/A on `GAP_GRID`), fitted jointly; the fitted g is
    reported as the nuisance "gap_m"."""

    name: ClassVar[str] = "backlash"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "clearance at reversal: force held at zero across a gap g"
    refit_starts: ClassVar[int] = 2  # the score's best gap can sit far from the refit's

    def designs(self, baseline):
        A = float(baseline.record.A)
        return [
            knob_design(
                baseline,
                ("backlash", "log_gap"),
                ("depth", "log_gap_shift"),
                ("1", "1"),
                np.ones(2),
                knob_set={"log_gap": float(np.log(q))},
                nuisance={"gap_m": q * A},
                free=((1, "gap_m", lambda s, g0=q * A: g0 * np.exp(s)),),
            )
            for q in GAP_GRID
        ]


_BAND = {
    "self_energizing": (
        "energizing",
        "sigma",
        "exponential (capstan) rise of the force to slip, exponent sigma",
    ),
    "direction_asymmetry": (
        "asymmetry",
        "a",
        "slip force muN(1 + a) sliding forward, muN(1 - a) backward",
    ),
}
"""The band brake's effects: name -> (knob of the loop model, strength, description)."""


class BandBrakeEffect(AbstractEffect):
    """An effect of a band brake's loop (`tribojax.BandBrake`), `name` one of `_BAND`'s: one
    signed strength (0 the null) moving one knob of the loop model, a default candidate only on
    a band brake's records (`LoopBaseline.band_brake`). `self_energizing`: the capstan bend ψ_σ
    of the stick branch; `direction_asymmetry`: slip forces μN(1 ± a), zero force kept at zero
    (unlike `force_offset`); both in the module docstring of `tribojax._model._loop_force`."""

    name: str
    kind: ClassVar[str] = "loop"

    def __check_init__(self):
        if self.name not in _BAND:
            raise ValueError(f"name = {self.name!r}: a band brake effect is one of {sorted(_BAND)}")

    @property
    def description(self) -> str:
        return _BAND[self.name][2]

    def applies(self, baseline):
        return baseline.band_brake

    def designs(self, baseline):
        knob, strength, _ = _BAND[self.name]
        return [knob_design(baseline, [knob], (strength,), ("1",), 1.0)]


class ForceOffset(AbstractEffect):
    """A constant offset f0 (N) of the force reading (a load-cell zero error): additive, f0 = 0
    null."""

    name: ClassVar[str] = "force_offset"
    kind: ClassVar[str] = "loop"
    description: ClassVar[str] = "constant offset of the force reading"

    def designs(self, baseline):
        scale = 0.5 * float(np.ptp(np.asarray(baseline.record.f)))
        ones = np.ones((np.asarray(baseline.record.f).size, 1)) * scale
        return [EffectDesign(("f0",), ("N",), np.array([scale]), basis=ones, columns=ones)]


LOOP_EFFECTS = (
    Microslip,
    Viscous("loop"),
    LoadDependence("loop"),
    Backlash,
    *(BandBrakeEffect(name) for name in _BAND),
    ForceOffset,
)
"""The loop model's effects in candidate order."""
