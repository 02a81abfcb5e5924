"""Curve discovery (issue 15): the Coulomb + viscous baseline of a steady friction curve and its
named effects `stribeck`, `asymmetry`, `viscous`.

The records come from `_curve_record` below: NumPy only, its own functional forms (a Lorentzian
Stribeck dip 1/(1 + (v/v_s)²), Coulomb levels that differ with the direction, a square-root
viscous rise, a sinusoidal ripple in v), velocities jittered off any grid, seed stated. Nothing
of tribojax's model code is used to make them.
"""

import json
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
from tribojax._cli import main
from tribojax.discovery import curve_baseline, default_effects, discover_curve

REAL = Path(__file__).resolve().parents[1] / "data" / "real"
SEED = 20261125


def _curve_record(shape: str, seed=SEED, n_side=16) -> tj.FrictionCurve:
    """A steady friction curve (torque in N m against rad/s, as the screw-drive records; 2·16
    points as driveNo1, so the compiled fit is shared) of 2·n_side points: Coulomb 1 N m,
    viscous 0.02 N m s, per-point standard errors 3–6 mN m, plus the named shape(s)."""
    rng = np.random.default_rng(seed)
    mag = np.geomspace(0.3, 25.0, n_side) * np.exp(rng.uniform(-0.08, 0.08, n_side))
    v = np.concatenate([-mag[::-1], mag])
    a = np.abs(v)
    side = np.sign(v)
    level = np.ones_like(v)
    visc = 0.02 * a
    if "stribeck" in shape:  # Lorentzian dip, v_s = 1.7 rad/s
        level = level + 0.3 / (1.0 + (a / 1.7) ** 2)
    if "asymmetry" in shape:  # Coulomb 1.06 N m forward, 0.94 N m backward
        level = level + np.where(v > 0, 0.06, -0.06)
    if shape == "viscous":  # square-root rise in place of the linear one
        visc = 0.09 * np.sqrt(a)
    elif shape == "ripple":  # a periodic ripple in v (no named effect has it)
        level = level + 0.04 * np.sin(2.0 * np.pi * a / 4.3)
    err = 0.003 * (1.0 + rng.uniform(0.0, 1.0, v.size))
    f = side * (level + visc) + err * rng.standard_normal(v.size)
    n = np.full(v.size, 400.0)
    units = {"velocity_unit": "rad/s", "friction_unit": "N m"}
    return tj.FrictionCurve(v, f, err * np.sqrt(n), 0.01 * a, n, units, f"synthetic {shape}")


@pytest.mark.slow
@pytest.mark.parametrize("shape", ["stribeck", "asymmetry", "viscous"])
def test_each_effect_is_named_first_where_present(shape):
    rep = discover_curve(_curve_record(shape), max_effects=2)
    assert rep.converged and rep.effects[0] == shape
    assert rep.verdict in ("explained", "partly_explained")
    assert rep.excess_rmse_after < 0.5 * rep.excess_rmse_before


@pytest.mark.slow
def test_stribeck_and_asymmetry_together_are_both_named():
    rep = discover_curve(_curve_record("stribeck+asymmetry"))
    assert set(rep.effects) == {"stribeck", "asymmetry"} and rep.verdict == "explained"


@pytest.mark.slow
def test_strengths_recover_the_hidden_values():
    rep = discover_curve(_curve_record("asymmetry"), max_effects=1)
    t0 = rep.strengths["asymmetry"]["T0"]
    # levels 1.06 / 0.94 N m: T0 = half their difference, 0.06 N m
    assert t0["value"] == pytest.approx(0.06, abs=4 * t0["std_error"] + 1e-3)
    assert rep.final_fit["parameters"]["F_c"] == pytest.approx(1.0, abs=0.01)
    rep = discover_curve(_curve_record("viscous"), max_effects=1)
    # 0.09·√v: the power-law exponent is 1/2
    delta = np.exp(rep.strengths["viscous"]["log_delta"]["value"])
    assert delta == pytest.approx(0.5, abs=0.08)


@pytest.mark.slow
def test_stribeck_velocity_lands_near_the_hidden_scale():
    rep = discover_curve(_curve_record("stribeck"), max_effects=1)
    st = rep.strengths["stribeck"]
    # a Lorentzian of half-width 1.7 rad/s is matched by exp(−|v/v_s|^β) with v_s of the same order
    assert 0.8 < st["nuisance"]["v_s"] < 3.5
    assert st["F_s_minus_F_c"]["value"] == pytest.approx(0.3, rel=0.35)


def test_clean_coulomb_viscous_curve_is_none():
    rep = discover_curve(_curve_record("clean"))
    assert rep.verdict == "none" and rep.effects == ()
    p = rep.baseline_fit["parameters"]
    assert p["F_c"] == pytest.approx(1.0, abs=0.005)
    assert p["sigma2"] == pytest.approx(0.02, abs=5e-4)


def test_a_ripple_is_not_explained():
    rep = discover_curve(_curve_record("ripple"))
    assert rep.verdict != "explained" and rep.verdict != "none"
    assert rep.misfit["regions"] or rep.misfit["final_noise_p_value"] < 0.01


def test_bad_input_names_the_point():
    c = _curve_record("clean")
    v = c.velocity.copy()
    v[3] = 0.0
    bad = tj.FrictionCurve(v, c.friction, c.friction_scatter, c.velocity_scatter, c.samples)
    with pytest.raises(ValueError, match=r"velocity\[3\] = 0"):
        curve_baseline(bad)
    with pytest.raises(ValueError, match="FrictionCurve"):
        discover_curve(np.zeros(3))


def test_model_jit_and_gradients():
    base = curve_baseline(_curve_record("clean"))
    theta = np.asarray(base.start()) + np.array([0.05, -0.1])
    knobs = np.array([0.2, 0.3, np.log(1.3), 0.04, -0.2])  # every knob away from its null

    def total(th, kn):
        return jnp.sum(jnp.sin(base.predict(th, kn)))

    jitted = jax.jit(lambda th, kn: base.predict(th, kn))
    assert np.allclose(jitted(theta, knobs), base.predict(theta, knobs), rtol=1e-12)
    g_th, g_kn = jax.grad(total, argnums=(0, 1))(theta, knobs)
    x = np.concatenate([theta, knobs])
    h = 1e-6
    for i in range(x.size):
        e = np.zeros(x.size)
        e[i] = h
        hi, lo = x + e, x - e
        fd = (total(hi[:2], hi[2:]) - total(lo[:2], lo[2:])) / (2 * h)
        g = (g_th if i < 2 else g_kn)[i if i < 2 else i - 2]
        assert float(g) == pytest.approx(float(fd), rel=1e-6, abs=1e-8)
    # null knobs: the baseline sgn(v)·F_c + σ2·v exactly
    F_c, sigma2 = np.asarray(base.physical(theta))
    plain = np.asarray(base.friction(theta, base.knob_null()))
    assert np.allclose(plain, np.sign(base.v) * F_c + sigma2 * np.asarray(base.v), rtol=1e-12)


def test_curve_effects_are_registered():
    assert [e.name for e in default_effects("curve")] == ["stribeck", "asymmetry", "viscous"]


def test_discover_cli_on_a_curve_file(tmp_path):
    src = REAL / "screwdrive" / "driveNo1_steady_0.096kg.csv"
    out = tmp_path / "d"
    assert main(["discover", str(src), "--out", str(out), "--format", "curve"]) == 0
    res = json.loads((out / "discovery.json").read_text())
    assert res["kind"] == "curve" and res["converged"]
    # the simple lead screw: its two directions differ (asymmetry) and it weakens at low speed
    assert set(res["effects"]) >= {"asymmetry", "stribeck"}
    assert res["verdict"] in ("explained", "partly_explained")
    assert {"excess_rmse_before", "excess_rmse_after", "misfit", "regions"} <= set(res)
    assert (out / "discovery.png").is_file()
