"""The band brake's effects in loop discovery (issue 30): `self_energizing` (the capstan rise of
the stick branch, ψ_σ) and `direction_asymmetry` (slip forces μN(1 ± a)).

The records come from the NumPy band-brake loop of tests/test_band_brake.py (a play operator with
a drag spring across a clearance and an exponential rise to F₊ ≠ F₋), which shares no code with
the loop model; it was written by the same hand as the effects, so the identification below is
a cross-check of the implementation, not a blind test. The real device is in
fitting/real_discovery_brfd.py --predicts (docs/data.md)."""

import hashlib
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
from test_band_brake import P, _drive, _reference
from tribojax._model._loop_force import (
    SIGMA_SERIES,
    LoopSpec,
    energize,
    loop_force,
    prepare_loop,
)
from tribojax.discovery import default_effects, discover_loop

NOISE = 60.0  # N
TENSION = 133.4  # N (30 lb): the record is a band brake's


def test_energize_keeps_the_slip_force_and_bends_the_stick_branch():
    q = jnp.linspace(-1.0, 1.0, 201)
    for sigma in (-3.0, 0.0, 2.0, 8.0):
        psi = energize(q, sigma)
        np.testing.assert_allclose(psi, -energize(-q, sigma), atol=1e-15)  # odd
        assert float(psi[-1]) == pytest.approx(1.0, abs=1e-14) and abs(float(psi[100])) < 1e-15
        assert bool(jnp.all(jnp.diff(psi) > 0))  # monotone: no force reversal inside the branch
    # σ > 0: convex on q > 0 (the capstan rise), below the line; σ = 0 the Jenkins line itself
    x = q[101:-1]
    assert bool(jnp.all(energize(x, 2.0) < x)) and bool(jnp.all(energize(x, -2.0) > x))
    np.testing.assert_allclose(energize(q, 0.0), q, atol=1e-15)
    # the series below |σ| = SIGMA_SERIES meets the exact form at the switch (to ~σ³)
    for s in (SIGMA_SERIES * (1 - 1e-9), SIGMA_SERIES * (1 + 1e-9)):
        exact = np.expm1(s * np.abs(q)) / np.expm1(s) * np.sign(q)
        np.testing.assert_allclose(energize(q, s), exact, atol=1e-10)
    # dψ/dσ at σ = 0 is x(x − 1)/2 (the direction the score test looks along)
    d = jax.vmap(jax.grad(lambda s, qq: energize(qq, s)), in_axes=(None, 0))(0.0, x)
    np.testing.assert_allclose(d, x * (x - 1) / 2, atol=1e-12)


def test_out_of_range_strengths_are_refused_with_their_value():
    t = np.linspace(0.0, 3.0, 301)
    data = prepare_loop(
        tj.HysteresisLoop(t=t, u=1e-3 * np.sin(2 * np.pi * t), f=np.cos(2 * np.pi * t))
    )
    with pytest.raises(ValueError, match=r"energizing = 45 is outside the allowed range"):
        loop_force(LoopSpec(1.0, 1e4, energizing=45.0), data)
    with pytest.raises(ValueError, match=r"asymmetry = -1 is outside the allowed range \(-1, 1\)"):
        loop_force(LoopSpec(1.0, 1e4, asymmetry=-1.0), data)


def test_candidates_on_a_band_brakes_records_only():
    names = {e.name for e in default_effects("loop")}
    assert {"self_energizing", "direction_asymmetry", "backlash"} <= names
    t = np.linspace(0.0, 3.0, 301)
    u, f = 1e-3 * np.sin(2 * np.pi * t), np.cos(2 * np.pi * t)
    for tension, expected in ((None, False), (TENSION, True)):
        base = tj.discovery.loop_baseline(tj.HysteresisLoop(t=t, u=u, f=f, band_tension=tension))
        applies = {e.name: e.applies(base) for e in default_effects("loop")}
        assert applies["self_energizing"] is applies["direction_asymmetry"] is expected
        assert applies["backlash"] and applies["force_offset"]


@pytest.mark.slow
def test_discovery_names_the_band_brake_and_its_model_predicts_another_drive():
    """A noisy 1 Hz sine loop of the NumPy band brake: discovery adds the capstan rise, the
    direction asymmetry and the clearance (all three parts of the device), with a and the gap
    close to the device's; the excess misfit shrinks > 10x in sample and on the held-out
    cycles; the saved model then predicts a two-tone history it never saw far better than the
    Jenkins baseline fitted on the same loop."""
    t = np.linspace(0.0, 3.0, 751)
    u = 8e-3 * np.sin(2 * np.pi * t)
    f = _reference(u, P) + np.random.default_rng(0).normal(0.0, NOISE, t.size)
    rep = discover_loop(tj.HysteresisLoop(t=t, u=u, f=f, band_tension=TENSION))
    assert set(rep.effects) == {"self_energizing", "direction_asymmetry", "backlash"}
    a_true = (P["F_pos"] - P["F_neg"]) / (P["F_pos"] + P["F_neg"])  # 0.143
    assert rep.strengths["direction_asymmetry"]["a"]["value"] == pytest.approx(a_true, abs=0.015)
    gap = rep.strengths["backlash"]["nuisance"]["gap_m"]
    assert gap == pytest.approx(P["gap_pos"] + P["gap_neg"], rel=0.15)
    assert rep.strengths["self_energizing"]["sigma"]["value"] > 0.5  # a rise, not a softening
    assert rep.excess_rmse_after < 0.1 * rep.excess_rmse_before
    assert rep.heldout_excess_after < 0.1 * rep.heldout_excess_before
    assert rep.noise_std == pytest.approx(NOISE, rel=0.2)
    # another drive (two tones, partial reversals), never fitted
    tt, uu = _drive(n=1201, seed=3)
    other = tj.HysteresisLoop(t=tt, u=uu, f=_reference(uu, P), periodic=False)
    found = tj.predict(rep.fitted, other).nrmse
    jenkins = tj.discovery.discover_loop(
        tj.HysteresisLoop(t=t, u=u, f=f), effects=[], max_effects=0
    ).fitted
    assert found < 0.1 and found < 0.4 * tj.predict(jenkins, other).nrmse


@pytest.mark.slow
def test_cli_discover_takes_the_band_tension(tmp_path):
    """`tribojax discover LOOP.csv --band-tension 30lb`: the record is a band brake's, so its
    effects are candidates (a CSV loop carries no tension of its own); the saved model names
    them and `tribojax predict` takes it."""
    from tribojax._cli._main import main
    from tribojax._io._hysteresis_loop import write_loop

    t = np.linspace(0.0, 3.0, 751)
    u = 8e-3 * np.sin(2 * np.pi * t)
    f = _reference(u, P) + np.random.default_rng(1).normal(0.0, NOISE, t.size)
    path = tmp_path / "band.csv"
    write_loop(tj.HysteresisLoop(t=t, u=u, f=f), path)
    assert (
        main(
            [
                "discover",
                str(path),
                "--out",
                str(tmp_path / "d"),
                "--band-tension",
                "30lb",
                "--quiet",
            ]
        )
        == 0
    )
    data = json.loads((tmp_path / "d" / "discovery.json").read_text())
    assert {"self_energizing", "direction_asymmetry"} <= set(data["effects"])
    assert (
        main(
            [
                "predict",
                str(tmp_path / "d" / "discovery.json"),
                str(path),
                "--out",
                str(tmp_path / "p"),
            ]
        )
        == 0
    )
    pred = json.loads((tmp_path / "p" / "prediction.json").read_text())
    assert pred["nrmse"] < 0.05


BLIND = Path(__file__).resolve().parents[1] / "benchmarks" / "blind"
FROZEN = {  # the blind generator and its records as written (sha256)
    "band_brake_generator.py": "482ff109db5c29776e6063413e471b66aaa87eb9e0a30f35e814d886912deb2e",
    "band_brake/sine_1Hz.csv": "e089ff245457c261de605a2a690f2fd8162127aa604af1151b0e2b59dd85b9a4",
    "band_brake/history.csv": "ceeef3c8d092407efd971b0c106054e5be8e9cc67e329de866570b104e6ceaac",
}


@pytest.mark.slow
def test_blind_band_brake_is_named_and_its_history_predicted():
    """Records of a band brake written blind (benchmarks/blind/band_brake_generator.py: a helper
    given only a physical description — a capstan band on a lever, a 4 mm clearance with a weak
    centring spring, a stop linkage that stiffens quadratically, slip forces +13.0 / −9.5 kN —
    and NumPy; it never saw the loop model). Discovery on its noisy 1 Hz sine names the band's
    rise, its asymmetry and the clearance, with a and the gap near the generator's (measured
    0.161 and 3.88 mm), shrinks the excess 11x in sample and on the held-out cycles, and its model
    predicts the generator's two-tone history, never fitted, at NRMSE 0.045 (Jenkins: 0.440)."""
    from benchmarks.experiments.blind_band_brake_discovery import main

    for name, digest in FROZEN.items():
        assert hashlib.sha256((BLIND / name).read_bytes()).hexdigest() == digest, name
    truth = json.loads((BLIND / "band_brake" / "truth.json").read_text())
    out = main()
    found = out["with the band's effects"]
    assert set(found["effects"]) == {"self_energizing", "direction_asymmetry", "backlash"}
    f_pos, f_neg = truth["slip_force_positive_N"], -truth["slip_force_negative_N"]
    a = found["strengths"]["direction_asymmetry"]["a"]["value"]
    assert a == pytest.approx((f_pos - f_neg) / (f_pos + f_neg), abs=0.02)  # 0.156
    gap = found["strengths"]["backlash"]["nuisance"]["gap_m"]
    assert gap == pytest.approx(truth["clearance_g_m"], rel=0.1)
    assert found["excess_after"] < 0.2 * found["excess_before"]
    assert found["heldout_excess_after"] < 0.2 * found["heldout_excess_before"]
    jenkins = out["jenkins baseline"]["history_nrmse"]
    assert found["history_nrmse"] < 0.1 and found["history_nrmse"] < 0.25 * jenkins
