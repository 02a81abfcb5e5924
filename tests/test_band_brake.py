"""The band-brake element (issue 30): a play operator whose backbone is a drag spring across a
clearance and an exponential (capstan) rise to a slip force per direction.

The reference is a NumPy loop written here from the physical description (a drum position e
that follows the drive until the band slips at e₊ or e₋; force k_g·e in the clearance, then
k_g·g + A(e^{β(e−g)} − 1) up to F), sharing no code with the element. Records made with it show
that fit_history identifies the parameters and predicts another drive; the generator was written
by the same hand as the element, so this is an implementation cross-check, not a blind test."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj

P = dict(
    F_pos=12e3,
    F_neg=9e3,
    gap_pos=1.5e-3,
    gap_neg=1.8e-3,
    k_gap=1.2e5,
    A_pos=2.4e3,
    A_neg=1.5e3,
    beta_pos=700.0,
    beta_neg=900.0,
)


def _reference(u, p):
    """Force history of the band brake, from rest at u[0] (NumPy loop)."""

    def side(e, gap, A, beta):
        return p["k_gap"] * e if e <= gap else p["k_gap"] * gap + A * np.expm1(beta * (e - gap))

    def limit(gap, A, beta, F):
        return gap + np.log1p((F - p["k_gap"] * gap) / A) / beta

    hi = limit(p["gap_pos"], p["A_pos"], p["beta_pos"], p["F_pos"])
    lo = -limit(p["gap_neg"], p["A_neg"], p["beta_neg"], p["F_neg"])
    e, out = 0.0, np.zeros_like(u)
    for i in range(1, u.size):
        e = min(max(e + u[i] - u[i - 1], lo), hi)
        if e >= 0:
            out[i] = min(side(e, p["gap_pos"], p["A_pos"], p["beta_pos"]), p["F_pos"])
        else:
            out[i] = -min(side(-e, p["gap_neg"], p["A_neg"], p["beta_neg"]), p["F_neg"])
    return out


def _drive(n=1201, seed=0, amplitude=8e-3):
    """A random-phase two-tone displacement history (m) with partial reversals."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 6.0, n)
    ph = rng.uniform(0, 2 * np.pi, 2)
    return t, amplitude * (
        np.sin(2 * np.pi * 0.5 * t + ph[0]) + 0.4 * np.sin(2 * np.pi * 2.1 * t + ph[1])
    )


def test_element_matches_the_numpy_reference():
    _, u = _drive()
    f = np.asarray(tj.drive(tj.BandBrake(**P), u))
    ref = _reference(u, P)
    assert np.max(np.abs(f - ref)) < 1e-9 * P["F_pos"]
    # the slip forces are reached both ways, and the clearance is crossed
    assert f.max() == pytest.approx(P["F_pos"]) and f.min() == pytest.approx(-P["F_neg"])
    e = tj.BandBrake(**P).limits()
    assert float(e[0]) < -P["gap_neg"] and float(e[1]) > P["gap_pos"]


def test_force_law_pieces():
    el = tj.BandBrake(**P)
    assert float(el.force(1e-3)) == pytest.approx(P["k_gap"] * 1e-3)  # inside the clearance
    e = P["gap_pos"] + 1e-3
    rise = P["k_gap"] * P["gap_pos"] + P["A_pos"] * np.expm1(P["beta_pos"] * 1e-3)
    assert float(el.force(e)) == pytest.approx(rise, rel=1e-12)
    lo, hi = el.limits()
    assert float(el.force(hi)) == pytest.approx(P["F_pos"], rel=1e-12)
    assert float(el.force(lo)) == pytest.approx(-P["F_neg"], rel=1e-12)


@pytest.mark.usefixtures("storable_programs")
def test_jit_vmap_and_gradients_against_finite_differences():
    _, u = _drive(n=301, seed=1)
    u = jnp.asarray(u)
    names = list(P)

    def energy(x):
        f = tj.drive(tj.BandBrake(*x), u)
        return jnp.sum(f * jnp.gradient(u))  # work done on the device, J

    x0 = jnp.asarray([P[n] for n in names])
    assert float(jax.jit(energy)(x0)) == pytest.approx(float(energy(x0)), rel=1e-12)
    g = jax.grad(energy)(x0)
    for i, name in enumerate(names):
        h = 1e-6 * float(x0[i])
        fd = (energy(x0.at[i].add(h)) - energy(x0.at[i].add(-h))) / (2 * h)
        assert float(g[i]) == pytest.approx(
            float(fd), rel=1e-5, abs=1e-9 * abs(float(fd)) + 1e-12
        ), name
    batch = jnp.stack([x0, x0.at[0].multiply(1.1)])
    vals = jax.vmap(energy)(batch)
    assert float(vals[0]) == pytest.approx(float(energy(x0)), rel=1e-12)


def test_bad_parameter_names_itself():
    with pytest.raises(ValueError, match=r"gap_neg = -0.001 m is outside the allowed range"):
        tj.BandBrake(**{**P, "gap_neg": -1e-3})


@pytest.mark.slow
def test_fit_history_identifies_it_and_predicts_another_drive():
    rng = np.random.default_rng(5)
    recs = []
    for seed, amp in ((2, 8e-3), (3, 12e-3)):
        t, u = _drive(seed=seed, amplitude=amp)
        f = _reference(u, P) + 40.0 + rng.normal(0.0, 60.0, u.size)
        recs.append(tj.HysteresisLoop(t, u, f, periodic=False, source=f"<drive {seed}>"))
    fit = tj.fit_history(recs, "band_brake")
    assert fit.fit.converged
    got = dict(zip(fit.fit.names, fit.fit.values))
    for name in ("F_pos", "F_neg", "gap_pos", "gap_neg"):
        assert got[name] == pytest.approx(P[name], rel=0.05), name
    assert got["f0"] == pytest.approx(40.0, abs=15.0)
    t, u = _drive(seed=4, amplitude=10e-3)
    held = tj.HysteresisLoop(t, u, _reference(u, P) + 40.0, periodic=False)
    _, nrmse = tj.predict_history(fit, held)
    assert nrmse < 0.02  # the noise, 60 N, is 0.01 of the force's sd
    jenkins = tj.fit_history(recs, "jenkins")
    assert tj.predict_history(jenkins, held)[1] > 5 * nrmse


@pytest.mark.slow
def test_a_record_that_starts_loaded_is_predicted_from_its_first_force():
    el = tj.BandBrake(**P)
    for F in (-8e3, -1e3, 0.0, 150.0, 5e3, 11.9e3):  # inverse of the force law
        assert float(el.force(el.state_for_force(F))) == pytest.approx(F, abs=1e-6)
    assert float(el.state_for_force(20e3)) == pytest.approx(float(el.limits()[1]))
    jen = tj.Jenkins(0.3, 100.0, 1e6)
    assert float(jen.force(jen.state_for_force(-12.0), 0.0)) == pytest.approx(-12.0)
    # the NumPy reference started in the state of a 6 kN force (a band left loaded), + f0
    t, u = _drive(seed=6, amplitude=3e-3)
    lo, hi = el.limits()
    e0 = float(el.state_for_force(6e3))
    assert float(lo) < e0 < float(hi)
    f = _reference(np.r_[u[0] - e0, u], P)[1:]  # one step from rest to e0, then the drive
    held = tj.HysteresisLoop(t, u, f + 40.0, periodic=False)
    t2, u2 = _drive(seed=2, amplitude=8e-3)
    fitted = tj.HysteresisLoop(t2, u2, _reference(u2, P) + 40.0, periodic=False)
    # a noise-free record: the standard errors are ~0, so the step left is many of them and the
    # fit says short_of_optimum (issue 68); its values are what this test uses
    fit = tj.fit_history(fitted, "band_brake", throw=False)
    rest = tj.predict_history(fit, held)[1]
    measured = tj.predict_history(fit, held, initial="measured")[1]
    assert measured < 0.02 and rest > 5 * measured
    saved = tj.fitted_model(fit)
    assert tj.predict(saved, held, initial="measured").nrmse == pytest.approx(measured, rel=1e-9)
    lugre = tj.FittedModel(
        "history",
        {"sigma0": 1e6, "F_c": 1e4, "F_s": 1e4, "v_s": 0.01, "f0": 0.0},
        {},
        {"element": "lugre"},
    )
    with pytest.raises(ValueError, match=r"initial = 'measured' is not one of \['rest'\]"):
        tj.predict(lugre, held, initial="measured")
