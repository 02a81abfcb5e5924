"""Rodas4 (tribojax._dynamics._rodas4) on linear test problems with known solutions."""

import diffrax as dfx
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.linalg import expm

import tribojax as tj

A = np.array([[-1.0, 2.0], [-3.0, -50.0]])  # eigenvalues ~ -1.1 and -49.9
B = np.array([1.0, 0.5])
Y0 = np.array([1.0, 0.5])


def exact(t):
    """Solution of y' = A y + b t, y(0) = y0: expm(A t)(y0 − p(0)) + p(t), p(t) = −A⁻¹b t − A⁻²b."""
    ai = np.linalg.inv(A)

    def p(s):
        return -ai @ B * s - ai @ ai @ B

    return expm(A * t) @ (Y0 - p(0.0)) + p(t)


def solve(dt0, controller=None, ts=(0.37, 1.0)):
    term = dfx.ODETerm(lambda t, y, a: jnp.asarray(A) @ y + jnp.asarray(B) * t)
    kw = {} if controller is None else dict(stepsize_controller=controller)
    sol = dfx.diffeqsolve(
        term,
        tj.Rodas4(),
        0.0,
        1.0,
        jnp.asarray(dt0),
        jnp.asarray(Y0),
        saveat=dfx.SaveAt(ts=jnp.asarray(ts)),
        **kw,
    )
    return np.asarray(sol.ys)


@pytest.mark.slow
def test_fourth_order_convergence_and_dense_output():
    errs = []
    for n in (10, 20, 40, 80):
        mid = (n // 2 + 0.5 + np.arange(5)) / n  # step midpoints past the stiff transient
        ys = solve(1.0 / n, ts=(*mid, 1.0))
        want = np.stack([exact(t) for t in (*mid, 1.0)])
        errs.append((np.abs(ys[-1] - want[-1]).max(), np.abs(ys[:-1] - want[:-1]).max()))
    e = np.array(errs)
    order = np.log2(e[:-1, 0] / e[1:, 0])
    # Rodas4 is order 4 (Hairer & Wanner IV.7); the first halving is still pre-asymptotic
    assert np.all(order[1:] > 3.7) and np.all(order < 4.6), order
    # dense output (RODAS's, order 3 locally) at step midpoints: measured errors ~1.3x the
    # step-end ones and the same global order 4 on this problem
    dense_order = np.log2(e[:-1, 1] / e[1:, 1])
    assert np.all(dense_order > 3.5), dense_order
    assert e[-1, 0] < 1e-10 and e[-1, 1] < 1e-10, e[-1]


def test_adaptive_solve_meets_tolerance():
    ys = solve(1e-3, dfx.PIDController(rtol=1e-8, atol=1e-10))
    np.testing.assert_allclose(ys[1], exact(1.0), rtol=1e-7)
    np.testing.assert_allclose(ys[0], exact(0.37), rtol=1e-6)  # dense output


@pytest.mark.parametrize("lam", [1e4, 1e8])
def test_stiff_prothero_robinson_one_big_step(lam):
    # y' = -lam (y - cos t) - sin t, y(0) = 1: solution cos t. L-stability and stiff accuracy
    # keep one step of h = 0.1 at the smooth solution however large lam is.
    term = dfx.ODETerm(lambda t, y, a: -lam * (y - jnp.cos(t)) - jnp.sin(t))
    sol = dfx.diffeqsolve(term, tj.Rodas4(), 0.0, 0.1, 0.1, jnp.array([1.0]))
    assert abs(float(sol.ys[0, 0]) - np.cos(0.1)) < 1e-6


@pytest.mark.slow
def test_unrolled_lu_solves_like_lapack_with_pivoting():
    from tribojax._dynamics._rodas4 import SMALL_N, _lu_small, _lu_solve_small

    rng = np.random.default_rng(7)
    for n in range(1, SMALL_N + 1):
        for trial in range(10):
            w = rng.normal(size=(n, n))
            if n > 1 and trial % 2:
                w[0, 0] = 1e-14  # a zero first pivot: only row exchanges solve this
            b = rng.normal(size=n)
            lu = _lu_small(jnp.asarray(w))
            for trans, m in ((False, w), (True, w.T)):
                want = np.linalg.solve(m, b)
                got = np.asarray(_lu_solve_small(lu, jnp.asarray(b), trans=trans))
                tol = 1e-14 * np.linalg.cond(m) * np.abs(want).max()
                np.testing.assert_allclose(got, want, rtol=0, atol=tol)


def test_system_above_the_unrolled_size_is_accurate():
    from tribojax._dynamics._rodas4 import SMALL_N

    # above SMALL_N states Rodas4's default factorisation is LAPACK's LU
    n = SMALL_N + 2  # a stiff diagonal chain y_i' = -k_i y_i: y_i = exp(-k_i t)
    k = jnp.logspace(0, 3, n)
    term = dfx.ODETerm(lambda t, y, a: -k * y)
    sol = dfx.diffeqsolve(
        term,
        tj.Rodas4(),
        0.0,
        1.0,
        1e-3,
        jnp.ones(n),
        stepsize_controller=dfx.PIDController(rtol=1e-9, atol=1e-12),
    )
    np.testing.assert_allclose(
        np.asarray(sol.ys[-1]), np.exp(-np.asarray(k)), rtol=1e-6, atol=1e-12
    )


_ONE_KERNEL = r"""
import json, os, sys
import tribojax as tj
if os.environ.get("ONE_KERNEL") == "1":
    tj.use_one_kernel()
import jax, jax.numpy as jnp
el = lambda f: tj.PreSlipLuGre(f, 2.1478e7, 708.8274, 1.0)
txt = jax.jit(lambda f: tj.simulate_slip(el(f)).slip).lower(0.7372).compile().as_text()
p = [float(v) for v in tj.slip_phase_averages(el(0.7372))]
import re
step_loop = [line for line in txt.splitlines()  # diffrax's loop over the ODE steps
             if re.search(r'outer-loop/(checkpointed-no-vjp/)?while"', line)]
whole = any(" call(" in line and "xla_cpu_small_call" in line for line in step_loop)
from tribojax._chain import phase_slips
chain = jax.jit(lambda f: phase_slips(el(f))).lower(0.7372).compile().as_text()
flags = os.environ.get("XLA_FLAGS", "")
print(json.dumps(dict(flags=flags, whole=whole, lapack="lapack" in txt, phases=p,
                      chain_lapack="lapack" in chain)))
"""


def _one_kernel_probe(code=_ONE_KERNEL, **env):
    import json
    import os
    import subprocess
    import sys

    clean = {k: v for k, v in os.environ.items() if k not in ("XLA_FLAGS", "TRIBOJAX_XLA_HOIST")}
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**clean, **env},
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_slip_solve_is_one_kernel_on_request_within_its_tolerance_of_xlas_loops():
    from tribojax._xla import HOIST_FLAG

    hoisted = _one_kernel_probe(ONE_KERNEL="1")
    assert HOIST_FLAG in hoisted["flags"]
    # diffrax's step loop moved into a call XLA:CPU compiles as one kernel, no LAPACK call left
    # in it (docs/performance.md)
    assert hoisted["whole"] and not hoisted["lapack"]
    plain = _one_kernel_probe()
    # without the option: XLA's own loop of kernels, the same unrolled LU (Rodas4.lu, not the
    # environment, chooses the factorisation)
    assert plain["flags"] == "" and not plain["whole"] and not plain["lapack"]
    # the wang2022 chain keeps LAPACK's LU in both (`PAPER_SOLVER`)
    assert hoisted["chain_lapack"] and plain["chain_lapack"]
    # the same arithmetic fused differently, whose rounding moves the adaptive steps: wang2022's
    # phase slips agree within the solve's rtol 1e-6
    np.testing.assert_allclose(hoisted["phases"], plain["phases"], rtol=1e-6)


def test_one_kernel_is_an_explicit_choice_that_leaves_a_users_options_alone():
    show = (
        "import json, os, tribojax as tj; r = {}; r['after_import'] = os.environ.get("
        "'XLA_FLAGS', ''); r['chosen'] = tj.use_one_kernel(); "
        "r['flags'] = os.environ.get('XLA_FLAGS', ''); print(json.dumps(r))"
    )
    # importing tribojax writes no XLA option; asking for it does
    out = _one_kernel_probe(show)
    assert out["after_import"] == "" and out["chosen"] and "small_while_loop" in out["flags"]
    # a user's own backend options stay: the flag cannot merge with them, so it is not set
    mine = "--xla_backend_extra_options=xla_cpu_small_while_loop_byte_threshold=1024 "
    mine2 = "--xla_backend_extra_options=xla_cpu_enable_fast_math=false"
    out = _one_kernel_probe(show, XLA_FLAGS=mine2)
    assert out == {"after_import": mine2, "chosen": False, "flags": mine2}
    assert _one_kernel_probe(show, XLA_FLAGS=mine)["flags"] == mine  # already raised: kept
    # a backend already running has read XLA_FLAGS: refused with the reason, nothing written;
    # Rodas4's factorisation does not depend on any of it
    late = (
        "import json, os, jax; jax.numpy.zeros(1).block_until_ready(); import tribojax as tj\n"
        "try:\n    tj.use_one_kernel(); e = ''\nexcept RuntimeError as err:\n    e = str(err)\n"
        "from tribojax._dynamics._rodas4 import unrolled_lu\n"
        "print(json.dumps([os.environ.get('XLA_FLAGS', ''), e, unrolled_lu(4)]))"
    )
    flags, err, unrolled = _one_kernel_probe(late)
    assert flags == "" and "backend has started" in err and unrolled


def test_cli_refuses_an_unknown_one_kernel_setting(tmp_path):
    import os
    import subprocess
    import sys

    cmd = [
        sys.executable,
        "-m",
        "tribojax._cli._main",
        "contact",
        "--D",
        "2.5",
        "--G",
        "1e-9",
        "--load",
        "5",
    ]
    out = subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "TRIBOJAX_XLA_HOIST": "maybe"},
    )
    assert out.returncode == 2 and "TRIBOJAX_XLA_HOIST = 'maybe'" in out.stderr


def test_rodas4_refuses_an_unknown_factorisation():
    with pytest.raises(ValueError, match="lu = 'qr'"):
        tj.Rodas4(lu="qr")
