"""The one residual of every record-model fit (`padded_residual`, its arguments `Padded`), and
the model evaluated at given values (`evaluate`)."""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import mode_jit
from .._export import cached_jit
from ._base import K_MAX, AbstractBaseline


class Padded(eqx.Module):
    """Everything the residual needs, the strengths padded to `K_MAX` (array leaves only)."""

    baseline: AbstractBaseline
    base: jax.Array  # knob vector at s = 0 (n_knobs,)
    gain: jax.Array  # ∂knobs/∂s (n_knobs, K_MAX)
    basis: jax.Array  # additive columns (n, K_MAX), output units per unit s
    mask: jax.Array  # 1 for the active strengths (K_MAX,)
    y: jax.Array  # observed samples (n,)
    w: jax.Array  # weight of each sample's residual (n,): 1, or 0 for a held-out sample
    scale: jax.Array  # residual unit (output units)
    bad: jax.Array  # residual of every row where the model is not finite
    d: jax.Array  # variable scaling: x = d·u (p + K_MAX,)
    knobs: bool = eqx.field(static=True, default=True)  # an active effect moves a knob


def _residual_and_jac(x, a: Padded):
    """Residual [(model − y)/scale, held strengths] and its Jacobian ∂/∂x at x = [θ_b, s].

    Inactive strengths are masked out of the model and held at 0 by a row each (residual s,
    Jacobian 1), so the normal matrix stays regular. A model that is not finite gives `a.bad` in
    every row and a zero Jacobian: the trial is rejected as a rise of the cost.
    """
    p = x.size - K_MAX
    hold = 1.0 - a.mask
    s = x[p:] * a.mask
    if a.knobs:
        value, jb, jk = a.baseline.value_and_jacobians(x[:p], a.base + a.gain @ s)
        js = jk @ a.gain + a.basis
    else:  # no knob moves: the null physics alone, differentiated over θ only
        value, jb = a.baseline.value_and_jacobian(x[:p], a.base)
        js = a.basis
    r = a.w * (value + a.basis @ s - a.y) / a.scale
    J = jnp.concatenate([jb, js * a.mask[None, :]], axis=1) / a.scale * a.w[:, None]
    ok = jnp.all(jnp.isfinite(r)) & jnp.all(jnp.isfinite(J))
    r = jnp.concatenate([jnp.where(ok, r, a.bad), hold * x[p:]])
    J_hold = jnp.concatenate([jnp.zeros((K_MAX, p)), jnp.diag(hold)], axis=1)
    return r, jnp.concatenate([jnp.where(ok, J, 0.0), J_hold], axis=0)


_traced_once = mode_jit(_residual_and_jac)


def _model_pass(x, a: Padded):
    """`_residual_and_jac` traced once per solve: optimistix traces the residual for its shapes
    (under `jax.make_jaxpr`, no mesh context) and again for the linearisation (inside the solve's
    jit, an empty abstract mesh); the same context in both makes the second a trace-cache hit
    (docs/performance.md)."""
    with jax.sharding.use_abstract_mesh(jax.sharding.get_abstract_mesh()):
        return _traced_once(x, a)


@eqx.filter_custom_jvp
def padded_residual(u, a):
    """The residual function of every record-model fit, in scaled variables u = x/d (module
    level: the solve compiles once per record shape)."""
    return _model_pass(a.d * u, a)[0]


@padded_residual.def_jvp
def _residual_jvp(primals, tangents):
    # the Jacobian from one forward pass over (θ_b, knobs), not over the K_MAX padded strengths:
    # optimistix's linearisation and the statistics then cost one model pass per point
    u, a = primals
    r, J = _model_pass(a.d * u, a)
    tu = tangents[0]
    return r, (jnp.zeros_like(r) if tu is None else (J * a.d[None, :]) @ tu)


def pack_designs(baseline, designs):
    """Knob base vector, knob gain (n_knobs, K_MAX) and additive basis (n, K_MAX) of the active
    designs (their k strengths first, zero columns after)."""
    names = baseline.knob_names
    n = baseline.data().y.shape[0]
    k = sum(d.k for d in designs)
    if k > K_MAX:
        raise ValueError(f"{k} effect strengths in one model: more than K_MAX = {K_MAX}")
    gain = np.zeros((len(names), K_MAX))
    base = np.asarray(baseline.knob_null(), dtype=float).copy()
    basis = np.zeros((n, K_MAX))
    j = 0
    for d in designs:
        if d.knob_gain is not None:
            gain[:, j : j + d.k] = d.knob_gain
        for key, value in d.knob_set.items():
            base[names.index(key)] = value
        if d.basis is not None:
            basis[:, j : j + d.k] = d.basis
        j += d.k
    return base, gain, basis


def padded_args(baseline, base, gain, basis, k, y, scale, weights=None) -> Padded:
    """The `Padded` arguments of `padded_residual` (float64 leaves; `bad` inf and the scaling
    `d` 1 until `fit_model` sets them). Where no knob leaves its null (no gain, no knob set), the
    residual evaluates the null physics alone (`value_and_jacobian`: the fit of the model alone,
    or with additive effects only); the baseline is specialised to the knobs that may move
    (`for_knobs`). `weights`: per-sample residual weights (default 1)."""
    d = np.ones(len(baseline.param_names) + K_MAX)
    w = np.ones(np.shape(y)) if weights is None else weights
    arrays = (base, gain, basis, np.arange(K_MAX) < k, y, w, scale, np.inf, d)
    moved = np.any(gain != 0, axis=1) | (base != np.asarray(baseline.knob_null(), dtype=float))
    return Padded(
        _for_knobs(baseline, moved),
        *(jnp.asarray(v, dtype=jnp.float64) for v in arrays),
        knobs=bool(np.any(moved)),
    )


def _for_knobs(baseline, moved):
    return baseline.for_knobs(tuple(bool(m) for m in moved))


def _names(baseline, designs):
    out = list(baseline.param_names)
    for d in designs:
        out += [f"s:{name}" for name in d.strength_names]
    return tuple(out)


def _padded(baseline, designs, theta0, y, scale, weights=None):
    """The padded start x0 = [θ_b, s, 0…] (default `baseline.start()`, zero strengths) and the
    arguments of `padded_residual` for this model and data."""
    base, gain, basis = pack_designs(baseline, designs)
    p, k = len(baseline.param_names), sum(d.k for d in designs)
    x0 = np.zeros(p + K_MAX)
    x0[: p + k] = np.asarray(baseline.start() if theta0 is None else theta0, dtype=float)
    return x0, padded_args(baseline, base, gain, basis, k, y, scale, weights=weights)


@cached_jit
def _predict(baseline, theta, null):
    return baseline.predict_null(theta, null)


@cached_jit
def _predict_knobs(baseline, theta, knobs):
    return baseline.predict(theta, knobs)


def evaluate(baseline, theta, designs=(), strengths=()) -> np.ndarray:
    """The model's samples (output units) at θ (compiled): with every effect at its null, or with
    the effects' `designs` at their strengths s (one value per design strength, in the designs'
    units per unit s): knobs = null ⊕ knob_set + gain·s, plus the additive columns basis·s."""
    theta = jnp.asarray(theta, dtype=jnp.float64)
    base, gain, basis = pack_designs(baseline, tuple(designs))
    s = np.zeros(K_MAX)
    s[: len(strengths)] = np.asarray(strengths, dtype=float)
    knobs = base + gain @ s
    null = np.asarray(baseline.knob_null(), dtype=float)
    baseline = _for_knobs(baseline, knobs != null)
    if np.array_equal(knobs, null):
        out = _predict(baseline, theta, jnp.asarray(knobs))
    else:
        out = _predict_knobs(baseline, theta, jnp.asarray(knobs))
    return np.asarray(out) + basis @ s
