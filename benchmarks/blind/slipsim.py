"""Reticle slip on a vacuum chuck (wang2022 Eq 27, consistent reading) and the
reading-side hidden effects. Written blind from the papers.

Friction ODE (state in nm internally; slip dx = x_stage - x_reticle):
    dx'' = a(t) - F_f / m
    z'   = v * (1 - sgn(v) * K z / g(v))^alpha,   v = dx'
    F_f  = K z + C z' + sigma2 v
with, for the hidden friction effects,
    load_coupling:    phi = 1 + kappa a(t)/9.81,  F_s -> F_s phi, K -> K phi
    stribeck:         g(v) = F_s [(1 - delta) + delta / (1 + (v/v_s)^2)]
    viscous_friction: sigma2 > 0.
All switched off (kappa = delta = sigma2 = 0) gives the plain model exactly.
"""
import numpy as np
from scipy.integrate import solve_ivp
from scipy.ndimage import gaussian_filter1d

G_LOAD = 9.81        # [m/s^2] in the load-coupling law N = N0 (1 + kappa a / g)
G_WEIGHT = 9.8       # [m/s^2] in wang2022 Eq 28
A_SUCTION = 909e-6   # [m^2] chuck suction area (wang2022 Sec 5.2)
M_RETICLE = 0.321    # [kg]

# wang2022 Table 3: vacuum [kPa] -> (F_s [N], K_tau [N/m], C_tau [N s/m])
TABLE3 = {0.6: (0.4868, 1.4878e7, 771.0516), 2: (0.7372, 2.1478e7, 708.8274),
          4: (1.0861, 3.0343e7, 712.2624), 7: (1.7201, 4.5509e7, 749.7264),
          10: (2.4402, 6.1890e7, 799.5422), 20: (5.7685, 1.3173e8, 994.1022)}


def normal_load(vac_kpa, mass):
    """Eq 28: N = A_v P_v + m g [N]."""
    return A_SUCTION * vac_kpa * 1e3 + mass * G_WEIGHT


def contact_params(vac_kpa, mass=M_RETICLE):
    """(F_s, K_tau, C_tau) at the load N = A_v P_v + m g: Table 3 itself for the
    0.321 kg reticle, else log-log interpolation of Table 3 against its load."""
    if abs(mass - M_RETICLE) < 1e-12:
        return TABLE3[vac_kpa]
    loads = np.array([normal_load(v, M_RETICLE) for v in TABLE3])
    vals = np.log(np.array(list(TABLE3.values())))
    ln = np.log(normal_load(vac_kpa, mass))
    return tuple(float(np.exp(np.interp(ln, np.log(loads), vals[:, k]))) for k in range(3))


def solve_slip(drive, t_out, m, Fs, K, C, alpha=1.0, kappa=0.0, delta=0.0,
               v_s=1.0, sigma2=0.0, rtol=1e-10, method="Radau"):
    """Integrate the friction ODE from rest, segment by segment (restarting at
    every acceleration kink from the exact end state). Radau, rtol 1e-10,
    atol 1e-7 nm / 1e-5 nm/s. Returns dict of slip [m], v [m/s], z [m] at t_out.
    v_s in m/s; sigma2 in N s/m."""
    vs_nm = v_s * 1e9

    def make_rhs(seg):
        def rhs(t, y):
            _, v, z = y
            a = drive.seg_accel(seg, t)
            phi = 1.0 + kappa * a / G_LOAD
            Kt = K * phi
            g = Fs * phi * ((1.0 - delta) + delta / (1.0 + (v / vs_nm) ** 2))
            r = 1.0 - np.sign(v) * Kt * z * 1e-9 / g
            if alpha != 1.0:
                r = max(r, 0.0) ** alpha
            zd = v * r
            F = Kt * z + C * zd + sigma2 * v          # [nN]
            return [v, 1e9 * a - F / m, zd]

        def jac(t, y):
            _, v, z = y
            a = drive.seg_accel(seg, t)
            phi = 1.0 + kappa * a / G_LOAD
            Kt = K * phi
            q = 1.0 + (v / vs_nm) ** 2
            g = Fs * phi * ((1.0 - delta) + delta / q)
            dg = -Fs * phi * delta * 2.0 * v / (vs_nm**2 * q * q)
            sv = np.sign(v)
            r = 1.0 - sv * Kt * z * 1e-9 / g
            dzd_dv = r + v * sv * Kt * z * 1e-9 * dg / g**2
            dzd_dz = -abs(v) * Kt * 1e-9 / g
            return np.array([[0.0, 1.0, 0.0],
                             [0.0, -(C * dzd_dv + sigma2) / m, -(Kt + C * dzd_dz) / m],
                             [0.0, dzd_dv, dzd_dz]])
        return rhs, (jac if alpha == 1.0 else None)

    y = np.zeros(3)
    out = np.empty((len(t_out), 3))
    atol = np.array([1e-7, 1e-5, 1e-7])
    segs = drive.segs
    for k, seg in enumerate(segs):
        t0, t1 = seg[0], seg[1]
        last = k == len(segs) - 1
        sel = (t_out >= t0) & ((t_out < t1) | (last & (t_out <= t1)))
        rhs, jac = make_rhs(seg)
        sol = solve_ivp(rhs, (t0, t1), y, method=method, rtol=rtol, atol=atol,
                        jac=jac, dense_output=True)
        if not sol.success:
            raise RuntimeError(sol.message)
        if sel.any():
            out[sel] = sol.sol(t_out[sel]).T
        y = sol.y[:, -1]
    return {"slip": out[:, 0] * 1e-9, "v": out[:, 1] * 1e-9, "z": out[:, 2] * 1e-9}


def drift(t, kind, p):
    """Additive slow reading drift [m].
    poly:    c1 t + c2 t^2 + c3 t^3                (c_k in m/s^k)
    thermal: D (1 - exp(-(t - t0)/tau)) for t > t0  (D in m, tau, t0 in s)
    walk:    Gaussian-smoothed random walk, step sd sigma_rw sqrt(dt)
             (sigma_rw in m/sqrt(s)), smoothing sd smooth_s [s], own seed; 0 at t = 0."""
    if kind == "poly":
        return p["c1_m_s"] * t + p["c2_m_s2"] * t**2 + p["c3_m_s3"] * t**3
    if kind == "thermal":
        s = np.clip(t - p["t0_s"], 0.0, None)
        return p["D_m"] * (1.0 - np.exp(-s / p["tau_s"]))
    dt = t[1] - t[0]
    rng = np.random.default_rng(p["seed"])
    w = np.cumsum(rng.standard_normal(len(t))) * p["sigma_rw_m_sqrt_s"] * np.sqrt(dt)
    w = gaussian_filter1d(w, p["smooth_s"] / dt, mode="nearest")
    return w - w[0]


def position_error(x_stage, eps, eps2=0.0):
    """Reading error eps x_stage + eps2 x_stage^2 [m] (eps dimensionless, eps2 in 1/m)."""
    return eps * x_stage + eps2 * x_stage**2


def vibration(drive, t_out, f_n, zeta, gain, mode):
    """Structural mode between stage and sensor, added to the reading [m]:
        q'' + 2 zeta w q' + w^2 q = -gain * d(t),  w = 2 pi f_n
    mode "accel": d = a, gain dimensionless, reading += q;
    mode "accel_dynamic": d = a, reading += q + gain a / w^2 (quasi-static part removed);
    mode "jerk": d = da/dt, gain in s, reading += q.
    Integrated with DOP853 (rtol 1e-11) from rest, restarting at every kink."""
    w = 2 * np.pi * f_n
    use_jerk = mode == "jerk"
    y = np.zeros(2)
    out = np.empty(len(t_out))
    for k, seg in enumerate(drive.segs):
        t0, t1 = seg[0], seg[1]
        last = k == len(drive.segs) - 1
        sel = (t_out >= t0) & ((t_out < t1) | (last & (t_out <= t1)))
        fd = drive.seg_jerk if use_jerk else drive.seg_accel

        def rhs(t, s, seg=seg, fd=fd):
            return [s[1], -2 * zeta * w * s[1] - w * w * s[0] - gain * 1e9 * fd(seg, t)]
        sol = solve_ivp(rhs, (t0, t1), y, method="DOP853", rtol=1e-11, atol=1e-9,
                        dense_output=True)
        out[sel] = sol.sol(t_out[sel])[0]
        y = sol.y[:, -1]
    q = out * 1e-9
    if mode == "accel_dynamic":
        q = q + gain * drive.accel(t_out) / w**2
    return q
