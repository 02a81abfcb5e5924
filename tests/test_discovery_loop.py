"""Loop side of discovery: the drive model and its effects, the hidden-effect generators, and
the wu2015 Eq 7 stand-in loops."""

import dataclasses
import json
import os
from typing import ClassVar

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
import tribojax.discovery as disc
from tribojax._model import LoopSpec, cycle_noise, loop_force, prepare_loop
from tribojax.discovery import AbstractEffect, EffectDesign
from tribojax.discovery._loop_synthetic import (
    LOAD_GRADIENT,
    LOOP_EFFECTS,
    VISCOUS_STRENGTH,
    eq7_standin_loop,
    eq7_standin_shape,
    hidden_effect_loop,
    rig,
)

MUN, KD, A0, OMEGA = rig()
_force = jax.jit(loop_force)


@pytest.mark.parametrize("Ab", [1.2, 3.0])
@pytest.mark.parametrize("effect", ["none", *LOOP_EFFECTS])
def test_model_reproduces_each_generator(effect, Ab):
    """The augmented drive model at the generator's strength reproduces the noise-free record
    (each generator is written independently: closed-form steady loops or a NumPy sample loop)."""
    spec = {
        "none": LoopSpec(MUN, KD),
        "microslip": LoopSpec(MUN, KD, w=1.0),
        "viscous_damping": LoopSpec(MUN, KD, c=VISCOUS_STRENGTH * MUN / (OMEGA * A0)),
        "normal_load_variation": LoopSpec(MUN, KD, beta=LOAD_GRADIENT),
    }[effect]
    loop = hidden_effect_loop(effect, 0.0, Ab, 0)
    data = prepare_loop(loop)
    err = np.max(np.abs(np.asarray(_force(spec, data)) - np.asarray(data.f))) / MUN
    # Jenkins and N(u): exact updates (round-off); Mindlin: Iwan bank of 128 elements (~1/n²);
    # viscous: u̇ by second-order differences, (ωΔt)²/6 of the viscous force
    tol = {"none": 1e-12, "normal_load_variation": 1e-12, "microslip": 1e-4}.get(effect, 1e-4)
    assert err < tol


@pytest.mark.usefixtures("storable_programs")
def test_effects_vanish_at_their_null_and_are_differentiable():
    base = disc.loop_baseline(hidden_effect_loop("none", 0.0, 2.0, 0))
    theta = jnp.log(jnp.array([MUN, KD]))
    null = jnp.asarray(base.knob_null())
    f0 = loop_force(LoopSpec(MUN, KD), base.record, microslip=False)
    assert float(jnp.max(jnp.abs(base.predict(theta, null) - f0))) < 1e-12 * MUN
    # jit == eager, and jacfwd against central differences in θ and every knob
    # w, β, c, backlash ε, ln(g/A), γ, K_d ∝ N^p, self-energizing σ, direction asymmetry a,
    # ln(p − 1) of the microslip law's shape p
    knobs = jnp.array([0.3, 0.05, 0.08, 0.6, np.log(0.3), 0.03, 0.5, 1.5, 0.1, np.log(0.8)])
    assert knobs.size == len(base.knob_names)
    eager = base.predict(theta, knobs)
    jitted = jax.jit(type(base).predict)(base, theta, knobs)
    np.testing.assert_allclose(np.asarray(jitted), np.asarray(eager), rtol=0, atol=1e-13 * MUN)

    @jax.jit
    def flat(x):
        return base.predict(x[:2], x[2:])

    x = jnp.concatenate([theta, knobs])
    J = jax.jacfwd(flat)(x)
    for i in range(x.size):
        h = 1e-6
        e = jnp.zeros(x.size).at[i].set(h)
        fd = (flat(x + e) - flat(x - e)) / (2 * h)
        # piecewise-smooth force (slip onsets): compare in RMS; FD error O(h) at the kinks
        scale = float(jnp.sqrt(jnp.mean(J[:, i] ** 2)))
        assert float(jnp.sqrt(jnp.mean((J[:, i] - fd) ** 2))) < 2e-3 * scale, i
    # vmap over knob settings == one at a time; reverse mode (grad of a loss) == forward mode
    batch = jnp.stack([knobs, 0.5 * knobs, -knobs])
    vm = jax.vmap(lambda kn: flat(jnp.concatenate([theta, kn])))(batch)
    for row, kn in zip(vm, batch):
        np.testing.assert_allclose(
            np.asarray(row),
            np.asarray(flat(jnp.concatenate([theta, kn]))),
            rtol=0,
            atol=1e-13 * MUN,
        )
    y = base.record.f

    def loss(x):
        return 0.5 * jnp.sum((flat(x) - y) ** 2)

    np.testing.assert_allclose(
        np.asarray(jax.grad(loss)(x)), np.asarray(J.T @ (flat(x) - y)), rtol=1e-9, atol=0
    )


def test_model_drops_the_mindlin_bank_only_while_w_is_held_at_zero():
    """`for_knobs`: a fit in which the microslip weight w stays 0 runs the Jenkins element
    without the 128-slider Mindlin bank; its force and Jacobian over θ and the other knobs are
    those of the full bank at w = 0. Where w may move, or the element is Mindlin (w = 1 at the
    null), the bank stays."""
    base = disc.loop_baseline(hidden_effect_loop("none", 0.0, 2.0, 0))
    names = base.knob_names
    lean = base.for_knobs(tuple(n != "microslip" for n in names))
    assert base.bank and not lean.bank
    assert base.for_knobs(tuple(True for _ in names)) is base
    mindlin = dataclasses.replace(base, element="mindlin")
    assert mindlin.for_knobs(tuple(False for _ in names)) is mindlin
    theta = jnp.log(jnp.array([MUN, KD]))
    knobs = jnp.array([0.0, 0.05, 0.08, 0.6, np.log(0.3), 0.03, 0.5, 1.5, 0.1])
    x = jnp.concatenate([theta, knobs])
    out = [jax.jit(jax.jacfwd(lambda z, b=b: b.predict(z[:2], z[2:])))(x) for b in (base, lean)]
    value = [jax.jit(lambda z, b=b: b.predict(z[:2], z[2:]))(x) for b in (base, lean)]
    np.testing.assert_allclose(np.asarray(value[1]), np.asarray(value[0]), rtol=0, atol=1e-12 * MUN)
    J_full, J_lean = (np.delete(np.asarray(J), 2, axis=1) for J in out)  # all but ∂/∂w
    np.testing.assert_allclose(J_lean, J_full, rtol=0, atol=1e-12 * np.max(np.abs(J_full)))
    assert np.max(np.abs(np.asarray(out[0])[:, 2])) > 0  # the bank's own column: w is seen


def test_backlash_gap_below_zero_is_refused():
    data = prepare_loop(hidden_effect_loop("none", 0.0, 2.0, 0))
    with pytest.raises(ValueError, match="gap"):
        loop_force(LoopSpec(MUN, KD, depth=1.0, gap=-1e-7), data)


def test_load_variation_out_of_range_is_refused():
    data = prepare_loop(hidden_effect_loop("none", 0.0, 2.0, 0))
    with pytest.raises(ValueError, match="beta"):
        loop_force(LoopSpec(MUN, KD, beta=1.5), data)


def test_generator_arguments_are_checked():
    with pytest.raises(ValueError, match="effect"):
        hidden_effect_loop("stribeck", 0.01, 2.0, 0)
    with pytest.raises(ValueError, match="noise"):
        hidden_effect_loop("none", -0.01, 2.0, 0)
    with pytest.raises(ValueError, match="amplitude"):
        hidden_effect_loop("none", 0.01, 0.0, 0)


@pytest.mark.parametrize("Ab", [0.5, 2.0, 4.0])
def test_eq7_standin_loops_have_eq7_coefficients(Ab):
    shape = eq7_standin_shape(Ab)
    assert shape["mismatch"] < 1e-10
    assert 1.0 <= shape["p"] < 3.0 and 0.2 < shape["s"] < 1.5
    loop = eq7_standin_loop(Ab, noise=0.0, samples_per_cycle=800)
    a = tj.analyse_loop(loop)
    K7, C7 = (float(x) for x in tj.eq7_curves(Ab))
    # the record's first harmonic (sampled) against Eq 7, normalised with the rig's K_d
    # (Eq 6 on the record gives it to ~1e-3: the quadratic window on a curved branch)
    assert a.K_eq / KD == pytest.approx(K7, abs=2e-3)
    assert np.pi * a.omega * a.C_eq / KD == pytest.approx(C7, abs=2e-3)
    assert a.K_d == pytest.approx(KD, rel=3e-3)


# --- discovery on hidden-effect loops ---------------------------------------------------------

NOISES = (0.005, 0.015)  # force-noise sd / μN
# Ā: gross slip for Jenkins but not for Mindlin (1.2, < 1.5), for every model (3.0). At Ā = 0.6
# (no gross slip anywhere) microslip and viscous damping are near-collinear and, at 1.5 % noise,
# not much above the noise: see the issue-6 note; not part of the asserted grid.
AMPLITUDES = (1.2, 3.0)
GRID = [(e, s, a) for e in ("none", *LOOP_EFFECTS) for s in NOISES for a in AMPLITUDES]
CI_GRID = [  # one case per effect in CI: both noise levels, both amplitudes, sidecar or not
    ("none", 0.015, 1.2),
    ("microslip", 0.015, 1.2),
    ("viscous_damping", 0.005, 3.0),
    ("normal_load_variation", 0.015, 3.0),
]
TRUTH = {  # generator strengths (see tribojax.discovery._loop_synthetic)
    "microslip": ("w", 1.0),
    "viscous_damping": ("c", VISCOUS_STRENGTH * MUN / (OMEGA * A0)),
    "normal_load_variation": ("beta", LOAD_GRADIENT),
}


def _discover_case(effect, noise, Ab, seed=11):
    # the sidecar noise is given for the lower noise level and estimated for the higher one
    loop = hidden_effect_loop(effect, noise, Ab, seed, give_noise=noise < 0.01)
    return loop, disc.discover_loop(loop)


def _check_discovery(effect, noise, Ab, seed=11, case=None):
    loop, rep = _discover_case(effect, noise, Ab, seed) if case is None else case
    assert rep.converged
    assert rep.noise_estimated is (noise >= 0.01)
    # σ̂ from differences between cycles: ~400 differences, MAD efficiency → sd ≈ 6 %
    assert rep.noise_std == pytest.approx(noise * MUN, rel=0.2)
    if effect == "none":
        assert rep.effect == "none" and rep.effects == ()
        assert rep.regions == []
        assert rep.final_rmse == rep.baseline_rmse
        return rep
    assert rep.effect == effect and rep.effects == (effect,)
    assert rep.final_rmse <= 0.5 * rep.baseline_rmse  # the "shrinks by at least half"
    assert rep.final_rmse == pytest.approx(noise * MUN, rel=0.15)  # down to the noise
    name, value = TRUTH[effect]
    s = rep.strengths[effect][name]
    assert abs(s["value"] - value) < 5 * s["std_error"] + 0.02 * abs(value), s
    assert rep.regions, "a hidden effect must flag regions"
    u_lo, u_hi = loop.u.min(), loop.u.max()
    for rg in rep.regions:
        assert rg["branch"] in ("loading", "unloading")
        assert u_lo <= rg["u_min"] <= rg["u_max"] <= u_hi
        assert rg["rmse_after"] < rg["rmse_before"]
    # accepted by ΔBIC among the refitted candidates (the score only ranks them)
    chosen = {c["name"]: c for c in rep.candidates}[effect]
    assert chosen["delta_bic"] < -10
    others = [c["delta_bic"] for c in rep.candidates if c["name"] != effect]
    assert all(d is None or d > chosen["delta_bic"] for d in others)
    return rep


@pytest.mark.parametrize("effect,noise,Ab", CI_GRID)
def test_discovery_names_hidden_loop_effect(effect, noise, Ab):
    _check_discovery(effect, noise, Ab)


@pytest.mark.slow
def test_discovery_confusion_table():
    """The full grid (every effect and clean × 2 noise levels × 2 amplitudes × 3 seeds) with
    TRIBOJAX_FULL=1; otherwise a short form of two cases outside the CI subset."""
    if os.environ.get("TRIBOJAX_FULL") == "1":
        cases = [(*g, seed) for g in GRID for seed in (11, 12, 13)]
    else:
        cases = [("microslip", 0.005, 3.0, 12), ("none", 0.005, 3.0, 12)]
    table: dict = {}
    failures = []
    for effect, noise, Ab, seed in cases:
        case = _discover_case(effect, noise, Ab, seed)
        named = "+".join(case[1].effects) or "none"
        row = table.setdefault(effect, {})
        row[named] = row.get(named, 0) + 1
        try:
            _check_discovery(effect, noise, Ab, seed, case=case)
        except AssertionError as err:
            failures.append(f"{effect} noise={noise} Abar={Ab} seed={seed}: {err}")
    print("\nconfusion (true -> named counts):", json.dumps(table))
    assert not failures, "\n".join(failures)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_clean_loops_give_none(seed):
    """Clean Jenkins records with the noise estimated: nothing named, nothing flagged."""
    rep = disc.discover_loop(hidden_effect_loop("none", 0.01, 2.0, seed, give_noise=False))
    assert rep.effect == "none" and rep.regions == []
    for c in rep.candidates:
        assert c["p_value"] > 0.01 / len(rep.candidates) or c["delta_bic"] > -10


class ForceDrift(AbstractEffect):
    """A user effect defined here (not in the library): a force reading drifting linearly in
    time, 0 at the record's first fitted sample (N per record duration)."""

    name: ClassVar[str] = "force_drift"
    kind: ClassVar[str] = "loop"

    def designs(self, baseline):
        t = np.asarray(baseline.t)
        ramp = (t - t[0]) / (t[-1] - t[0])
        return [EffectDesign(("drift",), ("N",), np.ones(1) * 0.01, basis=0.01 * ramp[:, None])]


def test_user_effect_without_editing_the_library():
    loop = hidden_effect_loop("none", 0.005, 2.0, 4)
    base = disc.loop_baseline(loop)
    t0, t1 = float(base.t[0]), float(base.t[-1])
    drifted = dataclasses.replace(loop, f=loop.f + 0.05 * MUN * (loop.t - t0) / (t1 - t0))
    rep = disc.discover_loop(drifted, effects=[*disc.default_effects("loop"), ForceDrift()])
    assert rep.effect == "force_drift"
    s = rep.strengths["force_drift"]["drift"]
    assert abs(s["value"] - 0.05 * MUN) < 4 * s["std_error"]
    names = {e.name for e in disc.default_effects("loop")}
    assert names >= {*LOOP_EFFECTS, "backlash", "force_offset"}
    assert {c["name"] for c in rep.candidates} == {"force_drift", *names}
    json.dumps(rep.as_dict())  # the report is JSON-ready


def test_cycle_noise_estimator_ignores_a_periodic_misfit():
    """σ and AR(1) ρ of noise under a large periodic misfit, from differences between cycles."""
    rng = np.random.default_rng(5)
    n, per, sigma, rho = 2000, 97.3, 0.01, 0.5
    t = np.arange(n) * 1.0
    e = np.zeros(n)
    for i in range(1, n):
        e[i] = rho * e[i - 1] + np.sqrt(1 - rho**2) * sigma * rng.standard_normal()
    misfit = 0.2 * np.sign(np.sin(2 * np.pi * t / per)) * np.abs(np.sin(2 * np.pi * t / per))
    s_hat, rho_hat = cycle_noise(misfit + e, t, per)
    # interpolation between samples smooths the later copy a little: ρ̂ and σ̂ within ±0.1, 15 %
    assert s_hat == pytest.approx(sigma, rel=0.15)
    assert rho_hat == pytest.approx(rho, abs=0.1)


@pytest.mark.slow
def test_wu2015_standin_study_short(tmp_path):
    """fitting/wu2015_discovery.py, short form: Eq 7-like loops are not Jenkins loops; the
    missing effect named is microslip and the residual falls to about the noise."""
    from fitting import wu2015_discovery

    assert wu2015_discovery.main(["--short", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "wu2015_discovery.json").read_text())
    assert [r["A_bar"] for r in result["rows"]] == [1.0, 3.0]
    for r in result["rows"]:
        assert r["effect"] == "microslip"
        assert r["final_rmse_N"] < 0.5 * r["baseline_rmse_N"]
        assert r["final_rmse_N"] < 1.3 * r["true_noise_std_N"]
        w = r["strengths"]["microslip"]["w"]
        assert 0.5 < w["value"] < 1.5 and w["std_error"] < 0.1


def test_loop_file_round_trip_to_discovery_json(tmp_path):
    """The issue's loop file format (CSV + sidecar) → read_record → discover_loop → JSON."""
    loop = hidden_effect_loop("viscous_damping", 0.005, 3.0, 21)
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path, comment="hidden viscous damping, seed 21")
    back = tj.read_record(path)
    assert back.noise_std == pytest.approx(loop.noise_std) and back.normal_load == 2.94
    out = disc.discover_loop(back).as_dict()
    text = json.dumps(out)
    assert json.loads(text)["effect"] == "viscous_damping"
    for key in ("effect", "effects", "baseline_rmse", "final_rmse", "regions", "candidates"):
        assert key in out
    assert {"branch", "u_min", "u_max"} <= set(out["regions"][0])
    with pytest.raises(ValueError, match="HysteresisLoop"):
        disc.discover_loop(np.zeros(10))


@pytest.mark.slow
def test_cli_discover_on_a_loop_file(tmp_path, capsys):
    """`tribojax discover LOOP.csv --out DIR`: the loop goes to the Jenkins baseline."""
    from tribojax._cli._main import main

    loop = hidden_effect_loop("normal_load_variation", 0.01, 2.0, 8, give_noise=False)
    path = tmp_path / "loop.csv"
    tj.write_loop(loop, path)
    out = tmp_path / "out"
    assert main(["discover", str(path), "--out", str(out)]) == 0
    result = json.loads((out / "discovery.json").read_text())
    assert result["effect"] == "normal_load_variation" and result["kind"] == "loop"
    assert result["noise_estimated"] is True
    assert all({"branch", "u_min", "u_max"} <= set(rg) for rg in result["regions"])
    assert "normal_load_variation" in capsys.readouterr().out
    # its discovery.json predicts a loop at another amplitude (1.5x) and noise draw: the model
    # with the effect misses by less than half what the baseline alone misses
    held = tmp_path / "held.csv"
    tj.write_loop(hidden_effect_loop("normal_load_variation", 0.01, 3.0, 9, give_noise=False), held)
    pred_dir = tmp_path / "pred"
    assert main(["predict", str(out / "discovery.json"), str(held), "--out", str(pred_dir)]) == 0
    pred = json.loads((pred_dir / "prediction.json").read_text())
    assert pred["model"]["effects"][0]["name"] == "normal_load_variation"
    alone = tj.FittedModel("loop", result["baseline_fit"]["parameters"], {}, {"element": "jenkins"})
    assert pred["rms_error"] < 0.5 * tj.predict(alone, tj.read_record(held)).rms_error


def test_microslip_bank_of_shape_p_interpolates_its_virgin_curve():
    """`power_unit_bank`: p = 3/2 is the Mindlin bank itself; for p = 2 (slip limits spread
    uniformly on (0, 2A0], an independent closed form: F = K(x − x²/(4A0))) the bank's virgin
    curve meets μN[1 − (1 − x/(p·A0))^p] to the interpolation error ~1/n²; the bank is
    differentiable in p."""
    from tribojax._friction._rate_independent import mindlin_unit_bank, power_unit_bank

    y15, k15 = power_unit_bank(128, 1.5)
    np.testing.assert_array_equal(y15, mindlin_unit_bank(128)[0])
    np.testing.assert_array_equal(k15, mindlin_unit_bank(128)[1])
    y, k = power_unit_bank(128, 2.0)
    x = np.linspace(0.0, 2.5, 41)  # units of A0: full slip at 2
    virgin = np.array([np.sum(k * np.minimum(xx, y)) for xx in x])
    uniform = np.where(x < 2.0, x - x**2 / 4.0, 1.0)
    assert np.max(np.abs(virgin - uniform)) < 1e-4
    dk = jax.jacfwd(lambda p: power_unit_bank(128, p, xp=jnp)[1])(2.0)
    fd = (power_unit_bank(128, 2.0 + 1e-6)[1] - power_unit_bank(128, 2.0 - 1e-6)[1]) / 2e-6
    np.testing.assert_allclose(np.asarray(dk), fd, rtol=1e-5, atol=1e-6)  # K_d units


@pytest.mark.slow
def test_microslip_shape_is_fitted_for_uniformly_spread_slip_limits(tmp_path):
    """The blind generator's s5013 (benchmarks/blind/: a 200-slider Iwan bank with slip limits
    uniform on (0, 2A0] and viscous damping, under a three-harmonic drive; examined while adding
    the shape, so a regression case). With Mindlin's law alone the misfit it left (1.6 noise sd)
    had a clearance added for it; with the shape fitted both effects are named, nothing else,
    and the misfit goes, the shape p at the bank's 2 and c at the hidden one."""
    import subprocess
    import sys
    from pathlib import Path

    blind = Path(__file__).resolve().parents[1] / "benchmarks" / "blind"
    label = "loop/microslip+viscous_damping/sine3/muN120N/s5013"
    subprocess.run(
        [
            sys.executable,
            str(blind / "generate.py"),
            "--out",
            str(tmp_path),
            "--quiet",
            "--only",
            label,
        ],
        check=True,
    )
    (entry,) = json.loads((tmp_path / "manifest.json").read_text())
    rep = disc.discover(disc.loop_baseline(tj.read_record(tmp_path / entry["file"])))
    assert rep.effects == ("microslip", "viscous_damping") and rep.verdict == "explained"
    assert rep.excess_rmse_after < 0.05 * rep.excess_rmse_before
    assert abs(rep.strengths["microslip"]["nuisance"]["shape"] - 2.0) < 0.1
    c_true = entry["params"]["effects"]["viscous_damping"]["c_N_s_m"]
    assert abs(rep.strengths["viscous_damping"]["c"]["value"] / c_true - 1) < 0.05
    # saved with its shape and rebuilt: the same model (discovery.json's "fitted_model")
    model = tj.FittedModel.from_dict(json.loads(json.dumps(rep.as_dict()["fitted_model"])))
    assert model.effects[0].nuisance["shape"] == rep.strengths["microslip"]["nuisance"]["shape"]
    own = tj.predict(model, tj.read_record(tmp_path / entry["file"])).predicted
    np.testing.assert_allclose(own, rep.final_y, rtol=0, atol=1e-12 * np.ptp(rep.final_y))
