"""Independent NumPy/SciPy reference for the fractal contact model of wang2022 (Sections 2–3).

This file is written the way a user without tribojax would write the model: per-asperity
quantities are built from their physical definitions, the regime integrals over the asperity
size distribution are done numerically with `scipy.integrate.quad`, and the largest truncated
area a'_l comes from `scipy.optimize.brentq`. It deliberately shares no code, no closed-form
regime integral and no power-law bookkeeping with `tribojax` (and imports no JAX), so that
agreement between the two is evidence that both are right.

Model (equation numbers of papers/wang2022_reticle_slip.txt):

* Asperity geometry. Truncated area a' = π r'^2; deformation δ(a') (Eq 2); radius of curvature
  R(a') (Eq 3); critical deformation δ_ec(a') = (πKH/(2E))^2 R (Eq 4), K = 0.454 + 0.41ν.
* Critical areas a'_ec, a'_epc, a'_pc: the a' at which δ/δ_ec = 1, 6, 110 (the definitions of
  Eqs 5–7), found here with brentq instead of the printed closed forms.
* Normal load per asperity:
    elastic  P = (4/3) E R^(1/2) δ^(3/2)                         (Hertz, Eq 8)
    ep1      P = 3·0.34 · P_c(a') · ρ^1.425                        (Kogut–Etsion form of Eq 9)
    ep2      P = 3·0.47 · P_c(a') · ρ^1.263                        (Kogut–Etsion form of Eq 11)
    plastic  P = H a'                                               (Eq 13)
  with the critical load P_c(a') = (2/3) π K H R δ_ec (the Hertz load at δ = δ_ec) and the
  paper's deformation ratio ρ = δ(a')/δ(a'_ec) = (a'/a'_ec)^((3-D)/2), which is < 1 inside the
  elastic–plastic regimes (the paper's reading, kept on purpose). Kogut–Etsion's fits are
  P/P_c = 1.03 ρ^1.425 and 1.40 ρ^1.263; the paper prints their thirds rounded, 0.34 and 0.47,
  and this reference keeps the printed values, so the load jumps by 3·0.34 = 1.02 at a'_ec.
  Written this way the a' exponent of Eq 9 is (D-1) + 1.425(3-D)/2 = 1.1375 + 0.2875 D (the
  printed exponent is garbled), and Eq 11 is reproduced exactly.
* Real contact area (area="real"): elastic a = π R δ (Hertz, = a'/2); ep1 a = 0.93 A_c ρ^1.136 and
  ep2 a = 0.94 A_c ρ^1.146 with A_c = π R δ_ec at a'_ec (Kogut–Etsion; printed as 0.465 and 0.47
  times a'_ec in Eqs 10 and 12); plastic a = a'. With area="truncated", a = a' in every regime.
* Eq 14 friction T = 8 a σ_s/(π(6-3ν)) + 8(2ν-1) P/(π(6-3ν)); Eq 18 stiffness
  k = 8 G' r (1-ψ)^(1/3) with r = (a/π)^(1/2); Eq 20 dissipation and Eq 22 stored energy per
  cycle as printed, with ψ = T/(μ_t P) = tangential_load/(μ_t · load) (docs/reproduction.md).
* Size distribution n(a') = (D-1)/(2a'_l) (a'_l/a')^((D+1)/2), 0 < a' <= a'_l (Eq 15).
  Regime integrals (Eqs 16, 19, 21, 23 and the load balance) are ∫ f(a') n(a') da' over the
  regime's range clipped to (0, a'_l], computed with quad in s = ln a' (the areas are
  ~1e-21…1e-5 m^2, so the substitution a' = e^s keeps the integrand O(1)-smooth).
* F_s (Eq 16), K_τ (Eq 19), W_d (Eq 21), W_s (Eq 23), C_τ = W_d/W_s (m K_τ)^(1/2) (Eq 24),
  z_max = F_s/K_τ (Eq 26).

Limitation: the plastic integral runs down to a' = 0, done as quad over s in (-inf, ln a'_pc].
Asperities smaller than the smallest double (a' < ~5e-324 m^2) are dropped, a relative error
of about (5e-324/a'_pc)^((3-D)/2): below 1e-12 for D <= 2.9 and a'_pc > 1e-25 m^2. The
reference refuses D > 2.9 for that integral rather than return a silently truncated value.
"""

import math
from dataclasses import dataclass

from scipy import integrate, optimize

ELASTIC, EP1, EP2, PLASTIC = 0, 1, 2, 3
REGIMES = ("elastic", "ep1", "ep2", "plastic")

# Kogut–Etsion coefficients as printed in wang2022 (0.34 = 1.03/3 and 0.47 = 1.40/3, rounded):
# P/P_c = 3·coef·ρ^exponent; real area A/A_c = coef·ρ^exponent.
KE_LOAD = {EP1: (3 * 0.34, 1.425), EP2: (3 * 0.47, 1.263)}
KE_AREA = {EP1: (0.93, 1.136), EP2: (0.94, 1.146)}

# quad: relative accuracy only (the integrals range from ~1e-30 to ~1e+3 in SI units).
QUAD_EPSREL = 1e-12
QUAD_LIMIT = 200
# brentq on log areas: |error in ln a'| <= 1e-13, i.e. ~1e-13 relative in a'.
BRENTQ_XTOL = 1e-13
MAX_D_LOWER_LIMIT_ZERO = 2.9


@dataclass(frozen=True)
class Inputs:
    """Surface, material pair and tangential conditions, all SI (m, Pa, N, kg)."""

    D: float
    G: float
    M: float
    gamma: float
    E_star: float
    G_star: float
    H: float
    nu: float
    sigma_s: float
    mu_t: float = 0.14
    tangential_load: float = 0.0
    mass: float = 1.0
    area: str = "truncated"

    def __post_init__(self):
        if not 2.0 < self.D < 3.0:
            raise ValueError(f"D = {self.D} outside (2, 3)")
        if self.area not in ("truncated", "real"):
            raise ValueError(f"area must be 'truncated' or 'real', got {self.area!r}")

    @property
    def K(self):
        """Hardness coefficient K = 0.454 + 0.41 ν (text below Eq 4)."""
        return 0.454 + 0.41 * self.nu


# ---------------------------------------------------------------------------------------------
# One asperity
# ---------------------------------------------------------------------------------------------


def truncated_radius(a):
    """r' with a' = π r'^2."""
    return math.sqrt(a / math.pi)


def deformation(a, p: Inputs):
    """δ(a'), m (Eq 2): 2 G^(D-2) (ln γ / M)^(1/2) (2 r')^(3-D)."""
    return (
        2.0
        * p.G ** (p.D - 2.0)
        * math.sqrt(math.log(p.gamma) / p.M)
        * (2.0 * truncated_radius(a)) ** (3.0 - p.D)
    )


def curvature_radius(a, p: Inputs):
    """R(a'), m (Eq 3)."""
    return (
        a ** ((p.D - 1.0) / 2.0)
        * math.sqrt(p.M)
        / (
            2.0 ** (5.0 - p.D)
            * math.pi ** ((p.D - 1.0) / 2.0)
            * p.G ** (p.D - 2.0)
            * math.sqrt(math.log(p.gamma))
        )
    )


def critical_deformation(a, p: Inputs):
    """δ_ec(a') = (π K H / (2E))^2 R(a'), m (Eq 4, first form)."""
    return (math.pi * p.K * p.H / (2.0 * p.E_star)) ** 2 * curvature_radius(a, p)


def _root_in_log(f, x0, step=5.0, max_expand=400):
    """brentq root of a monotone f(x) (x = ln a'), bracketing outward from x0."""
    lo, hi = x0 - step, x0 + step
    flo, fhi = f(lo), f(hi)
    for _ in range(max_expand):
        if flo * fhi <= 0.0:
            return optimize.brentq(f, lo, hi, xtol=BRENTQ_XTOL, maxiter=500)
        if abs(flo) < abs(fhi):
            lo -= step
            flo = f(lo)
        else:
            hi += step
            fhi = f(hi)
        step *= 1.5
    raise RuntimeError("could not bracket the root")


def critical_areas(p: Inputs):
    """(a'_ec, a'_epc, a'_pc), m^2: the a' where δ/δ_ec = 1, 6, 110 (definitions of Eqs 5–7)."""

    def area_at(ratio):
        def f(x):
            a = math.exp(x)
            return math.log(deformation(a, p) / critical_deformation(a, p)) - math.log(ratio)

        return math.exp(_root_in_log(f, -40.0))

    return area_at(1.0), area_at(6.0), area_at(110.0)


def regime_of(a, crit):
    """Regime index of an asperity of truncated area a' given (a'_ec, a'_epc, a'_pc)."""
    a_ec, a_epc, a_pc = crit
    if a > a_ec:
        return ELASTIC
    if a > a_epc:
        return EP1
    if a > a_pc:
        return EP2
    return PLASTIC


def hertz_load(a, p: Inputs):
    """Elastic load P_e = (4/3) E R^(1/2) δ^(3/2), N (Hertz; Eq 8)."""
    return 4.0 / 3.0 * p.E_star * curvature_radius(a, p) ** 0.5 * deformation(a, p) ** 1.5


def critical_load(a, p: Inputs):
    """P_c(a') = (2/3) π K H R δ_ec, N: the Hertz load at the onset of yield, δ = δ_ec."""
    return 2.0 / 3.0 * math.pi * p.K * p.H * curvature_radius(a, p) * critical_deformation(a, p)


def deformation_ratio(a, p: Inputs, a_ec):
    """The paper's ratio ρ = δ(a')/δ(a'_ec) = (a'/a'_ec)^((3-D)/2) used in Eqs 9–12."""
    return deformation(a, p) / deformation(a_ec, p)


def asperity_load(a, regime, p: Inputs, a_ec):
    """Normal load of one asperity of truncated area a' (m^2) under the law of `regime`, N."""
    if regime == ELASTIC:
        return hertz_load(a, p)
    if regime in (EP1, EP2):
        coef, expo = KE_LOAD[regime]
        return coef * critical_load(a, p) * deformation_ratio(a, p, a_ec) ** expo
    if regime == PLASTIC:
        return p.H * a
    raise ValueError(regime)


def real_area(a, regime, p: Inputs, a_ec):
    """Real contact area of one asperity, m^2 (Hertz π R δ; Eqs 10, 12; Eq 13)."""
    if regime == ELASTIC:
        return math.pi * curvature_radius(a, p) * deformation(a, p)
    if regime in (EP1, EP2):
        coef, expo = KE_AREA[regime]
        area_c = math.pi * curvature_radius(a_ec, p) * critical_deformation(a_ec, p)
        return coef * area_c * deformation_ratio(a, p, a_ec) ** expo
    if regime == PLASTIC:
        return a
    raise ValueError(regime)


def contact_area(a, regime, p: Inputs, a_ec):
    """Area used in Eqs 14, 18, 20, 22: a' (area='truncated') or the real area."""
    return a if p.area == "truncated" else real_area(a, regime, p, a_ec)


def contact_radius(a, regime, p: Inputs, a_ec):
    """r = (a/π)^(1/2) of the contact area used in Eqs 18 and 20."""
    return math.sqrt(contact_area(a, regime, p, a_ec) / math.pi)


def psi_of(p: Inputs, load):
    """ψ = T/(μ_t P) with T the applied tangential load and P the normal load."""
    psi = p.tangential_load / (p.mu_t * load)
    if not 0.0 <= psi < 1.0:
        raise ValueError(f"psi = {psi} must be in [0, 1) (Mindlin's law needs T < mu_t P)")
    return psi


def asperity_friction(a, regime, p: Inputs, a_ec):
    """Maximum static friction of one asperity, N (Eq 14)."""
    den = math.pi * (6.0 - 3.0 * p.nu)
    return (
        8.0 * contact_area(a, regime, p, a_ec) * p.sigma_s / den
        + 8.0 * (2.0 * p.nu - 1.0) * asperity_load(a, regime, p, a_ec) / den
    )


def asperity_stiffness(a, regime, p: Inputs, a_ec, psi):
    """Tangential stiffness of one asperity k = 8 G' r (1-ψ)^(1/3), N/m (Eq 18)."""
    return 8.0 * p.G_star * contact_radius(a, regime, p, a_ec) * (1.0 - psi) ** (1.0 / 3.0)


def asperity_dissipation(a, regime, p: Inputs, a_ec, psi):
    """Energy dissipated by one asperity per tangential cycle, J (Eq 20 as printed)."""
    P = asperity_load(a, regime, p, a_ec)
    r = contact_radius(a, regime, p, a_ec)
    bracket = (
        1.0 - (1.0 - psi) ** (5.0 / 3.0) - 5.0 * psi / 6.0 * (1.0 + (1.0 - psi) ** (2.0 / 3.0))
    )
    return 9.0 * p.mu_t**2 * P**2 / (10.0 * p.G_star * r) * bracket


def asperity_storage(a, regime, p: Inputs, a_ec, psi):
    """Maximum energy stored by one asperity per tangential cycle, J (Eq 22 as printed)."""
    P = asperity_load(a, regime, p, a_ec)
    area = contact_area(a, regime, p, a_ec)
    bracket = 0.6 - (1.0 - psi) ** (2.0 / 3.0) + 0.4 * (1.0 - psi) ** (5.0 / 3.0)
    return 3.0 * math.sqrt(math.pi) * p.mu_t**2 * P**2 / (16.0 * p.G_star * area**0.5) * bracket


def mindlin_loop_energies(psi):
    """Mindlin's tangential loop done numerically, independently of Eqs 18, 20 and 22.

    Loading branch (Eq 17 with the contact radius): t(δ) = μP[1 - (1 - δ/δ_s)^(3/2)] with
    δ_s = 3μP/(16 G' r); amplitude t* = ψμP. Unloading/reloading follow Masing's rule
    t = ±t* ∓ 2 t((δ* ∓ δ)/2). Returns (w_d, w_s, k) with μP = 1 and δ_s = 1:
        w_d = area of the closed loop     (Eq 20 predicts 0.9·(16/3)·bracket_20)
        w_s = ∫_0^δ* t dδ                  (Eq 22 predicts (3/16)(16/3)·bracket_22)
        k   = dt/dδ at δ*                  (Eq 18 predicts 8G'r(1-ψ)^(1/3) = (3/2)(1-ψ)^(1/3))
    """

    def t_load(d):
        return 1.0 - (1.0 - d) ** 1.5

    d_star = optimize.brentq(lambda d: t_load(d) - psi, 0.0, 1.0, xtol=1e-15, rtol=1e-15)
    t_star = t_load(d_star)

    def gap(d):  # reloading (upper) branch minus unloading (lower) branch
        reload = -t_star + 2.0 * t_load((d_star + d) / 2.0)
        unload = t_star - 2.0 * t_load((d_star - d) / 2.0)
        return reload - unload

    w_d = integrate.quad(gap, -d_star, d_star, epsabs=0.0, epsrel=1e-13)[0]
    w_s = integrate.quad(t_load, 0.0, d_star, epsabs=0.0, epsrel=1e-13)[0]
    h = 1e-30  # complex-step derivative: no subtractive cancellation, exact to rounding
    k = t_load(complex(d_star, h)).imag / h
    return w_d, w_s, k


# ---------------------------------------------------------------------------------------------
# Size distribution and regime integrals
# ---------------------------------------------------------------------------------------------


def size_density(a, a_l, D):
    """n(a') = (D-1)/(2 a'_l) (a'_l/a')^((D+1)/2), per m^2 (Eq 15)."""
    return (D - 1.0) / (2.0 * a_l) * (a_l / a) ** ((D + 1.0) / 2.0)


def _density_per_log_area(s, a_l, D):
    """a' n(a') at a' = e^s (number of asperities per unit ln a'), overflow-safe form of Eq 15."""
    h = (D - 1.0) / 2.0
    return h * math.exp(h * (math.log(a_l) - s))


def distribution_integral(func, lo, hi, a_l, D):
    """∫ func(a') n(a') da' over [lo, hi] ∩ (0, a'_l], by quad in s = ln a'.

    lo=None means 0 (the plastic regime), hi=None means a'_l.
    """
    top = a_l if hi is None else min(hi, a_l)
    if lo is not None and lo >= top:
        return 0.0
    if lo is None and D > MAX_D_LOWER_LIMIT_ZERO:
        raise ValueError(
            f"D = {D} > {MAX_D_LOWER_LIMIT_ZERO}: the integral down to a' = 0 would lose the "
            "asperities below the smallest double (see the module docstring)"
        )

    def integrand(s):
        a = math.exp(s)
        if a == 0.0:  # below the smallest double; the integrand vanishes like a'^((3-D)/2)
            return 0.0
        return func(a) * _density_per_log_area(s, a_l, D)

    s_lo = -math.inf if lo is None else math.log(lo)
    value, _ = integrate.quad(
        integrand, s_lo, math.log(top), epsabs=0.0, epsrel=QUAD_EPSREL, limit=QUAD_LIMIT
    )
    return value


def regime_limits(regime, crit):
    """(lower, upper) truncated-area limits of a regime; None = 0 below, a'_l above."""
    a_ec, a_epc, a_pc = crit
    return {ELASTIC: (a_ec, None), EP1: (a_epc, a_ec), EP2: (a_pc, a_epc), PLASTIC: (None, a_pc)}[
        regime
    ]


def _per_asperity(kind, regime, p: Inputs, a_ec, psi):
    """The per-asperity function f(a') of `kind` under the law of `regime`."""
    if kind == "load":
        return lambda a: asperity_load(a, regime, p, a_ec)
    if kind == "area":
        return lambda a: contact_area(a, regime, p, a_ec)
    if kind == "sqrt_area":
        return lambda a: math.sqrt(contact_area(a, regime, p, a_ec))
    if kind == "p2_over_r":
        return lambda a: asperity_load(a, regime, p, a_ec) ** 2 / contact_radius(a, regime, p, a_ec)
    if kind == "friction":
        return lambda a: asperity_friction(a, regime, p, a_ec)
    if kind == "stiffness":
        return lambda a: asperity_stiffness(a, regime, p, a_ec, psi)
    if kind == "dissipation":
        return lambda a: asperity_dissipation(a, regime, p, a_ec, psi)
    if kind == "storage":
        return lambda a: asperity_storage(a, regime, p, a_ec, psi)
    raise ValueError(f"unknown kind {kind!r}")


def reference_regime_integral(
    kind, regime, p: Inputs, a_l, *, lo="regime", hi="regime", crit=None, psi=0.0
):
    """∫ f(a') n(a') da' for one regime, by quad.

    kind: "load" (P), "area" (a), "sqrt_area" (a^(1/2)), "p2_over_r" (P^2/r, r = (a/π)^(1/2)),
          "friction" (Eq 14), "stiffness" (Eq 18), "dissipation" (Eq 20), "storage" (Eq 22).
    regime: ELASTIC, EP1, EP2, PLASTIC (or its name) — selects the per-asperity law.
    lo, hi: limits in m^2; "regime" uses the regime's own range, None means 0 (lo) or a'_l (hi).
            The range is always clipped to (0, a'_l].
    """
    if isinstance(regime, str):
        regime = REGIMES.index(regime)
    if crit is None:
        crit = critical_areas(p)
    r_lo, r_hi = regime_limits(regime, crit)
    lo = r_lo if lo == "regime" else lo
    hi = r_hi if hi == "regime" else hi
    func = _per_asperity(kind, regime, p, crit[0], psi)
    return distribution_integral(func, lo, hi, a_l, p.D)


def total_load(a_l, p: Inputs, crit):
    """Load carried by the surface when the largest truncated area is a'_l, N (Eqs 8–15)."""
    return sum(reference_regime_integral("load", r, p, a_l, crit=crit) for r in range(4))


def largest_area(p: Inputs, load, crit=None):
    """a'_l such that the asperity loads sum to `load` (N), by brentq on ln a'_l."""
    if crit is None:
        crit = critical_areas(p)
    log_f = math.log(load)

    def f(x):
        return math.log(total_load(math.exp(x), p, crit)) - log_f

    # start from the area of one fully plastic asperity carrying the whole load
    return math.exp(_root_in_log(f, math.log(load / p.H), step=2.0))


def reference_contact_inputs(p: Inputs, load):
    """The contact parameters at normal load `load` (N) for `Inputs` p; see `reference_contact`."""
    crit = critical_areas(p)
    a_ec, a_epc, a_pc = crit
    psi = psi_of(p, load)
    a_l = largest_area(p, load, crit)

    def integral(kind, regime):
        return reference_regime_integral(kind, regime, p, a_l, crit=crit, psi=psi)

    load_parts = [integral("load", r) for r in range(4)]
    F_s = sum(integral("friction", r) for r in (ELASTIC, EP1))  # Eq 16
    K_tau = sum(integral("stiffness", r) for r in (ELASTIC, EP1, EP2))  # Eq 19
    W_d = sum(integral("dissipation", r) for r in (EP1, EP2))  # Eq 21
    W_s = sum(integral("storage", r) for r in (ELASTIC, EP1, EP2))  # Eq 23
    all_plastic = a_l <= a_pc
    if all_plastic:
        # every asperity is fully plastic: K_τ = W_s = 0 and Eqs 24, 26 are 0/0. Report zeros
        # (no tangential stiffness, damping or pre-slip), the convention tribojax uses too.
        C_tau = z_max = 0.0
    else:
        C_tau = W_d / W_s * math.sqrt(p.mass * K_tau)  # Eq 24
        z_max = F_s / K_tau  # Eq 26
    total = sum(load_parts)
    return {
        "load": load,
        "F_s": F_s,
        "K_tau": K_tau,
        "C_tau": C_tau,
        "z_max": z_max,
        "a_l": a_l,
        "a_ec": a_ec,
        "a_epc": a_epc,
        "a_pc": a_pc,
        "load_share": [x / total for x in load_parts],
        "load_total": total,
        "psi": psi,
        "W_d": W_d,
        "W_s": W_s,
        "all_plastic": all_plastic,
    }


def reference_contact(
    D,
    G,
    M,
    gamma,
    E_star,
    G_star,
    H,
    nu,
    sigma_s,
    mu_t,
    tangential_load,
    mass,
    load,
    area="truncated",
):
    """Contact parameters of wang2022 Sections 2–3 at one normal load, by quad and brentq.

    Returns a dict with F_s (N), K_tau (N/m), C_tau (N s/m), z_max (m), a_l (m^2), a_ec, a_epc,
    a_pc (m^2), load_share (4 floats: elastic, ep1, ep2, plastic), load_total (N), psi, W_d and
    W_s (J), all_plastic (a'_l <= a'_pc; then C_tau and z_max are reported as 0).
    """
    p = Inputs(
        D=float(D),
        G=float(G),
        M=float(M),
        gamma=float(gamma),
        E_star=float(E_star),
        G_star=float(G_star),
        H=float(H),
        nu=float(nu),
        sigma_s=float(sigma_s),
        mu_t=float(mu_t),
        tangential_load=float(tangential_load),
        mass=float(mass),
        area=area,
    )
    return reference_contact_inputs(p, float(load))


__all__ = [
    "ELASTIC",
    "EP1",
    "EP2",
    "PLASTIC",
    "REGIMES",
    "Inputs",
    "critical_areas",
    "reference_contact",
    "reference_regime_integral",
]
