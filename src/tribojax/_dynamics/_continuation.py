"""Pseudo-arclength continuation of multi-harmonic-balance solutions, and `FrequencyResponse`.

The branch z(s) = (X, λ) of R(X, λ) = 0 is followed in the arclength s of the scaled unknowns
(X / x_ref, λ / |λ_end − λ₀|): a step predicts along the unit tangent (the null vector of ∂R/∂z)
and corrects by Newton with Keller's condition t·(z − z_pred) = 0, so turning points need no
special treatment (step control: docs/structures.md). Stability: Hill's method (`_mhb`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from .._export import cached_jit
from .._precision import ensure_x64
from .._results import RESULTS, result_name
from ._mhb import FrictionSystem, floquet_exponents, solve_hbm

_COS_MAX_TURN = 0.98  # cos(0.2 rad)
_JAC_BLOCK = 64  # Hill stability: Jacobians of the branch's points, this many per call


def _tangent(full, z, prev, args):
    J = jax.jacfwd(full)(z, args)
    A = jnp.concatenate([J, prev[None, :]])
    e = jnp.zeros(z.shape[0]).at[-1].set(1.0)
    t = jnp.linalg.solve(A, e)
    return t / jnp.linalg.norm(t)


@cached_jit
def _arclength(fn, y0, lam0, lam_end, args, ds, ds_min, ds_max, max_points, max_newton, tol):
    """Continue R(y, λ) = fn(y, λ, args) from the solution (y0, λ0) towards λ_end (scaled y)."""
    lam_scale = jnp.abs(lam_end - lam0)
    direction = jnp.sign(lam_end - lam0)

    def full(z, a):
        return fn(z[:-1], lam0 + z[-1] * lam_scale, a)

    z0 = jnp.concatenate([y0, jnp.zeros(1)])
    n = z0.shape[0]
    e_lam = jnp.zeros(n).at[-1].set(direction)
    t0 = _tangent(full, z0, e_lam, args)
    t0 = t0 * jnp.sign(t0[-1] * direction)
    Z = jnp.full((max_points, n), jnp.nan).at[0].set(z0)
    steps = jnp.zeros(max_points, dtype=jnp.int32)
    solver = optx.Newton(rtol=tol, atol=tol)

    def cond(c):
        return c["code"] < 0

    def body(c):
        z, t, ds = c["z"], c["t"], c["ds"]
        z_pred = z + ds * t

        def aug(w, a):
            return jnp.concatenate([full(w, a), jnp.dot(t, w - z_pred)[None]])

        sol = optx.root_find(
            aug,
            solver,
            z_pred,
            args,
            max_steps=max_newton,
            throw=False,
            adjoint=optx.RecursiveCheckpointAdjoint(),
        )
        z_new = sol.value
        ok = (sol.result == optx.RESULTS.successful) & jnp.all(jnp.isfinite(z_new))
        ok = ok & (jnp.dot(z_new - z, t) > 0.0)
        t_new = _tangent(full, jnp.where(ok, z_new, z), t, args)
        ok = ok & jnp.all(jnp.isfinite(t_new))
        ok = ok & ((jnp.dot(t_new, t) > _COS_MAX_TURN) | (ds <= 2.0 * ds_min))
        nsteps = sol.stats["num_steps"]
        i = c["i"] + jnp.where(ok, 1, 0)
        factor = jnp.where(nsteps <= 3, 1.5, jnp.where(nsteps > 6, 0.6, 1.0))
        size = jnp.maximum(1.0, jnp.max(jnp.abs(z_new[:-1])))  # steps relative on large branches
        ds_new = jnp.where(ok, jnp.clip(ds * factor, ds_min, ds_max * size), 0.5 * ds)
        reached = ok & ((z_new[-1] * lam_scale * direction) >= lam_scale)
        code = jnp.where(reached, 0, -1)
        code = jnp.where((code < 0) & (i >= max_points - 1), 2, code)
        code = jnp.where((code < 0) & (ds_new < ds_min), 1, code)
        return dict(
            z=jnp.where(ok, z_new, z),
            t=jnp.where(ok, t_new, t),
            ds=ds_new,
            i=i,
            Z=jnp.where(ok, c["Z"].at[i].set(z_new), c["Z"]),
            steps=jnp.where(ok, c["steps"].at[i].set(nsteps), c["steps"]),
            code=code,
        )

    init = dict(
        z=z0,
        t=t0,
        ds=jnp.asarray(ds, float),
        i=jnp.asarray(0),
        Z=Z,
        steps=steps,
        code=jnp.asarray(-1),
    )
    out = jax.lax.while_loop(cond, body, init)
    lam = lam0 + out["Z"][:, -1] * lam_scale
    return out["Z"][:, :-1], lam, out["steps"], out["i"] + 1, out["code"]


class FrequencyResponse(eqx.Module):
    """A continued branch of periodic solutions (NumPy arrays, one row per point).

    Fields: parameter (the continued parameter: ω in rad/s for `frequency_response`), omega
    (rad/s), X (n, N, n_coef: harmonic coefficients, m), amplitude (n, N: first-harmonic
    amplitude √(a₁² + b₁²) of each DOF, m), stable (n, bool; Hill's method), max_floquet (n: the
    largest real part of the Floquet exponents, 1/s), newton_steps (n), harmonics, result
    (`RESULTS`: successful, continuation_failed or continuation_incomplete).
    """

    parameter: np.ndarray
    omega: np.ndarray
    X: np.ndarray
    amplitude: np.ndarray
    stable: np.ndarray
    max_floquet: np.ndarray
    newton_steps: np.ndarray
    harmonics: tuple = eqx.field(static=True)
    result: RESULTS

    @property
    def converged(self) -> bool:
        return bool(self.result == RESULTS.successful)

    @property
    def message(self) -> str:
        return RESULTS[self.result]

    def peak(self, dof: int = 0):
        """(ω, amplitude) of the largest first-harmonic amplitude of `dof` on the branch."""
        i = int(np.argmax(self.amplitude[:, dof]))
        return float(self.omega[i]), float(self.amplitude[i, dof])

    def to_dict(self) -> dict:
        return {
            "parameter": self.parameter.tolist(),
            "omega": self.omega.tolist(),
            "amplitude": self.amplitude.tolist(),
            "stable": [bool(s) for s in self.stable],
            "harmonics": list(self.harmonics),
            "result": result_name(self.result),
            "message": self.message,
        }


_CODES = (RESULTS.successful, RESULTS.continuation_failed, RESULTS.continuation_incomplete)


def _checked_range(start, end, name):
    start, end = float(start), float(end)
    if not np.isfinite(start) or not np.isfinite(end) or start == end:
        raise ValueError(f"{name} range [{start:g}, {end:g}] must be finite and non-empty")
    return start, end


@cached_jit
def _jacobians(res, Y, lam, args):
    return jax.vmap(lambda y, p: jax.jacfwd(res)(y, p, args))(Y, lam)


def _freq_res(y, w, args):
    system, f_ref, x_ref = args
    X = y.reshape(system.n_dof, system.n_coef) * x_ref
    return (system.residual(X, w) / f_ref).reshape(-1)


def _param_res(y, p, args):
    make, omega, f_ref, x_ref = args
    return _freq_res(y, omega, (make(p), f_ref, x_ref))


def _run(system_of, res, first, lam0, lam1, X0, omega0, extra, opts, stability):
    ensure_x64()
    start = solve_hbm(first, omega0, X0)
    if not bool(start.converged):
        raise ValueError(
            f"the harmonic balance did not converge at the start ({RESULTS[start.result]}); give "
            "a start X0 or another start value"
        )
    f_ref, x_ref = first.scales(omega0)
    x_ref = jnp.maximum(x_ref, jnp.max(jnp.abs(start.X)))
    args = extra + (f_ref, x_ref)
    ds, ds_min, ds_max, max_points, max_newton, tol = opts
    Y, lam, steps, n, code = _arclength(
        res,
        start.X.reshape(-1) / x_ref,
        jnp.asarray(lam0),
        jnp.asarray(lam1),
        args,
        ds,
        ds_min,
        ds_max,
        int(max_points),
        int(max_newton),
        tol,
    )
    n, code = int(n), int(code)
    lam_n = np.asarray(lam[:n])
    if code == 0 and n > 1 and (lam_n[-1] - lam1) * np.sign(lam1 - lam0) > 0.0:
        n, lam_n = n - 1, lam_n[:-1]  # the last step passed the end of the range
    if n < 2 and code == 0:
        code = 1
    nd, nc = first.n_dof, first.n_coef
    X = np.asarray(Y[:n]).reshape(n, nd, nc) * float(x_ref)
    omega = np.array(lam_n) if system_of is None else np.full(n, omega0)
    amp = np.hypot(X[..., first.index(1)], X[..., first.index(1, True)])
    mf = np.full(n, np.nan)
    if stability:
        # the branch's n points in blocks of _JAC_BLOCK rows (one compilation serves every n;
        # the padding rows of the last block repeat the start point, never the NaN rows past
        # the branch's end, which a parameter continuation's model may refuse)
        blocks = []
        for k in range(0, n, _JAC_BLOCK):
            rows = jnp.arange(k, k + _JAC_BLOCK)
            rows = jnp.where(rows < n, rows, 0)
            blocks.append(np.asarray(_jacobians(res, Y[rows], lam[rows], args)))
        J = np.concatenate(blocks)[:n, :, : nd * nc] * float(f_ref / x_ref)
        if system_of is None:  # one system: one stacked eigenvalue call
            mf = floquet_exponents(first, None, omega, J).real.max(axis=-1)
        for i in range(n if system_of is not None else 0):
            mf[i] = floquet_exponents(system_of(lam_n[i]), X[i], omega[i], J[i]).real.max()
    return FrequencyResponse(
        parameter=lam_n,
        omega=omega,
        X=X,
        amplitude=amp,
        stable=mf < 1e-6 * omega,
        max_floquet=mf,
        newton_steps=np.asarray(steps[:n]),
        harmonics=first.harmonics,
        result=_CODES[code],
    )


def frequency_response(
    system: FrictionSystem,
    omega_start,
    omega_end,
    *,
    X0=None,
    ds=0.02,
    ds_min=1e-6,
    ds_max=0.3,
    max_points: int = 400,
    max_newton: int = 12,
    tol=1e-9,
    stability: bool = True,
) -> FrequencyResponse:
    """Forced response of `system` from ω = omega_start to omega_end (rad/s, > 0) by
    pseudo-arclength continuation (docs/structures.md); the start solved by `solve_hbm` from X0.

    Steps ds, ds_min, ds_max are in the scaled arclength (x / x_ref with x_ref the larger of the
    static deflection F/K and the start amplitude; ω / |ω_end − ω_start|). A continuation that
    stops early is reported in `result`, never as NaN points. Hill stability when `stability`.
    """
    w0, w1 = _checked_range(omega_start, omega_end, "frequency")
    if w0 <= 0 or w1 <= 0:
        raise ValueError(f"frequency range [{w0:g}, {w1:g}] rad/s must be > 0")
    opts = (ds, ds_min, ds_max, max_points, max_newton, tol)
    return _run(None, _freq_res, system, w0, w1, X0, w0, (system,), opts, stability)


def parameter_response(
    make_system,
    p_start,
    p_end,
    omega,
    *,
    X0=None,
    ds=0.02,
    ds_min=1e-6,
    ds_max=0.3,
    max_points: int = 400,
    max_newton: int = 12,
    tol=1e-9,
    stability: bool = True,
) -> FrequencyResponse:
    """Continuation in a scalar parameter p (e.g. the normal load) at fixed ω (rad/s).

    `make_system(p)` builds the `FrictionSystem` at p with JAX operations (it is traced).
    `parameter` holds p; `omega` is constant. Otherwise as `frequency_response`.
    """
    p0, p1 = _checked_range(p_start, p_end, "parameter")
    if not float(omega) > 0:
        raise ValueError(f"omega = {float(omega):g} rad/s must be > 0")
    first = make_system(jnp.asarray(p0))
    opts = (ds, ds_min, ds_max, max_points, max_newton, tol)
    return _run(
        lambda p: make_system(jnp.asarray(p)),
        _param_res,
        first,
        p0,
        p1,
        X0,
        float(omega),
        (make_system, float(omega)),
        opts,
        stability,
    )
