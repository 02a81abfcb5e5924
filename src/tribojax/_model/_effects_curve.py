"""The friction-curve model's effects (`default_effects("curve")`): `stribeck` and `viscous`
(the friction law's, `_effects_friction`) and `asymmetry`; the model, its knobs, noise and
weighting are `_curve_model.CurveBaseline`'s."""

from __future__ import annotations

from typing import ClassVar

from ._effects import AbstractEffect, knob_design
from ._effects_friction import Stribeck, Viscous


class CurveAsymmetry(AbstractEffect):
    """A direction asymmetry: T0 (friction unit) added in both directions, the friction
    magnitudes then differ by 2·T0 (equivalently Coulomb levels F_c ± T0)."""

    name: ClassVar[str] = "asymmetry"
    kind: ClassVar[str] = "curve"
    description: ClassVar[str] = "direction-dependent level: T0 added in both directions"

    def designs(self, baseline):
        return [
            knob_design(
                baseline, ["asymmetry"], ("T0",), (baseline.units[1],), float(baseline.f_ref)
            )
        ]


CURVE_EFFECTS = (Stribeck("curve"), CurveAsymmetry, Viscous("curve"))
"""The curve model's effects in candidate order."""
