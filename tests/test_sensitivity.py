"""Sensitivities of the contact → slip / loop chain: exact gradients, physics identities, sweep."""

import json
import os
import subprocess
import sys
import textwrap

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj

REF = dict(D=2.8821, G=4.3636e-8, mu_t=0.1416, load=6.7818, a_max=1.0)  # Table 3 calibration, 4 kPa


def _fd_elasticities(f, params, outputs, h):
    """Central differences of ln|y| in ln p (relative step h), one column per input.

    Inputs are passed as arrays: equinox.filter_jit would recompile for every new Python float.
    """
    params = {k: jnp.asarray(v) for k, v in params.items()}
    cols = []
    for k in params:
        up, dn = (f({**params, k: jnp.asarray(params[k] * (1 + s))}) for s in (h, -h))
        cols.append(
            [
                (np.log(abs(float(up[o]))) - np.log(abs(float(dn[o]))))
                / (np.log1p(h) - np.log1p(-h))
                for o in outputs
            ]
        )
    return np.array(cols).T


def test_elasticities_of_a_closed_form():
    def fn(p):
        return {"a": p["x"] ** 2 / jnp.sqrt(p["y"]), "b": jnp.exp(p["x"])}

    e = tj.elasticities(fn, {"x": 1.5, "y": 4.0})
    r = tj.elasticities(fn, {"x": 1.5, "y": 4.0}, mode="rev")
    # e(a) = (2, -1/2); e(b) = (x, 0) exactly, forward and reverse mode alike
    np.testing.assert_allclose(e.elasticity, [[2.0, -0.5], [1.5, 0.0]], rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(r.elasticity, e.elasticity, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(e.jacobian[0], [2 * 1.5 / 2.0, -(1.5**2) / 2 / 8.0], rtol=1e-14)
    table = e.table()
    assert table.splitlines()[0] == "| output | value | e_x | e_y |"
    assert "| a | 1.125 | +2.000 | -0.500 |" in table
    assert e.as_dict()["elasticity"]["b"] == pytest.approx({"x": 1.5, "y": 0.0})


def test_elasticities_refuse_undefined_cases():
    with pytest.raises(ValueError, match="x = 0"):
        tj.elasticities(lambda p: {"a": p["x"] + 1.0}, {"x": 0.0})
    with pytest.raises(ValueError, match="output 'a' is 0"):
        tj.elasticities(lambda p: {"a": p["x"] - 2.0}, {"x": 2.0})
    with pytest.raises(ValueError, match="x = nan"):
        tj.elasticities(lambda p: {"a": p["x"]}, {"x": float("nan")})
    with pytest.raises(ValueError, match="not finite"):
        tj.elasticities(lambda p: {"a": jnp.sqrt(p["x"] - 3.0)}, {"x": 2.0})
    with pytest.raises(ValueError, match="mode"):
        tj.elasticities(lambda p: {"a": p["x"]}, {"x": 1.0}, mode="central")


def test_chain_bad_input_names_the_parameter():
    chain = tj.ReticleChain(slip=False)
    with pytest.raises(ValueError, match=r"D = 3.2 is outside the allowed range \(2, 3\)"):
        chain({**REF, "D": 3.2})
    with pytest.raises(ValueError, match=r"missing \['a_max'\]"):
        chain({k: v for k, v in REF.items() if k != "a_max"})
    with pytest.raises(ValueError, match="mass\\*a_max/load must be below mu_t"):
        tj.slip_sensitivities(load=3.6912, a_max=2.0)  # T/P = 0.174 > μ_t = 0.1416
    with pytest.raises(ValueError, match="A = -1e-08 m is outside"):
        tj.hysteresis_sensitivities(A=-1e-8)
    with pytest.raises(ValueError, match="element must be"):
        tj.LoopChain("iwan")


@pytest.mark.usefixtures("storable_programs")
def test_contact_and_loop_gradients_match_finite_differences():
    chain = tj.LoopChain("mindlin")
    params = {**REF, "A": 50e-9}
    e = tj.hysteresis_sensitivities(**params)
    assert e.outputs == ("F_s", "K_tau", "C_tau", "z_max", "A_bar", "K_bar", "C_bar")
    # central differences, relative step 1e-5: truncation ~h²·e³ (e_D ≈ 33) stays below 1e-6,
    # round-off ~1e-16/h ~ 1e-11; the Newton load balance is converged to 1e-13
    fd = _fd_elasticities(eqx.filter_jit(chain), params, e.outputs, 1e-5)
    np.testing.assert_allclose(e.elasticity, fd, rtol=2e-6, atol=2e-6)


@pytest.mark.slow
def test_jit_elasticities_match_eager_forward_mode():
    chain = tj.LoopChain("mindlin")
    params = {**REF, "A": 50e-9}
    e = tj.hysteresis_sensitivities(**params)
    # jit (elasticities compiles the chain) against eager forward mode: same program, same numbers
    eager = jax.jacfwd(chain)(params)
    J = np.array([[float(eager[o][k]) for k in params] for o in e.outputs])
    np.testing.assert_allclose(e.jacobian, J, rtol=1e-12)
    values = chain(params)
    np.testing.assert_allclose(e.values, [float(values[o]) for o in e.outputs], rtol=1e-13)


def test_elasticity_identities_of_the_contact_and_loop():
    e = tj.hysteresis_sensitivities(**REF, A=50e-9)
    row = dict(zip(e.outputs, e.elasticity))
    col = {k: j for j, k in enumerate(e.parameters)}
    # Eq 14/16: F_s has no μ_t and no tangential load in it
    assert row["F_s"][col["mu_t"]] == 0.0 and row["F_s"][col["a_max"]] == 0.0
    # Eqs 18-24: μ_t and T = m·a_max enter K_τ and C_τ (μ_t² cancels in W_d/W_s) only as
    # ψ = T/(μ_t P), so their elasticities are opposite
    for name in ("K_tau", "C_tau", "z_max"):
        assert row[name][col["mu_t"]] == pytest.approx(-row[name][col["a_max"]], rel=1e-12)
    # Eq 26: z_max = F_s / K_τ
    np.testing.assert_allclose(row["z_max"], row["F_s"] - row["K_tau"], atol=1e-12)
    # Ā = A / z_max, and K̄, C̄ depend on Ā alone: each row is a multiple of Ā's row
    expected_abar = -row["z_max"] + (np.arange(len(col)) == col["A"])
    np.testing.assert_allclose(row["A_bar"], expected_abar, atol=1e-12)
    for name in ("K_bar", "C_bar"):
        ratio = row[name][col["A"]]
        np.testing.assert_allclose(row[name], ratio * row["A_bar"], rtol=1e-10, atol=1e-12)


@pytest.mark.usefixtures("storable_programs")
def test_mindlin_small_amplitude_limit():
    # wu2015 Eq 2 at small Ā: K̄ ≈ 1 − Ā/6, C̄ ≈ 2Ā/9 (docs/reproduction.md), so ∂lnC̄/∂lnA → 1 and
    # ∂lnK̄/∂lnA → −Ā/6; at A = 0.5 nm, Ā ≈ 0.014 and the next order is ~Ā
    e = tj.hysteresis_sensitivities(**REF, A=0.5e-9)
    row = dict(zip(e.outputs, e.elasticity))
    abar = e.values[e.outputs.index("A_bar")]
    assert row["C_bar"][-1] == pytest.approx(1.0, abs=2 * abar)
    assert row["K_bar"][-1] == pytest.approx(-abar / 6, rel=0.05)


@pytest.mark.slow
def test_slip_gradients_match_finite_differences():
    e = tj.slip_sensitivities(**REF)
    assert e.outputs == ("F_s", "K_tau", "C_tau", "z_max", "T4", "T5", "T6", "T7")
    f = eqx.filter_jit(tj.ReticleChain())  # (jit against eager: the loop-chain test above)
    y = f({k: jnp.asarray(v) for k, v in REF.items()})
    # The forward-mode solve is another program (the tangents ride along): its primal agrees to
    # about the solver tolerance, not bitwise.
    np.testing.assert_allclose(e.values, [float(y[o]) for o in e.outputs], rtol=1e-5)
    # Central differences through an adaptive solver: the step sequence changes with the inputs,
    # so a step of 1e-3 (truncation ~1e-6·e³) against the solver's noise (rtol 1e-8) leaves
    # ~1e-3 of the largest elasticity of a row (e_D ≈ 24 for T4); measured worst 9e-4.
    fd = _fd_elasticities(f, REF, e.outputs, 1e-3)
    scale = np.abs(e.elasticity).max(axis=1, keepdims=True)
    assert np.all(np.abs(fd - e.elasticity) <= 2e-3 * scale)
    row = dict(zip(e.outputs, e.elasticity))
    # a → −a symmetry of the cycle (test_slip): T4 ≈ −T6 and T5 ≈ −T7 respond alike (1 %)
    np.testing.assert_allclose(row["T4"], row["T6"], rtol=0.01, atol=0.01)
    np.testing.assert_allclose(row["T5"], row["T7"], rtol=0.01, atol=0.01)
    # more vacuum load → stiffer, stronger contact → less slip (Tables 4-7's trend)
    assert row["T4"][3] < 0 and row["K_tau"][3] > 0


def test_bar_chart(tmp_path, monkeypatch, capsys):
    e = tj.elasticities(lambda p: {"a": p["x"] ** 2 * p["y"]}, {"x": 2.0, "y": 3.0})
    pytest.importorskip("matplotlib")
    path = tmp_path / "e.png"
    assert e.plot(path) is not None and path.stat().st_size > 1000
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if it were not installed
    assert e.plot(tmp_path / "none.png") is None
    assert "matplotlib is not installed" in capsys.readouterr().out
    assert not (tmp_path / "none.png").exists()


def test_product_grid_and_single_device_sweep():
    grid = tj.product_grid(x=jnp.array([1.0, 2.0]), y=jnp.array([10.0, 20.0, 30.0]), z=5.0)
    np.testing.assert_array_equal(grid["x"], [1, 1, 1, 2, 2, 2])
    np.testing.assert_array_equal(grid["y"], [10, 20, 30, 10, 20, 30])
    np.testing.assert_array_equal(grid["z"], [5.0] * 6)

    def fn(p):
        return {"s": p["x"] * p["y"] + p["z"]}

    out = tj.sweep(fn, grid, devices=jax.devices()[:1])
    np.testing.assert_array_equal(out["s"], grid["x"] * grid["y"] + 5.0)
    with pytest.raises(ValueError, match="same non-zero leading length"):
        tj.sweep(fn, {"x": jnp.ones(3), "y": jnp.ones(2), "z": jnp.ones(3)})
    with pytest.raises(ValueError, match="at least one device"):
        tj.sweep(fn, grid, devices=[])


# Runs in a fresh interpreter: the device count is fixed when JAX initialises.
_SHARDED = textwrap.dedent(
    """
    import json, jax, jax.numpy as jnp, numpy as np
    import tribojax as tj
    assert len(jax.devices()) == 2
    chain = tj.ReticleChain(slip=False)
    grid = tj.product_grid(
        D=jnp.linspace(2.70, 2.95, 20), G=jnp.geomspace(5e-9, 6e-8, 20), mu_t=0.1416,
        load=jnp.geomspace(3.6912, 21.3258, 25), a_max=1.0)
    sharded = tj.sweep(chain, grid)
    plain = jax.jit(jax.vmap(chain))(grid)
    odd = tj.sweep(lambda p: {"y": jnp.sin(p["x"]) * 2.0}, {"x": jnp.arange(7.0)})
    print(json.dumps({
        "n": int(grid["D"].shape[0]),
        "devices": len(sharded["K_tau"].sharding.device_set),
        "shard_rows": [s.data.shape[0] for s in sharded["K_tau"].addressable_shards],
        "max_rel": max(float(jnp.max(jnp.abs(sharded[k] / plain[k] - 1))) for k in plain),
        "finite": all(bool(jnp.all(jnp.isfinite(plain[k]))) for k in plain),
        "odd_err": float(jnp.max(jnp.abs(odd["y"] - 2 * jnp.sin(jnp.arange(7.0))))),
        "odd_len": int(odd["y"].shape[0]),
    }))
    """
)


@pytest.mark.slow
def test_sweep_sharded_over_two_cpu_devices_equals_unsharded():
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    run = subprocess.run(
        [sys.executable, "-c", _SHARDED], env=env, capture_output=True, text=True, timeout=300
    )
    assert run.returncode == 0, run.stderr[-3000:]
    res = json.loads(run.stdout.strip().splitlines()[-1])
    assert res["n"] == 10_000 and res["finite"]
    assert res["devices"] == 2 and res["shard_rows"] == [5000, 5000]
    # members are independent; vectorised math on 5000- vs 10000-long batches may round the last
    # bit differently (measured max 2e-14)
    assert res["max_rel"] < 1e-12
    assert res["odd_len"] == 7 and res["odd_err"] < 1e-15  # padded to 8, cut back to 7


@pytest.mark.slow
def test_sensitivity_study_short_form(tmp_path, capsys):
    from fitting import sensitivity

    assert sensitivity.main(["--short", "--out", str(tmp_path)]) == 0
    result = json.loads((tmp_path / "sensitivity.json").read_text())
    (row,) = result["elasticities"]
    assert row["vacuum_kPa"] == 4.0
    slip = row["slip"]["elasticity"]
    # Table 4's trend: more load, less slip; more stage acceleration, more slip
    assert slip["T4"]["load"] < 0 < slip["T4"]["a_max"]
    sweep = result["sweep"]
    assert sweep["members"] == 10_000 and sweep["sharded_over"] == len(jax.devices())
    assert sweep["max_rel_diff_sharded_vs_one_device"] < 1e-12
    assert sweep["ranges"]["F_s"][0] > 0
    # Mindlin's C̄ peaks at 5/6 (Ā = 2.4, docs/reproduction.md); the grid's Ā spans 0.4-7.8
    assert sweep["ranges"]["A_bar"][0] < 2.4 < sweep["ranges"]["A_bar"][1]
    assert 0.8 < sweep["ranges"]["C_bar"][1] <= 5 / 6 + 1e-9
    assert "| T4 |" in (tmp_path / "elasticities.md").read_text()
    # never over earlier output
    before = (tmp_path / "sensitivity.json").read_bytes()
    assert sensitivity.main(["--short", "--out", str(tmp_path)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert (tmp_path / "sensitivity.json").read_bytes() == before


def test_range_checks_of_constants_inside_jit():
    # A model's array fields closed over inside jax.jit are constants, but comparisons of them
    # are traced: check_range used to call np.asarray on that traced result and fail.
    s = tj.FractalSurface(D=2.5, G=1e-9, M=1.0)
    d = jax.jit(lambda d: tj.FractalSurface(D=d, G=s.G, M=s.M).D)(jnp.asarray(2.6))
    assert float(d) == 2.6
