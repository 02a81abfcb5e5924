"""The two-body reticle slip model (wang2022 Eq 27, consistent reading) solved with diffrax.

The stage motion is prescribed by its acceleration a(t); the reticle (mass m) is driven only by
the friction force F_f of a friction element. With the slip Δx = x_stage − x_reticle and the
relative velocity v = dΔx/dt:

    dΔx/dt = v,   dv/dt = a(t) − F_f(z, v)/m,   dz/dt = element.state_rate(z, v)

plus I = ∫Δx dt, carried as a fourth state so that window averages of the slip are exact
differences of I at the window ends (no averaging of a sampled curve).
"""

from __future__ import annotations

import diffrax as dfx
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jax.flatten_util import ravel_pytree
from jaxtyping import Array

from .._checks import as_f64, cacheable_call, check_range, check_result, fail_if, mode_jit
from .._friction._element import AbstractFrictionElement
from .._presets import WANG2022_RETICLE_MASS_KG
from ._adjoint import ForwardJacobianAdjoint
from ._profiles import AbstractProfile, TrapezoidProfile
from ._rodas4 import Rodas4

DEFAULT_T_END = 2.3  # s, wang2022's cycle ends at rest at 2.3 s (Table 7)
DEFAULT_ATOL = 1e-15  # m, Rodas4's default absolute tolerance of slip and deflection
KVAERNO5_ATOL = 1e-16  # m, the same for solver="kvaerno5" (equal accuracy)


class SlipSolution(eqx.Module):
    """A slip simulation sampled at `ts` (SI units).

    ts (s), slip Δx (m), z (bristle deflection, m; the element state), friction F_f (N), velocity
    v = dΔx/dt (m/s), slip_integral ∫₀ᵗ Δx dt (m s), result (diffrax RESULTS code), stats.
    """

    ts: Array
    slip: Array
    z: Array
    friction: Array
    velocity: Array
    slip_integral: Array
    result: dfx.RESULTS
    stats: dict

    @property
    def ok(self) -> Array:
        return self.result == dfx.RESULTS.successful

    @property
    def message(self) -> str:
        """The solver's message ("" on success); concrete solutions only."""
        return "" if bool(self.ok) else str(dfx.RESULTS[self.result])


def _vector_field(t, y, args):
    # y = [Δx, v, element state (flattened), ∫Δx dt]: one flat array, so that per-component
    # tolerances reach the Newton iteration too.
    element, profile, mass, unravel = args
    dx, v, z = y[0], y[1], unravel(y[2:-1])
    force = element.force(z, v)
    zdot, _ = ravel_pytree(element.state_rate(z, v))
    acc = profile.acceleration(t) - force / mass
    return jnp.concatenate([jnp.stack([v, acc]), zdot, dx[None]])


def _kvaerno5_chord() -> dfx.AbstractSolver:
    """Kvaerno5 (L-stable ESDIRK, order 5) with a chord iteration whose Jacobian (4×4, forward
    mode) is re-evaluated at every stage (optimistix's `Chord`, not diffrax's `VeryChord`)."""
    return dfx.Kvaerno5(root_finder=dfx.with_stepsize_controller_tols(optx.Chord)())


_SOLVERS = {"rodas4": Rodas4, "kvaerno5": _kvaerno5_chord}


def _diffeqsolve(
    element, profile, mass, ts, unravel, t_end, rtol, atol, max_steps, throw, adjoint, dt0, solver
):
    """ys (len(ts), n_state), result, stats of one solve."""
    z0, _ = ravel_pytree(element.initial_state())
    y0 = jnp.concatenate([jnp.zeros(2, z0.dtype), jnp.zeros_like(z0), jnp.zeros(1, z0.dtype)])
    # per-component absolute tolerances (simulate_slip's docstring, "Numerics")
    atols = jnp.concatenate(
        [jnp.array([atol, atol * 1e3]), jnp.full(z0.shape, atol), jnp.array([atol * 0.1])]
    )
    # factormax 3 (default 10): a step grown 10x in a quasi-static phase is often rejected
    controller = dfx.PIDController(
        rtol=rtol, atol=atols, pcoeff=0.3, icoeff=0.4, factormax=3.0, jump_ts=profile.kinks()
    )
    sol = dfx.diffeqsolve(
        dfx.ODETerm(_vector_field),
        solver,
        0.0,
        t_end,
        dt0,
        y0,
        args=(element, profile, mass, unravel),
        saveat=dfx.SaveAt(ts=ts),
        stepsize_controller=controller,
        max_steps=max_steps,
        throw=False,  # a failure is checked by `_solve` (`check_result`), not by diffrax
        adjoint=adjoint,
    )
    return sol.ys, (sol.result, jax.tree.map(jnp.asarray, sol.stats))


@mode_jit
def _solve(element, profile, mass, ts, t_end, rtol, atol, max_steps, throw, adjoint, dt0, solver):
    _, unravel = ravel_pytree(element.initial_state())
    cfg = (t_end, rtol, atol, max_steps, throw)

    def solve(el, pr, m, t, adj):
        return _diffeqsolve(el, pr, m, t, unravel, *cfg, adj, dt0, solver)

    if isinstance(adjoint, ForwardJacobianAdjoint):

        def rate(el, pr, m, t, ys):
            return jax.vmap(lambda ti, y: _vector_field(ti, y, (el, pr, m, unravel)))(t, ys)

        ys, (result, stats) = adjoint.solve(solve, rate, (element, profile, mass, ts))
    else:
        ys, (result, stats) = solve(element, profile, mass, ts, adjoint)
    dx, v, integral = ys[:, 0], ys[:, 1], ys[:, -1]
    z = jax.vmap(unravel)(ys[:, 2:-1])
    friction = jax.vmap(element.force)(z, v)
    if throw:  # the solver's own message; NaN under `failures_as_nan`
        dx = check_result(dx, result, dfx.RESULTS, "simulate_slip")
    return SlipSolution(ts, dx, z, friction, v, integral, result, stats)


def _positive(x, name, unit=""):
    """A solver setting: a positive Python float (never traced)."""
    x = float(x)
    if not x > 0:
        raise ValueError(f"{name} = {x:g} {unit} is outside the allowed range (0, inf)")
    return x


def simulate_slip(
    element: AbstractFrictionElement,
    profile: AbstractProfile | None = None,
    mass=WANG2022_RETICLE_MASS_KG,
    *,
    ts=None,
    t_end=DEFAULT_T_END,
    rtol=1e-6,
    atol=None,
    max_steps=20_000,
    dt0=1e-5,
    throw=True,
    adjoint: dfx.AbstractAdjoint | ForwardJacobianAdjoint | None = None,
    solver: str | dfx.AbstractSolver | None = "rodas4",
) -> SlipSolution:
    """Slip of a body carried by friction on a stage with prescribed acceleration (wang2022 Eq 27).

    Solves Δx'' = a(t) − F_f/m, with F_f and the bristle law from `element` (LuGre, Eq 25, or
    PreSlipLuGre, Eq 27), from rest (Δx = v = z = 0) to `t_end`. Eq 27 as printed carries a
    spurious factor t and two masses; this is the consistent reading of docs/reproduction.md
    (stage prescribed, reticle driven by friction alone, Δx = x_stage − x_reticle).

    Numerics. The problem is stiff (√(K_τ/m) ≈ 7e3–2e4 rad/s, C_τ/K_τ ≈ 50 µs, horizon 2.3 s) and
    tiny (slips of nm). Default solver: `Rodas4` with a PID controller (p 0.3, i 0.4, step growth
    capped at 3x), per-component absolute tolerances (`atol` in m for Δx and z, atol·1e3 for v in
    m/s, atol·0.1 for ∫Δx dt in m s), and steps stopped at the profile's kinks (`jump_ts`). The
    elements' smooth sign (`velocity_scale`, ε = 1e-12 m/s) makes the right-hand side C¹ at v = 0.
    The velocity tolerance, not `rtol`, sets the accuracy of the phase averages (docs/slip.md,
    "Solver accuracy and cost", also for the step counts and cost of both solvers and for ε).

    Derivatives (`adjoint`). With Rodas4 the solve is differentiated by `ForwardJacobianAdjoint`:
    forward mode w.r.t. the float leaves of `element`, `profile`, `mass` and `ts`, transposed for
    `jax.grad`/`jacrev`, so both directions give the same numbers (reverse mode through diffrax
    would be wrong: see `Rodas4`). Other solvers use the diffrax adjoint given (`jax.jacfwd` then
    needs `adjoint=diffrax.ForwardMode()`). Batches: `jax.vmap` over loads steps all members
    together (the union of their steps).

    Args:
        element: a friction element (its parameters may be traced; batch with jax.vmap).
        profile: stage acceleration; default `TrapezoidProfile()` (wang2022's cycle).
        mass: mass of the driven body, kg (> 0); 0.321 kg is wang2022's reticle.
        ts: save times (s, increasing, within [0, t_end]); default 2301 points over [0, t_end].
        t_end: end time, s (> 0).
        rtol, atol: relative tolerance; absolute tolerance of the slip and deflection, m.
        max_steps: step budget; raise it if the result says it was reached.
        throw: raise on solver failure (else inspect `result` / `message`).
        adjoint: how to differentiate the solve (see Derivatives): `ForwardJacobianAdjoint(...)`
            or a diffrax adjoint; None (default) is `ForwardJacobianAdjoint()` with Rodas4 and
            `diffrax.RecursiveCheckpointAdjoint()` otherwise. With Rodas4 a diffrax adjoint only
            picks the undifferentiated solve (`ForwardJacobianAdjoint(adjoint)`).
        solver: "rodas4" (default), "kvaerno5" (Kvaerno5 with a chord iteration) or a diffrax
            solver instance. `atol` defaults to 1e-15 m for Rodas4, 1e-16 m otherwise.
    Returns:
        SlipSolution.
    """
    profile = TrapezoidProfile() if profile is None else profile
    mass = check_range(mass, "mass", 0.0, unit="kg")
    solver = "rodas4" if solver is None else solver
    solver = _SOLVERS[solver]() if isinstance(solver, str) and solver in _SOLVERS else solver
    if not isinstance(solver, dfx.AbstractSolver):
        raise ValueError(
            f"solver = {solver!r}: expected 'rodas4', 'kvaerno5' or a diffrax solver instance"
        )
    if atol is None:
        atol = DEFAULT_ATOL if isinstance(solver, Rodas4) else KVAERNO5_ATOL
    if adjoint is None:
        adjoint = dfx.RecursiveCheckpointAdjoint()
    if isinstance(solver, Rodas4) and isinstance(adjoint, dfx.AbstractAdjoint):
        adjoint = ForwardJacobianAdjoint(adjoint)  # never diffrax's reverse mode through Rodas4
    if not isinstance(adjoint, (dfx.AbstractAdjoint, ForwardJacobianAdjoint)):
        raise ValueError(
            f"adjoint = {adjoint!r}: expected a diffrax adjoint or ForwardJacobianAdjoint()"
        )
    t_end, rtol, atol = (
        _positive(t_end, "t_end", "s"),
        _positive(rtol, "rtol"),
        _positive(atol, "atol", "m"),
    )
    if rtol >= 1.0:
        raise ValueError(f"rtol = {rtol:g} is outside the allowed range (0, 1)")
    ts = jnp.linspace(0.0, t_end, 2301) if ts is None else as_f64(ts, "ts")
    ts = fail_if(ts, jnp.any(jnp.diff(ts) < 0), "ts must be non-decreasing")
    ts = fail_if(ts, jnp.any((ts < 0) | (ts > t_end)), "ts must lie within [0, t_end]")
    args = (element, profile, mass, ts, t_end, rtol, atol, int(max_steps))

    # called eagerly: a program without host callbacks (cached), `throw=False` inside; a failure
    # runs the raising program, whose exception (the check's or diffrax's) the user then meets
    def failed(sol):
        finite = all(np.all(np.isfinite(np.asarray(x))) for x in (sol.slip, sol.velocity))
        return not finite or (throw and not bool(sol.ok))

    return cacheable_call(
        lambda a: _solve(*a, False, adjoint, dt0, solver),
        args,
        failed=failed,
        raising=lambda a: _solve(*a, throw, adjoint, dt0, solver),
    )


def slip_phase_averages(
    element: AbstractFrictionElement,
    profile: TrapezoidProfile | None = None,
    mass=WANG2022_RETICLE_MASS_KG,
    *,
    t_end=DEFAULT_T_END,
    throw=True,
    **kw,
) -> Array:
    """wang2022's four phase slips [T4, T5, T6, T7] (m), Tables 4–7 (docs/slip.md, "Phase values").

    The differences of consecutive mean slips ⟨Δx⟩ over `profile.windows()` (exact, from ∫Δx dt
    at the window ends), from Δx(0) to Δx(t_end). Other keywords go to `simulate_slip`, whose
    "Derivatives" apply here too.
    """
    profile = TrapezoidProfile() if profile is None else profile
    w = profile.windows()
    ts = jnp.concatenate([jnp.zeros(1), w.ravel(), jnp.full(1, t_end)])
    sol = simulate_slip(element, profile, mass, ts=ts, t_end=t_end, throw=throw, **kw)
    integral = sol.slip_integral[1:7].reshape(3, 2)
    means = (integral[:, 1] - integral[:, 0]) / (w[:, 1] - w[:, 0])
    return jnp.stack(
        [means[0] - sol.slip[0], means[1] - means[0], means[2] - means[1], sol.slip[7] - means[2]]
    )
