"""Experiment (issue 3): a Rodas4 Rosenbrock solver for diffrax vs the default Kvaerno5+Chord
in `tribojax.simulate_slip`.

Rodas4 (Hairer & Wanner, Solving ODEs II, §IV.7; the RODAS code's coefficients): L-stable,
stiffly accurate, order 4(3), 6 stages, dense output of order 3. Each step: one 4×4 Jacobian
(`jax.jacfwd`), one ∂f/∂t (`jax.jvp`, exact here: the drive is linear between `jump_ts`, and
diffrax starts steps just after a jump and ends them just before one), one LU, six solves:

    (I/(γh) − J) K_i = f(t₀ + α_i h, y₀ + Σ_{j<i} a_ij K_j) + Σ_{j<i} (c_ij/h) K_j + γ_i h ∂f/∂t,
    y₁ = y₀ + Σ m_i K_i, error Σ e_i K_i.

Findings (2-core CPU): see the report in the issue; in short Rodas4 is ~2.5x faster per cycle at
better accuracy, but reverse-mode derivatives (`jax.jacrev` with RecursiveCheckpointAdjoint or
DirectAdjoint) through it disagree with forward mode / finite differences (3e-3 of the largest
entry, tens of % on small ones; test_slip.py's jacrev test fails) on the
slip problem (fine on smooth test problems), so it is not the default.

For Table 3's 0.6, 4 and 20 kPa rows and alpha 1 and 1.26: worst relative error of the four phase
averages against SciPy Radau (rtol 1e-11, exact sign; tests/test_slip_scipy.py), warm time per
cycle (median), accepted/rejected steps; then the six loads vmapped.
Run: python benchmarks/experiments/rosenbrock_slip.py [--quick] [--check | --grad | --step-ad]
[variants...]
"""

import sys
from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

import tribojax as tj


class _Tableau(eqx.Module):
    gamma: float = eqx.field(static=True)
    a: tuple = eqx.field(static=True)  # rows of the strictly lower a_ij
    c: tuple = eqx.field(static=True)  # rows of the strictly lower c_ij
    alpha: tuple = eqx.field(static=True)
    gammas: tuple = eqx.field(static=True)  # γ_i = Σ_j γ_ij (time-derivative weights)
    m: tuple = eqx.field(static=True)
    e: tuple = eqx.field(static=True)
    dense: tuple | None = eqx.field(static=True)  # two rows of dense-output weights (RODAS)
    order: int = eqx.field(static=True)
    error_order: int = eqx.field(static=True)


# Rodas4: Hairer & Wanner (1996), Solving ODEs II, 2nd ed., §IV.7 Table 7.? and their RODAS
# code (ro4coe, METH=1). L-stable, stiffly accurate, order 4 with an embedded order 3.
_A5 = (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950)
RODAS4_TABLEAU = _Tableau(
    gamma=0.25,
    a=(
        (),
        (1.544,),
        (0.9466785280815826, 0.2557011698983284),
        (3.314825187068521, 2.896124015972201, 0.9986419139977817),
        _A5,
        (*_A5, 1.0),
    ),
    c=(
        (),
        (-5.6688,),
        (-2.430093356833875, -0.2063599157091915),
        (-0.1073529058151375, -9.594562251023355, -20.47028614809616),
        (7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160),
        (
            8.083246795921522,
            -7.981132988064893,
            -31.52159432874371,
            16.31930543123136,
            -6.058818238834054,
        ),
    ),  # fmt: skip
    alpha=(0.0, 0.386, 0.21, 0.63, 1.0, 1.0),
    gammas=(0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0),
    m=(*_A5, 1.0, 1.0),
    e=(0.0, 0.0, 0.0, 0.0, 0.0, 1.0),
    dense=(
        (
            10.12623508344586,
            -7.487995877610167,
            -34.80091861555747,
            -7.992771707568823,
            1.025137723295662,
            0.0,
        ),
        (
            -0.6762803392801253,
            6.087714651680015,
            16.43084320892478,
            24.76722511418386,
            -6.594389125716872,
            0.0,
        ),
    ),  # fmt: skip
    order=4,
    error_order=4,
)


class RosenbrockInterpolation(dfx.AbstractLocalInterpolation):
    """RODAS dense output y(θ) = y₀ + θ(Δy + (1 − θ)(k₁ + θ k₂)), θ = (t − t₀)/h; linear if the
    tableau has no dense weights (k₁ = k₂ = 0)."""

    t0: Array
    t1: Array
    y0: Array
    y1: Array
    k1: Array
    k2: Array

    def _at(self, t):
        th = (t - self.t0) / (self.t1 - self.t0)
        return self.y0 + th * ((self.y1 - self.y0) + (1 - th) * (self.k1 + th * self.k2))

    def evaluate(self, t0, t1=None, left=True):
        del left
        if t1 is None:
            return self._at(t0)
        return self._at(t1) - self._at(t0)


class Rosenbrock(dfx.AbstractAdaptiveSolver):
    """A Rosenbrock (linearly implicit) solver; `Rodas4()` is the usual choice.

    One dense Jacobian (`jax.jacfwd`), one ∂f/∂t (`jax.jvp`) and one LU per step, no iterations:
    for small stiff systems much cheaper per step than an ESDIRK with a Newton/chord solve.
    ODEs only (a single `diffrax.ODETerm`-like term).
    """

    tableau: _Tableau = RODAS4_TABLEAU
    term_structure: ClassVar = dfx.AbstractTerm
    interpolation_cls: ClassVar[Callable[..., RosenbrockInterpolation]] = RosenbrockInterpolation

    def order(self, terms):
        return self.tableau.order

    def error_order(self, terms):
        return self.tableau.error_order

    def init(self, terms, t0, t1, y0, args):
        return None

    def func(self, terms, t0, y0, args):
        return terms.vf(t0, y0, args)

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        del solver_state, made_jump
        tab = self.tableau
        y0 = jnp.asarray(y0)
        h = t1 - t0

        def f_ty(t, y):
            return terms.vf(t, y, args)

        jac = jax.jacfwd(lambda y: f_ty(t0, y))(y0)
        f0, ft = jax.jvp(lambda t: f_ty(t, y0), (t0,), (jnp.ones_like(t0),))
        n = y0.shape[0]
        lu = jax.scipy.linalg.lu_factor(jnp.eye(n, dtype=y0.dtype) / (tab.gamma * h) - jac)
        ks = []
        for i in range(len(tab.alpha)):
            if i == 0:
                fi = f0
            else:
                yi = y0 + sum(a * k for a, k in zip(tab.a[i], ks) if a != 0.0)
                fi = f_ty(t0 + tab.alpha[i] * h, yi)
            rhs = fi + sum((c / h) * k for c, k in zip(tab.c[i], ks) if c != 0.0)
            if tab.gammas[i] != 0.0:
                rhs = rhs + (tab.gammas[i] * h) * ft
            ks.append(jax.scipy.linalg.lu_solve(lu, rhs))
        y1 = y0 + sum(m * k for m, k in zip(tab.m, ks) if m != 0.0)
        err = sum(e * k for e, k in zip(tab.e, ks) if e != 0.0)
        if tab.dense is None:
            k1 = k2 = jnp.zeros_like(y0)
        else:
            k1, k2 = (sum(d * k for d, k in zip(row, ks) if d != 0.0) for row in tab.dense)
        dense_info = dict(y0=y0, y1=y1, k1=k1, k2=k2)
        return y1, err, dense_info, None, dfx.RESULTS.successful


def Rodas4() -> Rosenbrock:
    """Rodas4 (Hairer & Wanner): L-stable, stiffly accurate, order 4(3), 6 stages, dense output
    of order 3."""
    return Rosenbrock(RODAS4_TABLEAU)


sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from test_slip_scipy import reference  # noqa: E402
from timing import median_time  # noqa: E402

T3 = tj.wang2022_table(3)
CACHE = Path("/tmp/rosenbrock_slip_ref.npz")


def params(row):
    return tuple(float(T3[k][row]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))


def refs(cases):
    store = dict(np.load(CACHE)) if CACHE.exists() else {}
    for row, alpha in cases:
        key = f"{row}_{alpha}"
        if key not in store:
            store[key] = reference(*params(row), alpha)[1]
    np.savez(CACHE, **store)
    return store


VARIANTS = {
    "kvaerno5 rtol1e-6 atol1e-16 (default)": dict(),
    "rodas4 rtol1e-6 atol1e-16": dict(solver=Rodas4()),
    "rodas4 rtol1e-7 atol1e-16": dict(solver=Rodas4(), rtol=1e-7),
    "rodas4 rtol1e-6 atol3e-17": dict(solver=Rodas4(), atol=3e-17),
    "rodas4 rtol1e-5 atol1e-16": dict(solver=Rodas4(), rtol=1e-5),
    "rodas4 rtol1e-6 atol3e-16": dict(solver=Rodas4(), atol=3e-16),
    "rodas4 rtol1e-6 atol1e-15": dict(solver=Rodas4(), atol=1e-15),
    "rodas4 rtol1e-5 atol1e-15": dict(solver=Rodas4(), rtol=1e-5, atol=1e-15),
    "rodas4 rtol1e-4 atol1e-15": dict(solver=Rodas4(), rtol=1e-4, atol=1e-15),
}


def main(quick=False):
    n = 5 if quick else 11
    cases = [(0, 1.0), (2, 1.0), (5, 1.0), (0, 1.26), (2, 1.26), (5, 1.26)]
    ref = refs(cases)
    names = [a for a in sys.argv[1:] if not a.startswith("--")] or list(VARIANTS)
    for name in names:
        kw = VARIANTS[name]
        fwd = jax.jit(lambda e, kw=kw: tj.slip_phase_averages(e, **kw))
        sim = jax.jit(lambda e, kw=kw: tj.simulate_slip(e, ts=jnp.array([2.3]), **kw).stats)
        for row, alpha in cases:
            el = tj.PreSlipLuGre(*params(row), alpha)
            ph = np.asarray(fwd(el)) * 1e9
            err = float(np.max(np.abs(ph / ref[f"{row}_{alpha}"] - 1)))
            t = median_time(lambda: fwd(el), n)
            st = sim(el)
            print(f"{name:40s} row {row} a {alpha:4}: {t * 1e3:6.2f} ms  err {err:.1e}  "
                  f"acc {int(st['num_accepted_steps'])} rej {int(st['num_rejected_steps'])}",
                  flush=True)  # fmt: skip
        els = jax.vmap(lambda f, k, c: tj.PreSlipLuGre(f, k, c))(
            *(jnp.asarray(T3[k]) for k in ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m"))
        )
        six = jax.jit(jax.vmap(lambda e, kw=kw: tj.slip_phase_averages(e, **kw)))
        print(f"{name:40s} six loads vmapped: {median_time(lambda: six(els), 5) * 1e3:6.1f} ms",
              flush=True)  # fmt: skip


def check_order():
    """Fixed-step convergence on y' = A y + b t (stiff, affine in t): order 4, dense output."""
    from scipy.linalg import expm

    A, b, y0 = np.array([[-1.0, 2.0], [-3.0, -50.0]]), np.array([1.0, 0.5]), np.array([1.0, 0.5])
    Ai = np.linalg.inv(A)

    def exact(t):
        yp = lambda s: -Ai @ b * s - Ai @ Ai @ b  # noqa: E731
        return expm(A * t) @ (y0 - yp(0.0)) + yp(t)

    term = dfx.ODETerm(lambda t, y, a: jnp.asarray(A) @ y + jnp.asarray(b) * t)
    errs = []
    for n in (20, 40, 80, 160):
        sol = dfx.diffeqsolve(term, Rodas4(), 0.0, 1.0, 1.0 / n, jnp.asarray(y0),
                              saveat=dfx.SaveAt(ts=jnp.array([0.37, 1.0])))  # fmt: skip
        ys = np.asarray(sol.ys)
        errs.append((np.abs(ys[1] - exact(1.0)).max(), np.abs(ys[0] - exact(0.37)).max()))
        print(f"n {n:4d}: error at t=1 {errs[-1][0]:.2e}, dense at t=0.37 {errs[-1][1]:.2e}")
    e = np.array(errs)[:, 0]
    print("observed orders", np.log2(e[:-1] / e[1:]))


def check_gradients():
    """jacrev vs jacfwd vs central FD of the phase averages (tests/test_slip.py's case); with
    Rodas4 the reverse-mode Jacobian is off by up to 1.9 nm per unit log-parameter in T4/T5
    (3e-3 of the largest entry, up to 50 % of the small ones); forward mode matches FD to 1e-5."""
    import diffrax as dfx

    F_s, K, C = params(0)
    theta = jnp.array([F_s, K, C, 1.2])
    for name, kw in [("rodas4", dict(solver=Rodas4())), ("kvaerno5", {})]:

        def phases(th, adjoint=dfx.RecursiveCheckpointAdjoint(), kw=kw):
            el = tj.PreSlipLuGre(th[0], th[1], th[2], th[3])
            return tj.slip_phase_averages(el, rtol=1e-8, atol=1e-18, adjoint=adjoint, **kw)

        jr = np.asarray(jax.jit(jax.jacrev(phases))(theta))
        jf = np.asarray(jax.jit(jax.jacfwd(lambda t: phases(t, dfx.ForwardMode())))(theta))
        f = jax.jit(phases)
        fd = np.stack([(np.asarray(f(theta.at[i].mul(1 + 1e-4))) -
                        np.asarray(f(theta.at[i].mul(1 - 1e-4)))) / (2e-4 * float(theta[i]))
                       for i in range(4)], 1)  # fmt: skip
        scale = np.abs(fd * np.asarray(theta)).max()
        print(
            f"{name}: max |jacrev - FD| {np.abs((jr - fd) * np.asarray(theta)).max() / scale:.1e}"
            f", |jacfwd - FD| {np.abs((jf - fd) * np.asarray(theta)).max() / scale:.1e}"
            " (relative to the largest elasticity)"
        )


def check_step_ad():
    """One Rodas4 step of the slip field: jacfwd vs jacrev w.r.t. (F_s, K_τ, C_τ, α) and y₀.

    Measured: they agree to ~4e-16 (also near v = 0), while the whole solve's jacfwd and jacrev
    differ by ~2e-4 even with DirectAdjoint: the reverse-mode fault is at the diffeqsolve level.
    """
    from jax.flatten_util import ravel_pytree

    from tribojax._slip import _vector_field

    theta = jnp.array([*params(0), 1.2])
    profile = tj.TrapezoidProfile()

    def one_step(th, y0, t0=0.26, h=1e-5):
        el = tj.PreSlipLuGre(th[0], th[1], th[2], th[3])
        _, unravel = ravel_pytree(el.initial_state())
        args = (el, profile, 0.321, unravel)
        term = dfx.ODETerm(_vector_field)
        y1, err, _, _, _ = Rodas4().step(term, t0, t0 + h, y0, args, None, False)
        return jnp.concatenate([y1, err])

    for v in (1e-6, 1e-11, 0.0, -1e-13):
        y0 = jnp.array([3e-8, v, 2e-8, 1e-9])
        for arg in (0, 1):
            jf = np.asarray(jax.jacfwd(one_step, argnums=arg)(theta, y0))
            jr = np.asarray(jax.jacrev(one_step, argnums=arg)(theta, y0))
            print(f"v = {v:g}, argnum {arg}: |jacfwd - jacrev| / |jacfwd| = "
                  f"{np.abs(jf - jr).max() / np.abs(jf).max():.1e}")  # fmt: skip


if __name__ == "__main__":
    if "--step-ad" in sys.argv:
        check_step_ad()
        sys.exit()
    if "--grad" in sys.argv:
        check_gradients()
        sys.exit()
    if "--check" in sys.argv:
        check_order()
    else:
        main(quick="--quick" in sys.argv)
