"""Discovery's acceptance threshold; the effect contract and registry are `tribojax._model`'s
(`AbstractEffect`, `register_effect`, `default_effects`, re-exported here), the workflow is in
`_discover`."""

from __future__ import annotations

from .._model import AbstractEffect as AbstractEffect
from .._model import default_effects as default_effects
from .._model import register_effect as register_effect

DELTA_BIC_THRESHOLD = -10.0
"""An effect is accepted only below ΔBIC = −10 ("very strong" evidence, Kass & Raftery 1995)."""
