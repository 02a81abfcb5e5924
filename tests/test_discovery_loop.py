"""Loop side of discovery: the drive model and its effects, the hidden-effect generators, and
the wu2015 Eq 7 stand-in loops."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
import tribojax.discovery as disc
from tribojax._loop_models import LoopSpec, loop_force, prepare_loop
from tribojax._loop_synthetic import (
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


def test_effects_vanish_at_their_null_and_are_differentiable():
    base = disc.loop_baseline(hidden_effect_loop("none", 0.0, 2.0, 0))
    theta = jnp.log(jnp.array([MUN, KD]))
    null = jnp.asarray(base.knob_null())
    f0 = loop_force(LoopSpec(MUN, KD), base.record, microslip=False)
    assert float(jnp.max(jnp.abs(base.predict(theta, null) - f0))) < 1e-12 * MUN
    # jit == eager, and jacfwd against central differences in θ and every knob
    knobs = jnp.array([0.3, 0.05, 0.08])
    eager = base.predict(theta, knobs)
    jitted = jax.jit(type(base).predict)(base, theta, knobs)
    np.testing.assert_allclose(np.asarray(jitted), np.asarray(eager), rtol=0, atol=1e-13 * MUN)

    @jax.jit
    def flat(x):
        return base.predict(x[:2], x[2:])

    x = jnp.concatenate([theta, knobs])
    J = jax.jacfwd(flat)(x)
    for i in range(5):
        h = 1e-6
        e = jnp.zeros(5).at[i].set(h)
        fd = (flat(x + e) - flat(x - e)) / (2 * h)
        # piecewise-smooth force (slip onsets): compare in RMS; FD error O(h) at the kinks
        scale = float(jnp.sqrt(jnp.mean(J[:, i] ** 2)))
        assert float(jnp.sqrt(jnp.mean((J[:, i] - fd) ** 2))) < 2e-3 * scale, i


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
