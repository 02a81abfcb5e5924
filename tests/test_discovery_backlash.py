"""`backlash` in loop discovery, on records from an independent generator.

The generator below shares nothing with the discovery model: it tracks the element's position
and the side of the slot its pin touches (a rigid clearance of travel g in series with a Masing
element), finds where the force falls to zero with SciPy's brentq, and uses a closed-form
virgin curve: Jenkins min(K·x, F_s) or the tanh curve F_s·tanh(K·x/F_s) (a smooth microslip
law of another form than the Mindlin bank of the model). Rig: F_s = 500 N, K = 2 MN/m
(A0 = 0.25 mm), u = 2 mm·sin(2π·3 Hz·t), 200 samples per cycle, white force noise of sd 5 N
(stated, as a sidecar would), seeds in the tests. Gaps 0.37 and 1.13 mm (g/A = 0.185, 0.565) sit
between the points of the discovery's gap grid.
"""

import numpy as np
import pytest
from scipy.optimize import brentq

import tribojax as tj
from tribojax._model import LoopSpec, loop_force
from tribojax._model._effects_loop import GAP_GRID
from tribojax.discovery import discover, loop_baseline

F_S, K, A, F_HZ, NOISE = 500.0, 2.0e6, 2.0e-3, 3.0, 5.0
GAPS = (0.37e-3, 1.13e-3)
BACKBONES = {
    "jenkins": lambda x: np.clip(K * x, -F_S, F_S),
    "tanh": lambda x: F_S * np.tanh(K * x / F_S),
}


def clearance_masing_force(u, backbone, gap):
    """Force (N) through a rigid clearance of total travel `gap` (m) into a Masing element with
    the odd virgin curve `backbone` (N of m), driven by u (m) from rest, clearance centred.
    Branches: the virgin curve, then F_r + s·2·backbone(s·(x − x_r)/2) after an element reversal
    at (x_r, F_r), s its sense; the pin leaves a wall where the force reaches zero."""
    h = 0.5 * gap
    x, F, branch, sense = 0.0, 0.0, None, 0
    out = np.zeros_like(u)

    def force(xn, b):
        if b is None:
            return backbone(xn)
        xr, fr, s = b
        return fr + s * 2.0 * backbone(s * (xn - xr) / 2.0)

    for i in range(1, len(u)):
        lo, hi = u[i] - h, u[i] + h  # where the pin may sit in the slot
        if F > 0 or (F == 0 and x < lo):
            xc = lo  # the wall pushing +
        elif F < 0 or (F == 0 and x > hi):
            xc = hi
        else:
            continue  # free in the gap: no force
        s = int(np.sign(xc - x))
        if s == 0:
            out[i] = F
            continue
        b = (x, F, s) if sense not in (0, s) else branch
        Fc = force(xc, b)
        if F != 0 and np.sign(Fc) == -np.sign(F):  # the spring relaxes: the pin leaves the wall
            x0 = brentq(lambda z: force(z, b), x, xc)
            far = hi if s < 0 else lo
            xc, Fc = (far, force(far, b)) if s * (far - x0) > 0 else (x0, 0.0)
        x, F, branch, sense = xc, Fc, b, s
        out[i] = F
    return out


def record(backbone="jenkins", gap=0.0, viscous=0.0, seed=0, noise=NOISE):
    """A loop of 2¼ cycles; `viscous`: a force c·u̇ with c·ωA = viscous·F_s."""
    t = np.arange(2 * 200 + 51) / 200 / F_HZ
    u = A * np.sin(2 * np.pi * F_HZ * t)
    f = clearance_masing_force(u, BACKBONES[backbone], gap)
    f = f + viscous * F_S * np.cos(2 * np.pi * F_HZ * t)
    f = f + noise * np.random.default_rng(seed).standard_normal(t.size)
    return tj.HysteresisLoop(
        t,
        u,
        f,
        frequency=F_HZ,
        noise_std=noise if noise else None,
        source=f"<{backbone} gap {gap} seed {seed}>",
    )


def test_generator_and_model_agree():
    """A clean clearance (ε = 1) in series with Jenkins: the model equals the independent
    generator after the first reversal (round-off), and the zero-force plateau is g wide."""
    gap = GAPS[1]
    loop = record(gap=gap, noise=0.0)
    base = loop_baseline(loop)
    model = np.asarray(loop_force(LoopSpec(F_S, K, depth=1.0, gap=gap), base.record))
    np.testing.assert_allclose(model, np.asarray(base.record.f), atol=1e-9 * F_S)
    u, f = np.asarray(base.x), model
    falling = np.gradient(u) < 0
    zero = falling & (np.abs(f) < 1e-9)
    width = u[zero].max() - u[zero].min()  # one falling plateau in the fitted samples
    assert width == pytest.approx(gap, abs=2 * np.max(np.abs(np.diff(u))))
    assert all(abs(np.log(gap / (q * A))) > 0.1 for q in GAP_GRID)  # off the grid


@pytest.mark.slow
@pytest.mark.parametrize("gap", GAPS)
@pytest.mark.parametrize("backbone", ["jenkins", "tanh"])
def test_backlash_named_first(backbone, gap):
    rep = discover(loop_baseline(record(backbone, gap, seed=11)), max_effects=2)
    d = rep.as_dict()
    assert rep.effects[0] == "backlash"
    fitted = d["strengths"]["backlash"]["nuisance"]["gap_m"]
    assert fitted == pytest.approx(gap, rel=0.05 if backbone == "jenkins" else 0.25)
    assert d["strengths"]["backlash"]["depth"]["value"] > 0.8
    assert d["excess_rmse_after"] < 0.5 * d["excess_rmse_before"]
    if backbone == "jenkins":  # the exact physics: nothing left but the noise
        assert d["verdict"] == "explained"
        assert d["excess_rmse_after"] < 0.5 * NOISE
    else:
        assert d["verdict"] in ("explained", "partly_explained")


# the tanh backbone: since the microslip law's shape p is fitted (stop 52) `microslip` takes the
# excess misfit from 31.9 to 2.1 (p = 3.44; with Mindlin's law alone 18.9, "unexplained"), and a
# clearance (ΔBIC −14.9) is then added for the rest of the tanh-vs-power-law difference: an effect
# that is not there, recorded as a known miss (strict: it fails once the clearance is no longer
# added)
_TANH_MISS = pytest.mark.xfail(strict=True, reason="a clearance added after the shaped microslip")


@pytest.mark.slow
@pytest.mark.parametrize(
    ("backbone", "viscous", "named"),
    [
        ("jenkins", 0.0, ()),
        pytest.param("tanh", 0.0, ("microslip",), marks=_TANH_MISS),
        ("jenkins", 0.06, ("viscous_damping",)),
    ],
)
def test_backlash_not_named_without_it(backbone, viscous, named):
    rep = discover(loop_baseline(record(backbone, 0.0, viscous, seed=5)))
    d = rep.as_dict()
    assert "backlash" not in rep.effects
    assert "force_offset" not in rep.effects
    assert set(named) <= set(rep.effects)
    if not named:
        assert d["verdict"] == "none"
        assert d["excess_rmse_after"] == d["excess_rmse_before"] < 0.5 * NOISE
    else:
        assert d["excess_rmse_after"] < d["excess_rmse_before"]
