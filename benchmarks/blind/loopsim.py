"""Tangential contact force under a prescribed displacement u(t) (wu2015):
Jenkins element (spring K_d in series with a Coulomb slider of limit mu N,
wu2015 Eq 1) by exact return mapping, plus the loop-side hidden effects.
Written blind from the papers.

Per element i (n = 1 for the plain Jenkins element):
    trial f_i = k_i * dz(u - s_i),   dz(e) = sgn(e) max(|e| - g/2, 0)  (backlash, g = 0 off)
    if |trial| > L_i:  s_i = u - sgn(trial) (g/2 + L_i/k_i),  f_i = sgn(trial) L_i
    f = sum_i f_i + c du/dt + f_off
microslip: n = 200 elements, k_i = K_d/n, slip displacements d_i = L_i/k_i spread
    uniformly: d_i = A0 (1 + w (2 (i - 1/2)/n - 1)), A0 = mu N / K_d, w = 1
    (w = 0 collapses the bank to one Jenkins element). Same mu N and K_d.
normal_load_variation: phi(u) = 1 + beta u/A + beta2 (u/A)^2;
    L_i -> L_i phi, k_i -> k_i phi^gamma (gamma = 0 or 0.76).
The state is updated at every output sample and at every exact reversal of
u(t) (found by root finding), so the update is exact between evaluation points
(u is monotone there and slip never stops before a reversal).
"""
import numpy as np


def contact_force(drive, t_out, muN, Kd, n_el=1, spread=1.0, gap=0.0, beta=0.0,
                  beta2=0.0, gamma=0.0, A_ref=1.0, c=0.0, f_off=0.0):
    """Noise-free tangential force [N] at t_out [s]. muN [N], Kd [N/m], gap [m],
    c [N s/m], f_off [N], A_ref [m] (the u scale of the load variation)."""
    if gap > 0.0 and n_el > 1:
        raise ValueError("backlash is implemented for the single Jenkins element")
    t_rev = drive.reversals(t_out[-1])
    t_all = np.concatenate([t_out, t_rev])
    order = np.argsort(t_all, kind="stable")
    is_out = order < len(t_out)
    u_all = drive.u(t_all[order])
    i = np.arange(1, n_el + 1)
    k0 = np.full(n_el, Kd / n_el)
    L0 = (muN / n_el) * (1.0 + spread * (2.0 * (i - 0.5) / n_el - 1.0))
    s = np.zeros(n_el)
    half = 0.5 * gap
    f_all = np.empty(len(u_all))
    for j, u in enumerate(u_all):
        phi = 1.0 + beta * u / A_ref + beta2 * (u / A_ref) ** 2
        k = k0 * phi**gamma
        L = L0 * phi
        e = u - s
        tr = k * (np.sign(e) * np.maximum(np.abs(e) - half, 0.0))
        over = np.abs(tr) > L
        if over.any():
            sg = np.sign(tr[over])
            s[over] = u - sg * (half + L[over] / k[over])
            tr[over] = sg * L[over]
        f_all[j] = tr.sum()
    f = f_all[is_out]
    return f + c * drive.udot(t_out) + f_off


def loop_energy(u, f):
    """Energy dissipated [J] = closed-contour integral of f du (trapezoid rule)."""
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(u)))


def jenkins_energy_formula(A, muN, Kd):
    """Steady sinusoidal Jenkins loop area [J]: W = 4 mu N (A - mu N / K_d), A > mu N/K_d."""
    return 4.0 * muN * (A - muN / Kd)
