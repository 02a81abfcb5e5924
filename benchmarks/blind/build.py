"""Turn record specs (catalog.py) into noise-free signals, noisy records,
sidecars, manifest entries and per-effect visibilities."""
import numpy as np
import slipsim as ss
from catalog import CONTACTS, loop_drive
from drives import scurve, trapezoid
from loopsim import contact_force

FS_SLIP = 2000.0                 # [Hz] slip-run sample rate
N_SLIP = 4601                    # samples, 0 .. 2.3 s
NOISE_FLOOR_M = 0.3e-9           # [m]
FRICTION_FX = ("load_coupling", "stribeck", "viscous_friction")

_DRIVES = {"trapezoid": trapezoid(), "scurve": scurve()}
_PHYS_CACHE = {}


def _fmt(x):
    return f"{x:g}"


def slip_label(spec):
    hid = "+".join(spec["effects"]) or "clean"
    m = "" if spec["mass_factor"] == 1.0 else f"/m{_fmt(spec['mass_factor'])}"
    return f"slip/{hid}/{spec['drive']}/{_fmt(spec['vac'])}kPa{m}/s{spec['seed']}"


def loop_label(spec):
    c = CONTACTS[spec["contact"]]
    hid = "+".join(spec["effects"]) or "clean"
    return f"loop/{hid}/{spec['drive']}/muN{c['mu'] * c['N']:.3g}N/s{spec['seed']}"


def _physical(drive_name, vac, mf, fr):
    """Cached friction solution; fr = (kappa, delta, v_s, sigma2)."""
    key = (drive_name, vac, mf, fr)
    if key not in _PHYS_CACHE:
        m = ss.M_RETICLE * mf
        Fs, K, C = ss.contact_params(vac, m)
        t = np.arange(N_SLIP) / FS_SLIP
        kappa, delta, v_s, sigma2 = fr
        _PHYS_CACHE[key] = ss.solve_slip(_DRIVES[drive_name], t, m, Fs, K, C, kappa=kappa,
                                         delta=delta, v_s=v_s, sigma2=sigma2, method="LSODA")
    return _PHYS_CACHE[key]


def resolve_slip(spec):
    """True parameters of a slip spec, all SI (v_s and sigma2 resolved)."""
    mf, vac = spec["mass_factor"], spec["vac"]
    m = ss.M_RETICLE * mf
    Fs, K, C = ss.contact_params(vac, m)
    fx = {}
    for name, p in spec["effects"].items():
        p = dict(p)
        if name == "stribeck":
            vpk = float(np.max(np.abs(_physical(spec["drive"], vac, mf, (0.0, 0.0, 1.0, 0.0))["v"])))
            p["v_s_m_s"] = p.pop("vs_factor") * vpk
        if name == "viscous_friction":
            p["sigma2_N_s_m"] = p["sigma2_over_C"] * C
            p["relaxation_time_sigma2_over_K_s"] = p["sigma2_N_s_m"] / K
        if name == "vibration":
            p["gain_unit"] = "s" if p["mode"] == "jerk" else "dimensionless"
        if name == "load_coupling":
            p["g_m_s2"] = ss.G_LOAD
        fx[name] = p
    return {"mass_kg": m, "vacuum_kPa": vac, "normal_load_N": ss.normal_load(vac, m),
            "F_s_N": Fs, "K_tau_N_m": K, "C_tau_N_s_m": C, "z_max_m": Fs / K,
            "alpha": 1.0, "effects": fx}


def slip_signals(spec, params, drop=()):
    """Noise-free (t, a, reading, physical slip) with the effects in drop removed."""
    fx = {k: v for k, v in params["effects"].items() if k not in drop}
    d = _DRIVES[spec["drive"]]
    t = np.arange(N_SLIP) / FS_SLIP
    fr = (fx.get("load_coupling", {}).get("kappa", 0.0),
          fx.get("stribeck", {}).get("delta", 0.0),
          fx.get("stribeck", {}).get("v_s_m_s", 1.0),
          fx.get("viscous_friction", {}).get("sigma2_N_s_m", 0.0))
    phys = _physical(spec["drive"], spec["vac"], spec["mass_factor"], fr)["slip"]
    reading = phys.copy()
    if "sensor_drift" in fx:
        p = fx["sensor_drift"]
        reading = reading + ss.drift(t, p["kind"], p)
    if "position_error" in fx:
        p = fx["position_error"]
        reading = reading + ss.position_error(d.position(t), p["eps"], p["eps2_per_m"])
    if "vibration" in fx:
        p = fx["vibration"]
        reading = reading + ss.vibration(d, t, p["f_n_Hz"], p["zeta"], p["gain"], p["mode"])
    return t, d.accel(t), reading, phys


def _visibility(full, sd, without):
    return {k: float(np.sqrt(np.mean((full - w) ** 2)) / sd) for k, w in without.items()}


def build_slip(spec):
    """Noisy record + sidecar + manifest entry for one slip spec."""
    params = resolve_slip(spec)
    t, a, reading, phys = slip_signals(spec, params)
    sd = max(NOISE_FLOOR_M, spec["noise_frac"] * float(np.max(np.abs(phys))))
    noisy = reading + sd * np.random.default_rng(spec["seed"]).standard_normal(len(t))
    vis = _visibility(reading, sd, {k: slip_signals(spec, params, drop=(k,))[2]
                                    for k in spec["effects"]})
    side = {"mass_kg": params["mass_kg"], "normal_load_N": params["normal_load_N"]}
    if spec["noise_stated"]:
        side["noise_std_m"] = sd
    params.update(noise_std_m=sd, noise_fraction_of_peak_slip=spec["noise_frac"],
                  noise_stated=spec["noise_stated"], peak_slip_m=float(np.max(np.abs(phys))),
                  sample_rate_Hz=FS_SLIP)
    return {"kind": "slip", "label": slip_label(spec), "header": "time_s,stage_accel_m_s2,slip_m",
            "columns": (t, a, noisy), "sidecar": side, "hidden": list(spec["effects"]),
            "drive": _DRIVES[spec["drive"]].meta, "params": params, "seed": spec["seed"],
            "visibility_sd": vis, "clean": (t, a, reading)}


def resolve_loop(spec):
    c = CONTACTS[spec["contact"]]
    muN, Kd, A = c["mu"] * c["N"], c["Kd"], c["A"]
    fx = {}
    for name, p in spec["effects"].items():
        p = dict(p)
        if name == "viscous_damping":
            p["c_N_s_m"] = p["c_omega_A_over_muN"] * muN / (2 * np.pi * c["f"] * A)
        if name == "backlash":
            p["gap_m"] = p["gap_over_A"] * A
        if name == "force_offset":
            p["offset_N"] = p["offset_over_muN"] * muN
        if name == "normal_load_variation":
            p["A_ref_m"] = A
        if name == "microslip":
            p["A0_m"] = muN / Kd
            p["layout"] = "k_i = K_d/n, slip displacements uniform on (0, 2 A0]"
        fx[name] = p
    return {"normal_load_N": c["N"], "mu": c["mu"], "muN_N": muN, "K_d_N_m": Kd,
            "A0_m": muN / Kd, "amplitude_m": A, "frequency_Hz": c["f"], "effects": fx}


def loop_signals(spec, params, drop=()):
    """Noise-free (t, u, f) with the effects in drop removed."""
    fx = {k: v for k, v in params["effects"].items() if k not in drop}
    d, t, _ = loop_drive(spec)
    ms, nl = fx.get("microslip", {}), fx.get("normal_load_variation", {})
    f = contact_force(d, t, params["muN_N"], params["K_d_N_m"],
                      n_el=ms.get("n_elements", 1), spread=ms.get("spread", 0.0),
                      gap=fx.get("backlash", {}).get("gap_m", 0.0),
                      beta=nl.get("beta", 0.0), beta2=nl.get("beta2", 0.0),
                      gamma=nl.get("gamma", 0.0), A_ref=nl.get("A_ref_m", 1.0),
                      c=fx.get("viscous_damping", {}).get("c_N_s_m", 0.0),
                      f_off=fx.get("force_offset", {}).get("offset_N", 0.0))
    return t, d.u(t), f


def build_loop(spec):
    """Noisy record + sidecar + manifest entry for one loop spec."""
    params = resolve_loop(spec)
    d, _, fund = loop_drive(spec)
    t, u, f = loop_signals(spec, params)
    sd = spec["noise_frac"] * params["muN_N"]
    noisy = f + sd * np.random.default_rng(spec["seed"]).standard_normal(len(t))
    vis = _visibility(f, sd, {k: loop_signals(spec, params, drop=(k,))[2] for k in spec["effects"]})
    side = {"normal_load_N": params["normal_load_N"]}
    if fund is None:
        side = {"drive": "history", **side}
        params["frequency_Hz"] = None
    else:
        side["frequency_Hz"] = fund
    if spec["noise_stated"]:
        side["noise_std_N"] = sd
    params.update(noise_std_N=sd, noise_fraction_of_muN=spec["noise_frac"],
                  noise_stated=spec["noise_stated"], n_samples=len(t),
                  sample_rate_Hz=float(1.0 / (t[1] - t[0])))
    return {"kind": "loop", "label": loop_label(spec), "header": "time_s,displacement_m,force_N",
            "columns": (t, u, noisy), "sidecar": side, "hidden": list(spec["effects"]),
            "drive": d.meta(), "params": params, "seed": spec["seed"],
            "visibility_sd": vis, "clean": (t, u, f)}
