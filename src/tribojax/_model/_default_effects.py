"""The effects each record model is offered (`default_effects`): a fixed table of the built-in
effects, in candidate order, then those a user added with `register_effect`. Nothing is filled in
by importing a module, so a saved model rebuilds (`rebuild`) without importing `discovery`."""

from __future__ import annotations

from ._effects import AbstractEffect, user_effects
from ._effects_curve import CURVE_EFFECTS
from ._effects_loop import LOOP_EFFECTS
from ._effects_slip import SLIP_EFFECTS

BUILT_IN = {"slip": SLIP_EFFECTS, "loop": LOOP_EFFECTS, "curve": CURVE_EFFECTS}
"""The built-in effects of each record model kind, in candidate order."""


def default_effects(kind: str) -> list[AbstractEffect]:
    """Instances of the effects of `kind` ("slip", "loop", "curve", or a kind a user registered):
    the built-in ones in candidate order, then the user's (`register_effect`; a user's effect of a
    built-in name takes its place)."""
    built_in = {e.name: e for e in BUILT_IN.get(kind, ())}
    users = user_effects()
    added = users.get(kind, {})
    if not built_in and not added:
        known = sorted({*BUILT_IN, *users})
        raise ValueError(f"kind = {kind!r}: no effects registered; known: {known}")
    table = {**built_in, **added}
    return [e() if isinstance(e, type) else e for e in table.values()]
