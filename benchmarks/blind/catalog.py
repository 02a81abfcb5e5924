"""The record table: every synthetic record as a small spec (pure data).

Slip specs: drive ("trapezoid" | "scurve"), vacuum [kPa], mass factor, noise
fraction of the peak physical slip (floor 0.3 nm), whether the sidecar states
the noise, and the hidden effects with their true parameters (SI).
Loop specs: contact, drive, noise fraction of mu N, effects.
"""
import numpy as np
from drives import LoopDrive, chirp_drive, decay_drive

SLIP_SEED0, LOOP_SEED0 = 3000, 5000

# --- slip runs -------------------------------------------------------------
_S = []


def _slip(drive, vac, effects=None, noise=0.02, mass_factor=1.0):
    _S.append({"drive": drive, "vac": vac, "mass_factor": mass_factor,
               "effects": effects or {}, "noise_frac": noise})


for _v in (0.6, 2, 4, 7, 10, 20):
    _slip("trapezoid", _v, noise=0.01 if _v < 5 else 0.02)

DRIFT_POLY = {"sensor_drift": {"kind": "poly", "c1_m_s": 3.0e-9, "c2_m_s2": -0.6e-9, "c3_m_s3": 0.0}}
DRIFT_THERM = {"sensor_drift": {"kind": "thermal", "D_m": 4.0e-9, "tau_s": 0.8, "t0_s": 0.0}}
DRIFT_WALK = {"sensor_drift": {"kind": "walk", "sigma_rw_m_sqrt_s": 4.0e-9, "smooth_s": 0.05, "seed": 77}}
_slip("trapezoid", 2, DRIFT_POLY, noise=0.02)
_slip("trapezoid", 20, DRIFT_THERM)
_slip("trapezoid", 0.6, {"position_error": {"eps": 1.0e-7, "eps2_per_m": 0.0}}, noise=0.03)
_slip("trapezoid", 2, {"position_error": {"eps": 1.0e-7, "eps2_per_m": -1.0e-7}}, noise=0.03)
_slip("trapezoid", 4, {"vibration": {"mode": "accel", "f_n_Hz": 60.0, "zeta": 0.03, "gain": 5.0e-4}})
_slip("trapezoid", 20, {"vibration": {"mode": "accel_dynamic", "f_n_Hz": 35.0, "zeta": 0.01, "gain": 4.0e-3}})
_slip("trapezoid", 0.6, {"load_coupling": {"kappa": -0.45}}, noise=0.01)
_slip("trapezoid", 2, {"load_coupling": {"kappa": 0.5}}, noise=0.01)
_slip("trapezoid", 4, {"stribeck": {"delta": 0.5, "vs_factor": 0.2}}, noise=0.01)
_slip("trapezoid", 2, {"stribeck": {"delta": 0.3, "vs_factor": 0.5}}, noise=0.01)
_slip("trapezoid", 0.6, {"viscous_friction": {"sigma2_over_C": 200.0}}, noise=0.01)
_slip("trapezoid", 2, {"viscous_friction": {"sigma2_over_C": 600.0}}, noise=0.01)
# S-curve drive
_slip("scurve", 4, noise=0.02)
_slip("scurve", 7, {"vibration": {"mode": "jerk", "f_n_Hz": 80.0, "zeta": 0.05, "gain": 1.0e-4}})
_slip("scurve", 4, {"stribeck": {"delta": 0.5, "vs_factor": 0.3}}, noise=0.01)
_slip("scurve", 2, {"load_coupling": {"kappa": 0.5}}, noise=0.01)
# heavier reticle (1.5 x 0.321 kg)
_slip("trapezoid", 0.6, mass_factor=1.5, noise=0.02)
_slip("trapezoid", 0.6, {"viscous_friction": {"sigma2_over_C": 400.0}}, mass_factor=1.5, noise=0.01)
_slip("trapezoid", 7, {"position_error": {"eps": 1.0e-7, "eps2_per_m": -1.0e-7}}, mass_factor=1.5, noise=0.03)
# two hidden effects at once
_slip("trapezoid", 10, {**DRIFT_WALK, "vibration": {"mode": "accel", "f_n_Hz": 150.0, "zeta": 0.04, "gain": 2.5e-3}})
_slip("trapezoid", 2, {"stribeck": {"delta": 0.3, "vs_factor": 0.5}, "load_coupling": {"kappa": -0.45}}, noise=0.01)
_slip("trapezoid", 0.6, {"position_error": {"eps": 1.0e-7, "eps2_per_m": -1.0e-7},
                         "viscous_friction": {"sigma2_over_C": 200.0}}, noise=0.01)
_slip("trapezoid", 4, {"vibration": {"mode": "jerk", "f_n_Hz": 120.0, "zeta": 0.02, "gain": 2.5e-4},
                       "stribeck": {"delta": 0.4, "vs_factor": 0.3}}, noise=0.01)

for _k, _s in enumerate(_S):
    _s["seed"] = SLIP_SEED0 + _k
    _s["noise_stated"] = _k % 2 == 0
SLIP_SPECS = _S

# --- hysteresis loops ------------------------------------------------------
# contacts: N [N], mu, K_d [N/m], amplitude A [m], fundamental f [Hz]
# (wu2015 Eq 5 read as K_d = 0.5924 N^0.7616 N/um for the small contacts)
CONTACTS = {
    "C1": {"N": 2.94, "mu": 0.50, "Kd": 0.5924e6 * 2.94**0.7616, "A": 10e-6, "f": 22.0},
    "C2": {"N": 4.90, "mu": 0.45, "Kd": 0.5924e6 * 4.90**0.7616, "A": 8e-6, "f": 82.0},
    "C3": {"N": 1.96, "mu": 0.55, "Kd": 0.5924e6 * 1.96**0.7616, "A": 15e-6, "f": 22.0},
    "C4": {"N": 400.0, "mu": 0.30, "Kd": 6.0e7, "A": 20e-6, "f": 50.0},
    "C5": {"N": 1000.0, "mu": 0.40, "Kd": 2.0e8, "A": 12e-6, "f": 100.0},
}


def loop_drive(spec):
    """(LoopDrive, sample times [s], fundamental [Hz] or None) for a loop spec."""
    c, kind = CONTACTS[spec["contact"]], spec["drive"]
    A, f = c["A"], c["f"]
    if kind == "sine":
        d = LoopDrive("sine", A=A, f=f)
    elif kind == "sine3":
        d = LoopDrive("sine3", A=A, f=f, h=spec.get("h", 0.25))
    elif kind == "rtri":
        d = LoopDrive("rtri", A=A, f=f, rho=0.97)
    elif kind == "decay":
        d = decay_drive(A, fk=[f, 2.77 * f], c=[1.0, 0.35], tau=[0.12, 0.05])
        return d, np.arange(3001) / 10000.0, None
    else:
        d = chirp_drive(A, f0=15.0, f1=60.0, T=0.25)
        return d, np.arange(3001) / 12000.0, None
    n = spec.get("cycles", 3) * 200
    return d, np.arange(n + 1) / (200.0 * f), f


_L = []


def _loop(contact, drive, effects=None, noise=0.01, **kw):
    _L.append({"contact": contact, "drive": drive, "effects": effects or {},
               "noise_frac": noise, **kw})


_loop("C1", "sine", noise=0.01)
_loop("C4", "sine", noise=0.005, cycles=2)
_loop("C2", "sine", {"microslip": {"n_elements": 200, "spread": 1.0}}, noise=0.01)
_loop("C3", "decay", {"microslip": {"n_elements": 200, "spread": 1.0}}, noise=0.01)
_loop("C5", "sine", {"viscous_damping": {"c_omega_A_over_muN": 0.08}}, noise=0.01)
_loop("C1", "sine3", {"viscous_damping": {"c_omega_A_over_muN": 0.06}}, noise=0.005, h=0.25)
_loop("C3", "sine", {"normal_load_variation": {"beta": 0.25, "beta2": 0.0, "gamma": 0.76}}, noise=0.01)
_loop("C4", "rtri", {"normal_load_variation": {"beta": 0.15, "beta2": 0.1, "gamma": 0.0}}, noise=0.01)
_loop("C2", "sine", {"backlash": {"gap_over_A": 0.3}}, noise=0.02)
_loop("C5", "sine3", {"backlash": {"gap_over_A": 0.15}}, noise=0.01, h=0.2)
_loop("C4", "sine", {"force_offset": {"offset_over_muN": 0.06}}, noise=0.01, cycles=4)
_loop("C3", "rtri", {"force_offset": {"offset_over_muN": -0.08}}, noise=0.015)
_loop("C1", "sine", {"backlash": {"gap_over_A": 0.4}, "force_offset": {"offset_over_muN": 0.05}}, noise=0.01)
_loop("C4", "sine3", {"microslip": {"n_elements": 200, "spread": 1.0},
                      "viscous_damping": {"c_omega_A_over_muN": 0.07}}, noise=0.008, h=0.3)
_loop("C5", "sine", {"normal_load_variation": {"beta": 0.2, "beta2": 0.0, "gamma": 0.76},
                     "backlash": {"gap_over_A": 0.2}}, noise=0.01)
_loop("C2", "chirp", noise=0.01)

for _k, _s in enumerate(_L):
    _s["seed"] = LOOP_SEED0 + _k
    _s["noise_stated"] = _k % 2 == 1
LOOP_SPECS = _L
