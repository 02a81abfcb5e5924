"""The loop model started in the state of a record's first measured force (`initial="measured"`,
`loaded_state`): a history that begins with the device under load (both brfd earthquake records
begin at ±0.7 kN, the band left engaged by the test before).

The reference is a NumPy stop operator (Jenkins element) started from a given deflection,
sharing no code with the model."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
from tribojax._model._loop_force import LoopSpec, loaded_state, loop_force, prepare_loop

MU_N, K_D = 1.0e3, 1.0e6  # N, N/m
A0 = MU_N / K_D


def _stop(u, z0):
    """Jenkins force history (N) from the spring deflection z0 (m) at u[0]."""
    z, out = z0, [K_D * z0]
    for du in np.diff(u):
        z = min(max(z + du, -A0), A0)
        out.append(K_D * z)
    return np.asarray(out)


def _history(z0=0.6 * A0, n=2001):
    t = np.linspace(0.0, 4.0, n)
    u = 3e-3 * np.sin(2 * np.pi * 0.5 * t) * t / 4.0  # a growing swing from the loaded start
    return tj.HysteresisLoop(t=t, u=u, f=_stop(u, z0), periodic=False)


def test_measured_start_reproduces_a_loaded_history():
    loop = _history()
    rest = prepare_loop(loop, "rest")
    loaded = prepare_loop(loop, "measured")

    def err(d):
        force = loop_force(LoopSpec(MU_N, K_D), d, microslip=False)
        return float(jnp.max(jnp.abs(force - d.f)))

    assert err(loaded) < 1e-9 * MU_N  # measured 1.7e-12
    assert err(rest) > 0.5 * MU_N  # from rest the spring starts 0.6 μN short
    with pytest.raises(ValueError, match="initial = 'loaded'"):
        prepare_loop(loop, "loaded")


@pytest.mark.parametrize("target", [-2.5e3, -400.0, 0.0, 350.0, 900.0, 5e3])
def test_loaded_state_carries_the_target_force(target):
    """With a clearance, the capstan bend and an asymmetry the model's force at the first sample
    is the target, or the slip force of that direction when the target is beyond it."""
    spec = LoopSpec(MU_N, K_D, depth=0.8, gap=1e-3, energizing=2.0, asymmetry=0.1)
    t = np.linspace(0.0, 2.0, 401)
    u = np.zeros(t.size)
    u[200:] = np.linspace(0.0, 1e-8, 201)  # (the first reversal after it is the last sample)
    loop = tj.HysteresisLoop(t=t, u=u, f=np.full(t.size, target), periodic=False)
    data = prepare_loop(loop, "measured")
    full = loop_force(spec, data.__class__(**{**vars(data), "skip": 0}), microslip=False)
    slip = MU_N * (1.1 if target > 0 else 0.9)
    assert float(full[0]) == pytest.approx(np.clip(target, -slip, slip), abs=1e-6 * MU_N)


@pytest.mark.slow
def test_gradients_through_the_start_match_finite_differences():
    data = prepare_loop(_history(z0=-0.4 * A0), "measured")

    def loss(x):
        spec = LoopSpec(x[0], x[1], depth=x[2], gap=1e-3, energizing=x[3], asymmetry=x[4])
        return jnp.sum(loop_force(spec, data, check=False) ** 2)

    x = jnp.array([MU_N, K_D, 0.5, 1.0, 0.05])
    g = jax.grad(loss)(x)
    np.testing.assert_allclose(jax.jit(jax.grad(loss))(x), g, rtol=1e-12)
    for i, h in enumerate([1e-3, 1.0, 1e-6, 1e-6, 1e-7]):
        e = jnp.zeros(5).at[i].set(h)
        fd = (loss(x + e) - loss(x - e)) / (2 * h)
        assert float(g[i]) == pytest.approx(float(fd), rel=1e-5), i
    # the start's derivative is the implicit one: d z0/d target = 1/K_d for a Jenkins spring
    dz = jax.grad(lambda f: loaded_state(lambda z: K_D * z[0], jnp.array([A0]), f)[0])(300.0)
    assert float(dz) == pytest.approx(1.0 / K_D, rel=1e-12)


@pytest.mark.slow
def test_predict_starts_as_fitted_or_as_asked(tmp_path):
    from tribojax._cli._main import main
    from tribojax._io._hysteresis_loop import write_loop

    loop = _history()
    report = tj.discovery.discover(
        tj.discovery.loop_baseline(loop, initial="measured"), max_effects=0
    )
    model = report.fitted
    assert model.options == {"element": "jenkins", "initial": "measured"}
    assert model.parameters["mu_N"] == pytest.approx(MU_N, rel=1e-6)
    assert tj.predict(model, loop).nrmse < 1e-5  # as fitted, from the loaded start (fit to ~1e-6)
    assert tj.predict(model, loop, initial="rest").nrmse > 0.1
    again = tj.FittedModel.from_dict(json.loads(json.dumps(report.as_dict()))["fitted_model"])
    assert tj.predict(again, loop).nrmse < 1e-5  # the option is saved with the model
    slip_model = tj.FittedModel("slip", {"F_s": 1.0, "K_tau": 1e7, "C_tau": 100.0}, {})
    with pytest.raises(ValueError, match="'measured' is for loop and history models"):
        tj.predict(
            slip_model,
            tj.synthetic_slip_run(tj.PreSlipLuGre(1.0, 1e7, 100.0), n=64),
            initial="measured",
        )
    # the CLI: discover --initial measured saves it; predict takes it; a slip run refuses it
    path = tmp_path / "h.csv"
    write_loop(loop, path)
    assert (
        main(
            [
                "discover",
                str(path),
                "--out",
                str(tmp_path / "d"),
                "--initial",
                "measured",
                "--max-effects",
                "0",
                "--quiet",
            ]
        )
        == 0
    )
    saved = json.loads((tmp_path / "d" / "discovery.json").read_text())["fitted_model"]
    assert saved["options"]["initial"] == "measured"
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
    assert pred["initial"] == "measured" and pred["nrmse"] < 1e-5
