"""Bad input: clear errors at the Python boundary (ValueError) and inside jit (error_if)."""

import subprocess
import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import tribojax as tj
from conftest import make_model


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        (dict(D=2.0, G=1e-9, M=1.0), r"D = 2 is outside the allowed range \(2, 3\)"),
        (dict(D=3.2, G=1e-9, M=1.0), r"D = 3.2 is outside the allowed range \(2, 3\)"),
        (dict(D=2.5, G=0.0, M=1.0), r"G = 0 m is outside the allowed range \(0, inf\)"),
        (dict(D=2.5, G=1e-9, M=0.5), r"M = 0.5 is outside the allowed range \[1, inf\)"),
        (dict(D=2.5, G=1e-9, M=1.0, gamma=1.0), r"gamma = 1 is outside .* \(1, inf\)"),
        (dict(D=float("nan"), G=1e-9, M=1.0), r"D = nan is outside"),
    ],
)
def test_surface_rejects(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        tj.FractalSurface(**kwargs)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        (dict(E_star=0.0), r"E_star = 0 Pa is outside the allowed range \(0, inf\)"),
        (dict(G_star=-1.0), r"G_star = -1 Pa"),
        (dict(H=-1.0), r"H = -1 Pa"),
        (dict(nu=0.6), r"nu = 0.6 is outside the allowed range \(-1, 0.5\)"),
        (dict(sigma_s=0.0), r"sigma_s = 0 Pa"),
    ],
)
def test_pair_rejects(kwargs, pattern):
    base = dict(E_star=41e9, G_star=9e9, H=1.4e9, nu=0.164, sigma_s=1e9)
    with pytest.raises(ValueError, match=pattern):
        tj.ContactPair(**{**base, **kwargs})


def test_model_rejects_bad_constants_and_load(model):
    with pytest.raises(ValueError, match=r"mu_t = -0.1 is outside"):
        make_model(mu_t=-0.1)
    with pytest.raises(ValueError, match=r"mass = 0 kg"):
        make_model(mass=0.0)
    with pytest.raises(ValueError, match=r"tangential_load = -1 N is outside .* \[0, inf\)"):
        make_model(tangential_load=-1.0)
    with pytest.raises(ValueError, match=r"load = 0 N is outside the allowed range \(0, inf\)"):
        model(0.0)
    with pytest.raises(ValueError, match=r"load = -3 N"):
        model(jnp.array(-3.0))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"load is outside"):  # traced under vmap
        jax.vmap(model)(jnp.array([3.0, -3.0]))
    with pytest.raises(ValueError, match="area must be 'truncated' or 'real'"):
        make_model(area="apparent")
    with pytest.raises(ValueError, match="must be a number"):
        make_model(mu_t="0.1")


def test_tangential_ratio_must_stay_below_mu_t():
    with pytest.raises(ValueError, match=r"T/P = 0.5, mu_t = 0.1416"):
        make_model(tangential_load=1.0)(2.0)


JIT_ERRORS = (eqx.EquinoxRuntimeError, jax.errors.JaxRuntimeError)


def test_errors_inside_jit(model):
    with pytest.raises(JIT_ERRORS, match=r"load is outside the allowed range"):
        jax.jit(lambda m, F: m(F).K_tau)(model, -1.0)
    f = eqx.filter_jit(lambda m, F: m(F).K_tau)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"load is outside the allowed range"):
        f(model, -1.0)
    with pytest.raises(eqx.EquinoxRuntimeError, match="tangential_load / load must be below mu_t"):
        f(model, 1.0)
    build = eqx.filter_jit(lambda D: make_model(D=D)(5.0).K_tau)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"D is outside the allowed range \(2, 3\)"):
        build(3.5)
    grad = eqx.filter_jit(jax.grad(lambda G: make_model(G=G)(5.0).K_tau))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"G is outside the allowed range"):
        grad(-1e-8)


def test_failed_load_balance_is_reported(model):
    # one Newton step cannot converge from the all-plastic start
    stubborn = make_model(max_steps=1)
    with pytest.raises(eqx.EquinoxRuntimeError, match="load balance .* did not converge"):
        stubborn(5.0)
    quiet = make_model(max_steps=1, throw=False)
    assert not bool(quiet(5.0).converged)
    assert bool(model(5.0).converged)


def test_all_plastic_contact_is_reported():
    # a huge G puts every asperity in the plastic regime: no tangential stiffness
    with pytest.raises(eqx.EquinoxRuntimeError, match="every asperity is fully plastic"):
        make_model(G=1e-3)(5.0)
    out = make_model(G=1e-3, throw=False)(5.0)
    assert bool(out.all_plastic) and float(out.K_tau) == 0.0 and float(out.z_max) == 0.0


def test_float32_is_refused():
    code = (
        "import jax, tribojax as tj\n"
        "jax.config.update('jax_enable_x64', False)\n"
        "try:\n"
        "    tj.FractalSurface(2.5, 1e-9, 1.0)\n"
        "except RuntimeError as e:\n"
        "    print('refused:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "refused: tribojax needs float64" in out.stdout


def test_import_enables_float64():
    code = "import tribojax, jax.numpy as jnp; print(jnp.asarray(1.0).dtype)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "float64"


def test_runtime_message_is_the_check_text_alone(model):
    from tribojax._checks import runtime_message

    f = eqx.filter_jit(lambda m, F: m(F).K_tau)
    with pytest.raises(eqx.EquinoxRuntimeError) as info:
        f(model, -1.0)
    msg = runtime_message(info.value)
    assert msg.startswith("load is outside the allowed range") and "\n" not in msg
    assert runtime_message(RuntimeError("first line\nsecond")) == "first line"


def test_a_failure_carried_as_nan_is_raised_at_the_boundary():
    # a program compiled with failures as NaN (no host callback) returns NaN where a traced check
    # fails; the boundary turns that into an error naming what was computed
    from tribojax._checks import check_range, failures_as_nan, finite_or_raise

    @jax.jit
    def f(x):
        return check_range(x, "alpha", 0.0) * 2.0

    with failures_as_nan():
        bad = f(jnp.asarray(-1.0))
    assert jnp.isnan(bad)
    with pytest.raises(RuntimeError, match="Tables 4-7 at alpha = -1: the result is not finite"):
        finite_or_raise(bad, "Tables 4-7 at alpha = -1")
    assert float(finite_or_raise(f(jnp.asarray(3.0)), "x")) == 6.0
    # a reproduction entry point checks its input where it enters
    from tribojax._reproduce._tables4to7 import table3_phase_slips

    with pytest.raises(ValueError, match=r"alpha = -0.5 is outside the allowed range \(0, inf\)"):
        table3_phase_slips(-0.5)


def _compile_log(fn):
    """(result of fn(), JAX's compile-log lines: persistent-cache hits, writes, refusals)."""
    import logging

    lines = []

    class Keep(logging.Handler):
        def emit(self, record):
            lines.append(record.getMessage())

    log = logging.getLogger("jax._src.compiler")
    handler, level = Keep(level=logging.DEBUG), log.level
    log.addHandler(handler)
    log.setLevel(logging.DEBUG)
    try:
        return fn(), lines
    finally:
        log.removeHandler(handler)
        log.setLevel(level)


@pytest.mark.slow
def test_eager_calls_compile_cacheable_programs_and_still_raise_the_checks_message():
    # issue 31: a library call made outside any trace compiles without host callbacks (JAX 0.10
    # never stores those), and a failure still reaches the user as the check's own message
    from tribojax._checks import cacheable_call, check_range, mode_jit

    f = mode_jit(lambda F: check_range(F, "load", 0.0) * 2.0)  # as tribojax's own jits
    _, plain = _compile_log(lambda: f(jnp.asarray([1.0, 2.0, 3.0])))
    assert any("uses host callbacks" in m for m in plain)  # the raising check is a callback
    out, lines = _compile_log(lambda: cacheable_call(f, jnp.asarray([1.0, 2.0, 3.0, 4.0])))
    assert out.tolist() == [2.0, 4.0, 6.0, 8.0]
    assert lines and not any("uses host callbacks" in m for m in lines)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"load is outside the allowed range"):
        cacheable_call(f, jnp.asarray([1.0, -2.0, 3.0, 4.0]))
    # simulate_slip called eagerly (a save grid no other test uses: compiled here or read back)
    el = tj.PreSlipLuGre(*map(jnp.asarray, (1.1, 2.0e7, 150.0, 1.0)))  # arrays: traced in both
    ts = jnp.linspace(0.0, 0.3, 53)
    sol, lines = _compile_log(lambda: tj.simulate_slip(el, ts=ts, t_end=0.3))
    assert bool(sol.ok) and np.all(np.isfinite(np.asarray(sol.slip)))
    assert not any("uses host callbacks" in m for m in lines), lines
    assert any("cache hit" in m or "compile" in m for m in lines)
    # the raising program that a caller's jit traces gives the same slip to the solver's
    # accuracy, not bit for bit: the NaN-mode check is another XLA program, and the step
    # control carries a rounding difference to rtol level (measured 1.3e-14 m of 1.9e-8 m)
    traced = np.asarray(jax.jit(lambda e: tj.simulate_slip(e, ts=ts, t_end=0.3).slip)(el))
    peak = np.max(np.abs(traced))
    assert peak > 1e-8 and np.max(np.abs(traced - np.asarray(sol.slip))) < 1e-5 * peak
