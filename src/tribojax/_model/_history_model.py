"""The history models: friction elements driven through a measured displacement history
(the time-domain route of `fit_history`, a separately named product beside the loop record
model: docs/fitting.md, "History fits are a separate product").

Each model is driven through the measured displacement u(t) from rest at the first sample
(`tribojax.drive`: exact increments for the rate-independent Jenkins and Mindlin elements, RK4
for LuGre and Bouc–Wen); its force plus a constant offset f0 (the load cell's zero and any mean
asymmetry) is compared with the measured force. The figure of merit is the normalised RMS
error NRMSE = rms(model − measured) / std(measured).

Band tension (a band brake's load knob, `HysteresisLoop.band_tension`): a model's slip forces
(`TENSION_SCALED`) are those at the fit's reference tension T_ref and scale on a record at
tension T by the tension law (`tension_factor`): by the capstan law the friction force is
proportional to the band's tension, here the set tension T plus a residual T_res that a slack
band keeps on the drum, with a wrap that may grow with the tension (rate γ, 1/N):
s(T) = (T_res + T·e^{γ(T − T_ref)}) / (T_res + T_ref). Records at one tension fix T_res = γ = 0
(s = T/T_ref); two tensions free T_res, three or more γ too (`law_spec`); the band brake has one
law per direction (its two band ends). The other parameters do not scale (the derivation and
assumptions: docs/data.md, "Band tension").
"""

from __future__ import annotations

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._checks import check_range
from .._dynamics._harmonic import drive
from .._export import cached_jit
from .._fit._measures import nrmse
from .._friction._band_brake import BandBrake
from .._friction._bouc_wen import BoucWen
from .._friction._lugre import LuGre
from .._friction._rate_independent import Jenkins, Mindlin
from .._io._hysteresis_loop import HysteresisLoop
from .._limits import TENSION_LAWS

HISTORY_MODELS = {
    "jenkins": (("mu_N", True), ("K_d", True), ("f0", False)),
    "mindlin": (("mu_N", True), ("K_d", True), ("f0", False)),
    "lugre": (("sigma0", True), ("F_c", True), ("F_s", True), ("v_s", True), ("f0", False)),
    "bouc_wen": (("K", True), ("F_y", True), ("n", True), ("f0", False)),
    "band_brake": (
        ("F_pos", True),
        ("F_neg", True),
        ("gap_pos", True),
        ("gap_neg", True),
        ("k_gap", True),
        ("A_pos", True),
        ("A_neg", True),
        ("beta_pos", True),
        ("beta_neg", True),
        ("f0", False),
    ),
}
TENSION_SCALED = ("mu_N", "F_c", "F_s", "F_y", "F_pos", "F_neg", "A_pos", "A_neg")
"""Slip-force parameters, scaled by the tension law (module docstring)."""
LAW_SIDES = {"band_brake": ("_pos", "_neg")}
"""A model whose two directions each have their own tension law (the band brake's two ends)."""


def law_spec(model: str, n_tensions: int, law: str = "auto") -> tuple:
    """(name, positive) of the tension-law parameters, after f0, of a fit of `model` to records
    at `n_tensions` distinct band tensions: T_res (N, > 0) for "residual", T_res and γ (1/N) for
    "growing", none for "proportional", one of each per direction for the band brake
    (`LAW_SIDES`); "auto" takes the fullest law the tensions determine (`TENSION_LAWS`).
    ValueError for a law the tensions do not determine, naming both."""
    if law == "auto":
        law = max(
            (k for k, v in TENSION_LAWS.items() if v <= max(n_tensions, 1)), key=TENSION_LAWS.get
        )
    if law not in TENSION_LAWS:
        raise ValueError(f"tension_law = {law!r} is not one of {['auto', *TENSION_LAWS]}")
    if n_tensions < TENSION_LAWS[law] and law != "proportional":
        raise ValueError(
            f"tension_law = {law!r} needs records at {TENSION_LAWS[law]} or more band tensions; "
            f"these are at {n_tensions}"
        )
    sides = LAW_SIDES.get(model, ("",))
    out = [(f"T_res{s}", True) for s in sides] if TENSION_LAWS[law] >= 2 else []
    return tuple(out + ([(f"gamma{s}", False) for s in sides] if TENSION_LAWS[law] >= 3 else []))


def tension_factor(law: dict, side: str, tension, reference):
    """s(T) of the module docstring: the factor on a slip force of direction `side` ("",
    "_pos", "_neg") at tension T (N), the slip forces being those at `reference` (N); `law`
    maps the law's parameter names to values (absent: T_res = γ = 0)."""
    t_res = law.get(f"T_res{side}", 0.0)
    grow = jnp.exp(law.get(f"gamma{side}", 0.0) * (tension - reference))
    return (t_res + tension * grow) / (t_res + reference)


def scaled_values(model: str, p, law: dict, tension, reference):
    """The element's parameters p (order of HISTORY_MODELS, without f0) at tension T (N)."""
    out = []
    for (name, _), v in zip(HISTORY_MODELS[model][:-1], p):
        if name in TENSION_SCALED:
            side = name[-4:] if model in LAW_SIDES else ""
            v = v * tension_factor(law, side, tension, reference)
        out.append(v)
    return jnp.stack(out)


MINDLIN_IWAN = 64  # Iwan elements of the Mindlin rate form in the history fits


def history_element(model: str, p):
    """The element of `model` for the physical parameter vector p (order of HISTORY_MODELS)."""
    if model == "jenkins":
        return Jenkins(p[0], 1.0, p[1])
    if model == "mindlin":
        return Mindlin(p[0], 1.0, p[1], n_iwan=MINDLIN_IWAN)
    if model == "lugre":  # σ1 = σ2 = 0: neither is resolved by these loops (σ2 drifts to 0)
        return LuGre(p[0], 0.0, 0.0, p[1], p[2], p[3], 1.0, 2.0)
    if model == "bouc_wen":
        return BoucWen(p[0], p[1], p[2], 0.5)
    return BandBrake(*(p[i] for i in range(9)))  # "band_brake" (callers check `model`)


class _Transform(eqx.Module):
    """θ → physical: exp for positive parameters, θ·scale for the signed ones (`scale`: one
    value for all, or one per parameter)."""

    positive: tuple = eqx.field(static=True)
    scale: float | tuple = eqx.field(static=True)

    def __call__(self, theta):
        mask = jnp.asarray(self.positive)
        return jnp.where(
            mask, jnp.exp(jnp.where(mask, theta, 0.0)), theta * jnp.asarray(self.scale)
        )


class _HistoryResiduals(eqx.Module):
    """(model + f0 − measured)/std(measured) over every record in args (a tuple of records
    (t, u, f, scale, tension T N)): the slip forces are those at `reference` (N) and scale to T
    by the tension law whose parameters (`law`, names) follow f0 in θ."""

    model: str = eqx.field(static=True)
    transform: _Transform
    initial: str = eqx.field(static=True, default="rest")
    law: tuple = eqx.field(static=True, default=())
    reference: float = eqx.field(static=True, default=1.0)
    held: tuple = eqx.field(static=True, default=())  # (index, value) of parameters not fitted
    # per record, (index, index) pairs: the campaign's own value of a parameter (`fit_history`'s
    # `per_campaign`, after the law's in θ) used in that parameter's place
    swaps: tuple = eqx.field(static=True, default=())

    def __call__(self, theta, args):
        p = self.transform(theta)
        if self.held:  # the fitted ones in order, the held ones at their places
            free = iter(range(p.size))
            n_all = p.size + len(self.held)
            at = dict(self.held)
            p = jnp.stack([at[i] if i in at else p[next(free)] for i in range(n_all)])
        n = len(HISTORY_MODELS[self.model])
        law, out = dict(zip(self.law, p[n:])), []
        for k, (t, u, f, scale, tension) in enumerate(args):
            q = p
            for i, j in self.swaps[k] if self.swaps else ():
                q = q.at[i].set(p[j])
            f0 = q[n - 1]
            values = scaled_values(self.model, q[: n - 1], law, tension, self.reference)
            el = history_element(self.model, values)
            if self.initial == "measured":  # the state that carries the first measured force
                force = drive(el, u, state0=el.state_for_force(f[0] - f0))
            elif self.model in ("jenkins", "mindlin", "band_brake"):
                force = drive(el, u)
            else:  # RK4, one step per sample interval (h·rate ≪ 1 at 1 kHz for these rigs)
                force = drive(el, u, t, substeps=1)
            out.append((force + f0 - f) / scale)
        return jnp.concatenate(out)


@cached_jit
def _residuals(fn, theta, records):
    # one compiled program per record shape (cached across processes), not op-by-op dispatch
    return fn(theta, records)


def _records(loops, decimate: int, band_tension=None, law=()):
    """((t, u, f, std f, T) of every `decimate`-th sample of each loop, T_ref): T_ref is
    `band_tension` (N), else the first loop's; without a tension law (`law`, its parameter
    names) T is the ratio to T_ref and T_ref 1. A loop without a tension among loops with one
    (or against a given reference), or one at 0 N against slip forces at a tension (or the other
    way round) without a law, is refused, naming it and the field."""
    for loop in loops:
        if not isinstance(loop, HysteresisLoop):
            raise ValueError(f"fit_history needs HysteresisLoop records, got {type(loop).__name__}")
    ref = band_tension if band_tension is not None else loops[0].band_tension
    with_tension = [lp.band_tension is not None for lp in loops]
    if (ref is not None or any(with_tension)) and not all(with_tension):
        lp = loops[with_tension.index(False)]
        raise ValueError(
            f"{lp.source}: field 'band_tension' is missing, while the model scales its slip "
            "forces with the band tension; name the file <f>Hz<T>lbtension<A>amplitude.json or "
            "earthquake_<name>_<T>lb.json, or give it (band_tension=..., N; --band-tension)"
        )
    slack = [lp for lp in loops if ref is not None and (lp.band_tension == 0) != (ref == 0)]
    if slack and not law:
        raise ValueError(
            f"{slack[0].source}: band_tension = {slack[0].band_tension:g} N with slip forces "
            f"at {ref:g} N and no tension law: proportional to the tension, they vanish at "
            "0 N (a slack band) and so leave out the drag that remains there; fit records at "
            "two or more tensions together (the law's residual tension), or 0 N on its own"
        )
    out = []
    for loop in loops:
        sl = slice(None, None, decimate)
        f = jnp.asarray(loop.f[sl])
        if law:
            tension = float(loop.band_tension)
        else:
            tension = 1.0 if not ref else loop.band_tension / ref
        out.append(
            (jnp.asarray(loop.t[sl]), jnp.asarray(loop.u[sl]), f, float(jnp.std(f)), tension)
        )
    return tuple(out), (float(ref) if law else 1.0)


def _nrmse(residuals, records) -> float:
    """rms(residual)/std(measured) over all records (residuals are divided by each std)."""
    scales = np.concatenate([np.full(len(rec[2]), rec[3]) for rec in records])
    f = np.concatenate([np.asarray(rec[2]) for rec in records])
    return nrmse(np.asarray(residuals) * scales, f)


HISTORY_UNITS = {
    "mu_N": "N",
    "K_d": "N/m",
    "f0": "N",
    "sigma0": "N/m",
    "F_c": "N",
    "F_s": "N",
    "v_s": "m/s",
    "K": "N/m",
    "F_y": "N",
    "n": "1",
    "F_pos": "N",
    "F_neg": "N",
    "gap_pos": "m",
    "gap_neg": "m",
    "k_gap": "N/m",
    "A_pos": "N",
    "A_neg": "N",
    "beta_pos": "1/m",
    "beta_neg": "1/m",
    **{f"T_res{s}": "N" for s in ("", "_pos", "_neg")},
    **{f"gamma{s}": "1/N" for s in ("", "_pos", "_neg")},
}
"""Units of the history models' parameters (`HISTORY_MODELS`, `law_spec`)."""


def campaign_spec(model, loops, campaigns, per_campaign, spec) -> tuple:
    """((name@label, positive) of each parameter fitted per campaign, after the first's; per
    record the (shared index, own index) pairs in the full parameter vector); ValueError
    naming what is wrong."""
    per_campaign = tuple(per_campaign)
    if not per_campaign:
        return (), ()
    allowed = dict(HISTORY_MODELS[model])
    unknown = [n for n in per_campaign if n not in allowed]
    if unknown or campaigns is None or len(campaigns) != len(loops):
        raise ValueError(
            f"per_campaign = {list(per_campaign)} needs parameters of {model!r} "
            f"({list(allowed)}) and campaigns, one label per record ({len(loops)})"
        )
    labels = list(dict.fromkeys(str(c) for c in campaigns))
    own = tuple((f"{n}@{lab}", allowed[n]) for lab in labels[1:] for n in per_campaign)
    where = {n: i for i, (n, _) in enumerate(spec + own)}
    swaps = tuple(
        tuple((where[n], where[f"{n}@{c}"]) for n in per_campaign) if str(c) != labels[0] else ()
        for c in campaigns
    )
    return own, swaps


INITIAL_STATES = ("rest", "measured")
"""How a history prediction starts: from rest, or in the state that carries the record's first
measured force (a device left loaded by an earlier test; `MEASURED_START` models only)."""
MEASURED_START = ("jenkins", "band_brake")


def history_force(
    model: str,
    values,
    loop: HysteresisLoop,
    decimate: int = 1,
    band_tension=None,
    initial: str = "rest",
    law=(),
):
    """(force N, NRMSE) of history model `model` at physical parameters `values` (the order of
    `HISTORY_MODELS[model]`, f0, then the tension law's parameters named by `law`) on every
    `decimate`-th sample of `loop`, driven from rest (`initial="rest"`) or from the state whose
    force (+ f0) is the first measured force (`"measured"`: Jenkins and the band brake);
    `band_tension` (N): the tension the slip forces in `values` belong to (None: unscaled)."""
    if model not in HISTORY_MODELS:
        raise ValueError(f"model must be one of {sorted(HISTORY_MODELS)}, got {model!r}")
    if initial not in INITIAL_STATES or (initial == "measured" and model not in MEASURED_START):
        allowed = INITIAL_STATES if model in MEASURED_START else ("rest",)
        raise ValueError(
            f"initial = {initial!r} is not one of {list(allowed)} for the {model} model"
        )
    dec = int(check_range(decimate, "decimate", 1, None, lo_open=False))
    law = tuple(law)
    records, ref = _records([loop], dec, band_tension, law)
    spec = HISTORY_MODELS[model] + tuple((n, n.startswith("T_res")) for n in law)
    tr = _Transform(tuple(pos for _, pos in spec), 1.0)  # θ of signed ones in physical units
    theta = [np.log(v) if pos else v for v, (_, pos) in zip(values, spec)]
    fn = _HistoryResiduals(model, tr, initial, law, ref)
    r = np.asarray(_residuals(fn, jnp.asarray(theta), records))
    t, u, f, s, _ = records[0]
    return np.asarray(f) + r * s, _nrmse(r, records)
