"""Stage acceleration profiles: wang2022's trapezoid, piecewise-linear and measured ones."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad

import tribojax as tj


def test_default_trapezoid_is_reproduction_profile():
    p = tj.TrapezoidProfile()
    # docs/reproduction.md: ramps 0.10-0.25, 0.60-0.75, 1.50-1.65, 2.00-2.15 s, a_max 1 m/s^2
    np.testing.assert_allclose(
        np.asarray(p.kinks()), [0.1, 0.25, 0.6, 0.75, 1.5, 1.65, 2.0, 2.15], atol=1e-14
    )
    t = jnp.array([0.0, 0.175, 0.4, 1.0, 1.575, 1.8, 2.3])
    np.testing.assert_allclose(
        np.asarray(p.acceleration(t)), [0, 0.5, 1, 0, -0.5, -1, 0], atol=1e-12
    )
    assert float(p.v_max) == pytest.approx(0.5, rel=1e-14)
    np.testing.assert_allclose(np.asarray(p.windows()), [[0.25, 0.6], [0.73, 1.5], [1.65, 2.0]])


def test_trapezoid_velocity_peaks_at_v_max_and_returns_to_rest():
    p = tj.TrapezoidProfile(a_max=2.0, ramp=0.1, hold=0.2, cruise=0.3)
    f = lambda t: float(p.acceleration(t))  # noqa: E731
    knots = [float(k) for k in p.kinks()]
    v_peak = quad(f, 0, knots[3], points=knots[:4], epsabs=1e-13)[0]
    v_end = quad(f, 0, knots[-1] + 0.1, points=knots, epsabs=1e-13)[0]
    assert v_peak == pytest.approx(float(p.v_max), rel=1e-10)
    assert v_end == pytest.approx(0.0, abs=1e-12)


def test_from_v_max():
    p = tj.TrapezoidProfile.from_v_max(a_max=1.0, v_max=0.5, ramp=0.15)
    assert float(p.hold) == pytest.approx(0.35)
    with pytest.raises(ValueError, match="v_max"):
        tj.TrapezoidProfile.from_v_max(a_max=1.0, v_max=0.1, ramp=0.15)


def test_piecewise_linear_and_gradient():
    p = tj.PiecewiseLinearProfile([0.0, 1.0, 2.0], [0.0, 2.0, -1.0])
    assert float(p.acceleration(0.5)) == pytest.approx(1.0)
    assert float(p.acceleration(3.0)) == pytest.approx(-1.0)  # constant beyond the last node
    g = jax.grad(lambda a: tj.TrapezoidProfile(a_max=a).acceleration(0.4))(1.5)
    assert float(g) == pytest.approx(1.0)
    jitted = jax.jit(lambda q, t: q.acceleration(t))(p, 1.5)
    assert float(jitted) == pytest.approx(0.5)


@pytest.mark.parametrize(
    "times, acc, match",
    [
        ([0.0, 1.0, 1.0], [0.0, 1.0, 2.0], "strictly increasing"),
        ([0.0, 2.0, 1.0], [0.0, 1.0, 2.0], "strictly increasing"),
        ([0.0, 1.0, 2.0], [0.0, float("nan"), 2.0], "NaN"),
        ([0.0, float("nan"), 2.0], [0.0, 1.0, 2.0], "NaN"),
        ([0.0], [1.0], "length"),
    ],
)
def test_bad_profiles(times, acc, match):
    with pytest.raises(ValueError, match=match):
        tj.PiecewiseLinearProfile(times, acc)
    with pytest.raises(ValueError, match=match):
        tj.MeasuredProfile(times, acc)


def test_bad_trapezoid():
    with pytest.raises(ValueError, match="a_max"):
        tj.TrapezoidProfile(a_max=0.0)
    with pytest.raises(ValueError, match="ramp"):
        tj.TrapezoidProfile(ramp=-0.1)


def test_measured_profile_from_file(tmp_path):
    t = np.linspace(0, 1, 11)
    good = tmp_path / "acc.csv"
    good.write_text(
        "# accelerometer\ntime_s,acceleration_m_per_s2\n" + "".join(f"{a},{np.sin(a)}\n" for a in t)
    )
    p = tj.MeasuredProfile.from_file(good)
    assert float(p.acceleration(0.55)) == pytest.approx(np.interp(0.55, t, np.sin(t)), rel=1e-12)
    assert p.kinks() is None
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,acceleration_m_per_s2\n0,1\n0.1,nan\n")
    with pytest.raises(tj.DataFileError, match="line 3"):
        tj.MeasuredProfile.from_file(bad)
    back = tmp_path / "back.csv"
    back.write_text("time_s,acceleration_m_per_s2\n0,1\n0.2,1\n0.1,0\n")
    with pytest.raises(ValueError, match="back.csv.*strictly increasing"):
        tj.MeasuredProfile.from_file(back)


def test_sampled_drive_stops_at_its_kinks_only_when_they_are_few():
    # a sampled trapezoid: linear between all samples, solver stops at its corners and ends
    t = np.linspace(0.0, 2.3, 461)
    a = np.asarray(tj.TrapezoidProfile().acceleration(t))
    p = tj.MeasuredProfile.from_samples(t, a)
    np.testing.assert_array_equal(np.asarray(p.accelerations), a)
    np.testing.assert_allclose(
        np.asarray(p.kinks()), [0, 0.1, 0.25, 0.6, 0.75, 1.5, 1.65, 2.0, 2.15, 2.3], atol=1e-12
    )
    # noisy measured data kink at every sample: the step controller handles them, no stops
    noisy = a + 1e-3 * np.random.default_rng(0).standard_normal(t.size)
    assert tj.MeasuredProfile.from_samples(t, noisy).kinks() is None
    # a short coarse log stops at every sample
    coarse = tj.MeasuredProfile.from_samples([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, -1.0, 0.5])
    np.testing.assert_array_equal(np.asarray(coarse.kinks()), [0.0, 1.0, 2.0, 3.0])
    assert tj.MeasuredProfile([0.0, 1.0], [0.0, 1.0], stop_at_samples=True).kinks() is not None


def test_displacement_history():
    h = tj.DisplacementHistory([0.0, 1.0, 3.0], [0.0, 2.0, 1.0])
    np.testing.assert_allclose(np.asarray(h.displacement(jnp.array([0.5, 2.0, 5.0]))), [1, 1.5, 1])
    np.testing.assert_allclose(np.asarray(h.velocity(jnp.array([0.5, 1.0, 2.0]))), [2, -0.5, -0.5])
    with pytest.raises(ValueError, match="displacements must be 1-D"):
        tj.DisplacementHistory([0.0, 1.0], [0.0])
