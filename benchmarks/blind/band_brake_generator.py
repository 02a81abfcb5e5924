"""Independent data generator for a banded rotary friction damper (band brake).

Physical model (written from the physical description only)
------------------------------------------------------------
* The rig imposes the drum-surface arc displacement x(t) [m].
* A steel band is wrapped around the drum over theta = 270 deg.  While the
  band sticks to the drum, the band moves with the drum surface; the band
  position is b = x - s, where s is the accumulated slip of the band over the
  drum (state variable).
* Both band ends sit on a carrier (lever) that is pinned to the frame with free
  play: the carrier travels freely between two stops, total clearance g
  (+-g/2 about centre).  Inside the clearance only a weak centering spring k_c
  (2 % of k_s) holds it, so the force is k_c*c (a few hundred N at most).
* Once the carrier sits on a stop, further band motion stretches the
  band/stop linkage by e = b - c (c = carrier position, clipped to +-g/2).
  The linkage force is taken as a mildly STIFFENING elastic law
      F_el(e) = sign(e) * k_s*|e|*(1 + a*|e|),
  (the band wraps tighter and more band length is engaged as it is loaded, so
  the tangent stiffness grows linearly with stretch).  The total transmitted
  force is F = k_c*c + F_el(e).
* Sliding: the friction the band can carry is set by the capstan law
  T_tight = T_slack*exp(mu*theta).  The pre-tension spring is set to
  T0 = 30 lbf (133.4 N) and acts through a lever with mechanical advantage M;
  the band ends are attached on the lever at arms a1 (end that is tight for
  +x rotation) and a2 = r*a1 on the same side of the pivot, so lever balance
  gives  M*T0*(a1+a2) = T1*a1 + T2*a2.
    +x rotation: end 1 tight, T1 = E*T2 (E = exp(mu*theta)):
        F+ = M*T0*(1+r)*(E-1)/(E+r)
    -x rotation: end 2 tight, T2 = E*T1:
        F- = M*T0*(1+r)*(E-1)/(1+E*r)
  Because the tight end sits on the short arm in +x rotation, the drum's
  friction needs less lever moment to hold it: the brake is self-energizing in
  +x (larger slip force) and the anchored end is the slack end in -x.
  r and M are chosen to give F+ = 13.0 kN and F- = 9.5 kN.
* Rate-independent elastic-plastic stick/slip: if the trial force (with s
  unchanged) exceeds the slip force of that direction, the band slips so that
  the force equals the slip force exactly (s is updated).  When the drum
  reverses the linkage unloads elastically, the carrier crosses the clearance
  (only k_c acts) and then loads against the opposite stop.
* Sign: f > 0 when the drum moves in +x and slides.
* Starts at rest: carrier centred, no stretch, no slip (s = 0, x(0) = 0 for
  the sine record; for the history record s is set so that b(0) = 0).
* Output force = model force + Gaussian noise (sd 60 N, seeded) where asked.
"""
import json
import os
import sys

import numpy as np

# ---------------- parameters ----------------
THETA = np.deg2rad(270.0)
MU = 0.30
T0 = 133.4                      # N (30 lbf pre-tension setting)
E = float(np.exp(MU * THETA))   # capstan ratio
F_PLUS = 13000.0                # N, target slip force in +x
F_MINUS = 9500.0                # N, target slip force magnitude in -x
R_ARM = (F_PLUS / F_MINUS * E - 1.0) / (E - F_PLUS / F_MINUS)   # a2/a1
M_LEVER = F_PLUS / (T0 * (1 + R_ARM) * (E - 1) / (E + R_ARM))
G = 4.0e-3                      # m, total clearance
K_S = 6.0e6                     # N/m, initial linkage stiffness
A_STIFF = 300.0                 # 1/m, stiffening coefficient
K_C = 0.02 * K_S                # N/m, centering spring
NOISE_SD = 60.0


def slip_forces():
    fp = M_LEVER * T0 * (1 + R_ARM) * (E - 1) / (E + R_ARM)
    fm = M_LEVER * T0 * (1 + R_ARM) * (E - 1) / (1 + E * R_ARM)
    return fp, fm


def f_el(e):
    return np.sign(e) * K_S * abs(e) * (1.0 + A_STIFF * abs(e))


def f_el_inv(y):
    """stretch magnitude giving elastic force magnitude y >= 0"""
    return (-1.0 + np.sqrt(1.0 + 4.0 * A_STIFF * y / K_S)) / (2.0 * A_STIFF)


def simulate(x):
    fp, fm = slip_forces()
    h = G / 2.0
    s = x[0]            # start at rest: band position b = 0, carrier centred
    f = np.empty_like(x)
    sliding = np.zeros(len(x), dtype=bool)
    for i, xi in enumerate(x):
        b = xi - s
        c = min(max(b, -h), h)
        e = b - c
        F = K_C * c + f_el(e)
        if F > fp:
            e = f_el_inv(fp - K_C * h)
            s = xi - (h + e)
            F = fp
            sliding[i] = True
        elif F < -fm:
            e = -f_el_inv(fm - K_C * h)
            s = xi - (-h + e)
            F = -fm
            sliding[i] = True
        f[i] = F
    return f, sliding


def write_csv(path, t, x, f):
    with open(path, "w") as fh:
        fh.write("time_s,displacement_m,force_N\n")
        for a, b, c in zip(t, x, f):
            fh.write(f"{float(a)!r},{float(b)!r},{float(c)!r}\n")


def main(outdir):
    os.makedirs(outdir, exist_ok=True)
    fp, fm = slip_forces()
    summary = {}

    t = np.linspace(0.0, 3.0, 751)
    x = 8e-3 * np.sin(2 * np.pi * 1.0 * t)
    f, _ = simulate(x)
    fn = f + np.random.default_rng(0).normal(0.0, NOISE_SD, size=f.shape)
    write_csv(os.path.join(outdir, "sine_1Hz.csv"), t, x, fn)
    summary["sine_1Hz"] = (float(fn.max()), float(fn.min()), float(f.max()), float(f.min()))

    t = np.linspace(0.0, 6.0, 1201)
    x = 6e-3 * np.sin(2 * np.pi * 0.5 * t + 0.3) + 2.5e-3 * np.sin(2 * np.pi * 2.1 * t + 1.1)
    f, _ = simulate(x)
    write_csv(os.path.join(outdir, "history.csv"), t, x, f)
    summary["history"] = (float(f.max()), float(f.min()), float(f.max()), float(f.min()))

    truth = {
        "clearance_g_m": G,
        "linkage_stiffness_k_s_N_per_m": K_S,
        "stiffening_coefficient_a_per_m": A_STIFF,
        "centering_spring_k_c_N_per_m": K_C,
        "mu": MU,
        "theta_rad": float(THETA),
        "theta_deg": 270.0,
        "capstan_ratio_exp_mu_theta": E,
        "pretension_T0_N": T0,
        "lever_arm_ratio_a2_over_a1": R_ARM,
        "lever_mechanical_advantage_M": M_LEVER,
        "slip_force_positive_N": fp,
        "slip_force_negative_N": -fm,
        "stretch_at_slip_positive_m": float(f_el_inv(fp - K_C * G / 2)),
        "stretch_at_slip_negative_m": float(f_el_inv(fm - K_C * G / 2)),
        "noise_sd_N": NOISE_SD,
        "noise_seed_sine_1Hz": 0,
        "noise_sd_history_N": 0.0,
        "force_law": (
            "band position b = x - s (s = slip); carrier c = clip(b, -g/2, g/2); "
            "stretch e = b - c; F = k_c*c + sign(e)*k_s*|e|*(1 + a*|e|); "
            "rate-independent stick/slip: F clamped at +F_plus / -F_minus by "
            "updating s (band slides over drum). Slip forces from capstan law "
            "with a two-arm lever: F+ = M*T0*(1+r)*(E-1)/(E+r), "
            "F- = M*T0*(1+r)*(E-1)/(1+E*r), E = exp(mu*theta). Starts at rest, "
            "carrier centred."
        ),
    }
    with open(os.path.join(outdir, "truth.json"), "w") as fh:
        json.dump(truth, fh, indent=2)
    return truth, summary


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python -m benchmarks.blind.band_brake_generator OUTDIR")
    truth, summary = main(sys.argv[1])
    print(json.dumps({k: truth[k] for k in ("slip_force_positive_N", "slip_force_negative_N",
                                            "clearance_g_m", "stretch_at_slip_positive_m",
                                            "stretch_at_slip_negative_m")}, indent=1))
    for k, v in summary.items():
        print(f"{k}: max {v[0]:.1f} N, min {v[1]:.1f} N (noise-free max {v[2]:.1f}, min {v[3]:.1f})")
