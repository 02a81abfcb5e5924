"""The contract of an effect a record model can carry (`AbstractEffect`) and a user's own effects
(`register_effect`; the built-in ones and `default_effects`: `_default_effects`): `discover` ranks
and adds them, a saved model (`FittedModel`) names them and is rebuilt from them (`rebuild`)."""

from __future__ import annotations

import abc
from typing import ClassVar

import equinox as eqx
import numpy as np

from ._base import AbstractBaseline, EffectDesign


class AbstractEffect(eqx.Module):
    """A named candidate effect: how it augments a baseline of its `kind`, per nuisance setting."""

    name: eqx.AbstractClassVar[str]
    kind: eqx.AbstractClassVar[str]
    description: ClassVar[str] = ""

    @abc.abstractmethod
    def designs(self, baseline: AbstractBaseline) -> list[EffectDesign]:
        """One `EffectDesign` per nuisance grid point (a single one when there is no nuisance)."""

    # refit starts: the best grid design by score, then the next best ones at least a factor 10
    # away in every nuisance value
    refit_starts: ClassVar[int] = 1
    # False: refitted whatever its score p-value (an effect whose optimum the score at the null
    # cannot see, e.g. one nearly confounded with a baseline parameter there); the ΔBIC of the
    # refit alone then decides
    score_gate: ClassVar[bool] = True

    def refine(self, baseline: AbstractBaseline, design: EffectDesign, score) -> EffectDesign:
        """Optionally improve the best grid design's nuisance values; `score(design) -> float` is
        the Rao statistic at the current fit. Default: no refinement."""
        return design

    def applies(self, baseline: AbstractBaseline) -> bool:
        """Whether the effect is a candidate on this record by default (e.g. a device's own
        physics on records of that device). Default: True."""
        return True

    def reject(self, nuisance: dict) -> str | None:
        """A reason why a refit with these fitted nuisance values is not this effect (it is
        then not accepted), or None. Default: None."""
        return None


_REGISTRY: dict[str, dict[str, type | AbstractEffect]] = {}  # the user's, by kind and name


def register_effect(effect):
    """Add `effect` to `default_effects(effect.kind)` (a user's own effect; the built-in ones are
    `_default_effects.BUILT_IN`): an AbstractEffect subclass with a no-argument constructor (as a
    class decorator) or an instance (an effect with named fields). Returns `effect`. Registering
    a name twice replaces the earlier entry; a built-in name is replaced in its place."""
    is_class = isinstance(effect, type) and issubclass(effect, AbstractEffect)
    if not (is_class or isinstance(effect, AbstractEffect)):
        raise TypeError(
            f"register_effect expects an AbstractEffect subclass or instance, got {effect!r}"
        )
    _REGISTRY.setdefault(effect.kind, {})[effect.name] = effect
    return effect


def user_effects() -> dict[str, dict]:
    """The effects a user registered: {kind: {name: class or instance}}, in order."""
    return {kind: dict(table) for kind, table in _REGISTRY.items()}


def knob_design(baseline, knobs, names, units, scale, **kw) -> EffectDesign:
    """A design whose strengths move the named knobs of `baseline` (its `knob_names`): `knobs`
    {knob: gain} or a sequence of knobs (gain 1), one strength each in that order; `scale` the
    physical strength per unit strength; further `EffectDesign` fields as keywords."""
    gains = knobs if isinstance(knobs, dict) else dict.fromkeys(knobs, 1.0)
    gain = np.zeros((len(baseline.knob_names), len(gains)))
    for j, (knob, g) in enumerate(gains.items()):
        gain[baseline.knob_names.index(knob), j] = g
    return EffectDesign(
        tuple(names), tuple(units), np.atleast_1d(np.asarray(scale, float)), knob_gain=gain, **kw
    )
