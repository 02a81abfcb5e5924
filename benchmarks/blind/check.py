"""Self-checks of the blind record generator.

usage: python benchmarks/blind/check.py [--records DIR]
Physics checks run on freshly simulated signals; file checks run on DIR
(default /tmp/blind_records, as written by generate.py). Exit status 1 on failure.
"""
import argparse
import copy
import filecmp
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import slipsim as ss  # noqa: E402
from build import build_loop, build_slip, loop_signals, resolve_loop, resolve_slip, slip_signals  # noqa: E402
from catalog import CONTACTS, LOOP_SPECS, SLIP_SPECS, loop_drive  # noqa: E402
from drives import LoopDrive, scurve, trapezoid  # noqa: E402
from loopsim import contact_force, jenkins_energy_formula, loop_energy  # noqa: E402
from recio import read_csv  # noqa: E402

FAILS = []


def ok(cond, msg):
    print(("PASS " if cond else "FAIL ") + msg)
    if not cond:
        FAILS.append(msg)


def check_inputs():
    loads = [ss.normal_load(v, ss.M_RETICLE) for v in ss.TABLE3]
    ok(np.allclose(loads, [3.6912, 4.9638, 6.7818, 9.5088, 12.2358, 21.3258], atol=5e-5),
       f"Eq 28 reproduces Table 3 loads {np.round(loads, 4).tolist()}")
    for d in (trapezoid(), scurve()):
        t = np.linspace(0, 2.3, 23001)
        v, a = d.velocity(t), d.accel(t)
        ok(abs(v.max() - 0.5) < 1e-12 and abs(v[-1]) < 1e-12 and abs(a).max() <= 1.0 + 1e-15,
           f"{d.name}: v_max 0.5 m/s, ends at rest, |a| <= 1 m/s^2 (x_end {d.position(2.3)[0]:.4f} m)")
        num = np.concatenate([[0], np.cumsum(0.5 * (a[1:] + a[:-1]) * np.diff(t))])
        ok(np.max(np.abs(num - v)) < 1e-7, f"{d.name}: exact velocity = integral of a")


def check_quasi_static():
    """Heaviest load, clean: slip in the steady-acceleration windows equals the
    quasi-static pre-sliding value -z_max ln(1 - m a/F_s) ~ m a / K_tau."""
    t = np.arange(4601) / 2000.0
    for dname, d, win_p, win_0, win_n in (
            ("trapezoid", trapezoid(), (0.35, 0.60), (0.90, 1.50), (1.75, 2.00)),
            ("scurve", scurve(), (0.30, 0.60), (0.85, 1.40), (1.60, 1.90))):
        m = ss.M_RETICLE
        Fs, K, C = ss.TABLE3[20]
        r = ss.solve_slip(d, t, m, Fs, K, C, method="LSODA")
        x, z = r["slip"], r["z"]
        lin, qs = m / K, -Fs / K * np.log(1 - m / Fs)
        w0 = (t >= win_0[0]) & (t <= win_0[1])
        for sgn, (a0, a1), base in ((1, win_p, 0.0), (-1, win_n, x[w0].mean())):
            w = (t >= a0) & (t <= a1)
            mean = sgn * (x[w].mean() - base)
            ok(abs(mean / qs - 1) < 5e-4 and abs(mean / lin - 1) < 0.04 and np.ptp(x[w]) < 1e-3 * qs,
               f"{dname} 20 kPa a={sgn:+d}: slip change {mean * 1e9:.4f} nm, -z_max ln(1-ma/F_s) "
               f"{qs * 1e9:.4f} nm, m a/K {lin * 1e9:.4f} nm, flat in window")
        ok(np.max(np.abs(z)) * K / Fs < 0.07 and abs(x[-1]) < 1e-13,
           f"{dname} 20 kPa: |z|/z_max <= {np.max(np.abs(z)) * K / Fs:.4f} (pre-sliding), "
           f"slip back to {x[-1] * 1e9:.1e} nm at rest")
    d = trapezoid()
    Fs, K, C = ss.TABLE3[20]
    ref = ss.solve_slip(d, t, ss.M_RETICLE, Fs, K, C, method="Radau", rtol=1e-12)["slip"]
    lso = ss.solve_slip(d, t, ss.M_RETICLE, Fs, K, C, method="LSODA")["slip"]
    ok(np.max(np.abs(ref - lso)) < 1e-14, f"LSODA vs Radau(rtol 1e-12): max diff "
       f"{np.max(np.abs(ref - lso)) * 1e9:.1e} nm")


def check_switched_off():
    """Every effect at zero strength gives the clean signal bit for bit."""
    t = np.arange(4601) / 2000.0
    d = trapezoid()
    for vac in (0.6, 20):
        Fs, K, C = ss.TABLE3[vac]
        base = ss.solve_slip(d, t, ss.M_RETICLE, Fs, K, C, method="LSODA")["slip"]
        for kw in ({"kappa": 0.0}, {"delta": 0.0, "v_s": 3.7e-7}, {"sigma2": 0.0},
                   {"kappa": 0.0, "delta": 0.0, "v_s": 1e-8, "sigma2": 0.0}):
            x = ss.solve_slip(d, t, ss.M_RETICLE, Fs, K, C, method="LSODA", **kw)["slip"]
            ok(np.array_equal(x, base), f"slip {vac} kPa friction effect off {kw}: identical")
    zero = {"sensor_drift": {"kind": "poly", "c1_m_s": 0.0, "c2_m_s2": 0.0, "c3_m_s3": 0.0},
            "position_error": {"eps": 0.0, "eps2_per_m": 0.0},
            "vibration": {"mode": "jerk", "f_n_Hz": 80.0, "zeta": 0.05, "gain": 0.0},
            "stribeck": {"delta": 0.0, "vs_factor": 0.3},
            "load_coupling": {"kappa": 0.0}, "viscous_friction": {"sigma2_over_C": 0.0}}
    clean = next(s for s in SLIP_SPECS if s["vac"] == 4 and not s["effects"] and s["drive"] == "trapezoid")
    rc = build_slip(clean)
    for name, p in zero.items():
        sp = copy.deepcopy(clean)
        sp["effects"] = {name: p}
        rz = build_slip(sp)
        ok(all(np.array_equal(a, b) for a, b in zip(rz["columns"], rc["columns"])),
           f"slip record with {name} at zero strength == clean record (noisy columns)")
    for mode in ("accel", "accel_dynamic", "jerk"):
        q = ss.vibration(d, t, 60.0, 0.03, 0.0, mode)
        ok(np.array_equal(q, np.zeros_like(q)), f"vibration {mode} with gain 0 adds exactly 0")
    lzero = {"viscous_damping": {"c_omega_A_over_muN": 0.0}, "force_offset": {"offset_over_muN": 0.0},
             "backlash": {"gap_over_A": 0.0},
             "normal_load_variation": {"beta": 0.0, "beta2": 0.0, "gamma": 0.76},
             "microslip": {"n_elements": 1, "spread": 1.0}}
    lclean = LOOP_SPECS[0]
    lc = build_loop(lclean)
    for name, p in lzero.items():
        sp = copy.deepcopy(lclean)
        sp["effects"] = {name: p}
        rz = build_loop(sp)
        ok(all(np.array_equal(a, b) for a, b in zip(rz["columns"], lc["columns"])),
           f"loop record with {name} at zero strength == clean record (noisy columns)")
    sp = copy.deepcopy(lclean)
    sp["effects"] = {"microslip": {"n_elements": 200, "spread": 0.0}}
    p = resolve_loop(sp)
    f0, f1 = loop_signals(lclean, resolve_loop(lclean))[2], loop_signals(sp, p)[2]
    ok(np.max(np.abs(f1 - f0)) < 1e-12 * p["muN_N"],
       f"200-element bank with zero spread == Jenkins to {np.max(np.abs(f1 - f0)):.1e} N")


def check_jenkins():
    """Clean sinusoidal Jenkins loop: dissipated energy per steady cycle
    equals 4 mu N (A - mu N / K_d); force bounded by mu N."""
    for spec in [s for s in LOOP_SPECS if not s["effects"] and s["drive"] == "sine"]:
        c = CONTACTS[spec["contact"]]
        muN, Kd, A, f = c["mu"] * c["N"], c["Kd"], c["A"], c["f"]
        W = jenkins_energy_formula(A, muN, Kd)
        d = LoopDrive("sine", A=A, f=f)
        td = np.linspace(1.0 / f, 2.0 / f, 400001)
        fd = contact_force(d, np.concatenate([[0.0, 0.25 / f, 0.75 / f], td]), muN, Kd)[3:]
        Wd = loop_energy(d.u(td), fd)
        t, u, fr = loop_signals(spec, resolve_loop(spec))
        n = 200
        Wr = loop_energy(u[-n - 1:], fr[-n - 1:])
        ok(abs(Wd / W - 1) < 1e-6 and abs(Wr / W - 1) < 5e-3,
           f"{spec['contact']}: W formula {W:.6e} J, dense {Wd:.6e} J, record {Wr:.6e} J")
        ok(np.max(np.abs(fr)) <= muN * (1 + 1e-12) and abs(np.max(fr) / muN - 1) < 1e-12,
           f"{spec['contact']}: |f| <= mu N = {muN:.4g} N and reaches it")
        sub = contact_force(d, np.linspace(0, t[-1], 30 * (len(t) - 1) + 1), muN, Kd)[::30]
        ok(np.max(np.abs(sub - fr)) < 1e-12 * muN, "return mapping exact: fine grid == record grid")
    # partial reversals (inner loops): slider memory against a naive dense reference
    d2 = LoopDrive("decay", A=1.0, fk=[1.0, 5.0], c=[1.0, 0.6], tau=[1e9, 1e9], norm=1.0)
    tt = np.linspace(0, 2, 4001)
    fa = contact_force(d2, tt, 0.2, 1.0)
    td = np.linspace(0, 2, 400001)
    sl, expect = 0.0, np.empty(len(td))
    for i, u in enumerate(d2.u(td)):
        tr = u - sl
        if abs(tr) > 0.2:
            sl = u - np.sign(tr) * 0.2
            tr = np.sign(tr) * 0.2
        expect[i] = tr
    err = np.max(np.abs(fa - expect[::100]))
    ok(err < 1e-7 and len(d2.reversals(2.0)) > 8,
       f"inner loops: Jenkins update == naive dense reference ({err:.1e} N of 0.2 N)")
    for spec in LOOP_SPECS:
        if spec["drive"] in ("sine3", "rtri"):
            d, t, f0 = loop_drive(spec)
            nrev = len(d.reversals(t[-1]))
            ok(nrev == 2 * round(t[-1] * f0), f"{spec['drive']} h={spec.get('h')}: {nrev} reversals "
               f"in {t[-1] * f0:g} periods (no extra reversals)")


def check_files(rdir):
    man = json.load(open(os.path.join(rdir, "manifest.json")))
    ok(len(man) == len(SLIP_SPECS) + len(LOOP_SPECS), f"manifest lists {len(man)} records")
    labels = [m["label"] for m in man]
    ok(len(set(labels)) == len(labels), "labels unique")
    need = {"label", "file", "kind", "hidden", "drive", "params", "seed", "visibility_sd"}
    vocab = {"slip": {"sensor_drift", "position_error", "vibration", "load_coupling", "stribeck",
                      "viscous_friction"},
             "loop": {"microslip", "viscous_damping", "normal_load_variation", "backlash", "force_offset"}}
    bad, low, vis_all = [], [], []
    for m in man:
        if not need <= set(m) or not set(m["hidden"]) <= vocab[m["kind"]] or \
                set(m["visibility_sd"]) != set(m["hidden"]):
            bad.append(m["label"])
        for k, v in m["visibility_sd"].items():
            vis_all.append(v)
            if v < 3:
                low.append(f"{m['label']}:{k}={v:.2f}")
        hdr, D = read_csv(os.path.join(rdir, m["file"]))
        side = json.load(open(os.path.join(rdir, m["file"][:-4] + ".json")))
        t = D[:, 0]
        if m["kind"] == "slip":
            good = hdr == ["time_s", "stage_accel_m_s2", "slip_m"] and "mass_kg" in side and \
                set(side) <= {"mass_kg", "normal_load_N", "noise_std_m", "comment"} and \
                np.max(np.abs(D[:, 2])) < 1e-6 and 2000 <= len(t) <= 6000 and \
                m["params"]["peak_slip_m"] < 0.5 * 1e-6
        else:
            per = "frequency_Hz" in side
            keys = {"normal_load_N", "frequency_Hz", "noise_std_N"} if per else \
                {"drive", "normal_load_N", "noise_std_N"}
            good = hdr == ["time_s", "displacement_m", "force_N"] and set(side) <= keys | {"comment"} \
                and (per or side.get("drive") == "history")
        if not (good and t[0] == 0.0 and np.all(np.diff(t) > 0) and np.all(np.isfinite(D))):
            bad.append(m["file"])
    ok(not bad, f"file formats, sidecar keys, vocabulary, slip < 1 um: bad = {bad}")
    ok(not low, f"every hidden effect visible (>= 3 sd): min {min(vis_all):.1f}, "
       f"max {max(vis_all):.1f}; low = {low}")
    stated = sum(("noise_std_m" in json.load(open(os.path.join(rdir, m["file"][:-4] + ".json")))) or
                 ("noise_std_N" in json.load(open(os.path.join(rdir, m["file"][:-4] + ".json"))))
                 for m in man)
    ok(0.35 * len(man) <= stated <= 0.65 * len(man), f"noise stated in {stated}/{len(man)} sidecars")
    # the CSV holds the clean signal plus the stated noise
    for m in man[:3] + [x for x in man if x["kind"] == "loop"][:3]:
        spec = (SLIP_SPECS + LOOP_SPECS)[[x["label"] for x in man].index(m["label"])]
        if m["kind"] == "slip":
            clean = slip_signals(spec, resolve_slip(spec))[2]
            sd = m["params"]["noise_std_m"]
        else:
            clean = loop_signals(spec, resolve_loop(spec))[2]
            sd = m["params"]["noise_std_N"]
        res = read_csv(os.path.join(rdir, m["file"]))[1][:, 2] - clean
        ok(abs(res.std() / sd - 1) < 0.1 and abs(res.mean()) < 5 * sd / np.sqrt(len(res)),
           f"{m['file']}: residual sd / stated sd = {res.std() / sd:.3f}")


def check_determinism(rdir):
    gen = os.path.join(HERE, "generate.py")
    man = json.load(open(os.path.join(rdir, "manifest.json")))
    pick = [man[1]["label"], man[26]["label"], man[-3]["label"]]
    with tempfile.TemporaryDirectory() as a, tempfile.TemporaryDirectory() as b:
        for o in (a, b):
            subprocess.run([sys.executable, gen, "--out", o, "--quiet", "--only", *pick], check=True)
        files = sorted(os.listdir(a))
        same = all(filecmp.cmp(os.path.join(a, f), os.path.join(b, f), shallow=False) for f in files)
        same_main = all(filecmp.cmp(os.path.join(a, f), os.path.join(rdir, f), shallow=False)
                        for f in files if f != "manifest.json")
    ok(same and same_main, f"two runs of {pick} identical and equal to the full run's files")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--records", default="/tmp/blind_records")
    args = ap.parse_args()
    check_inputs()
    check_quasi_static()
    check_switched_off()
    check_jenkins()
    if os.path.exists(os.path.join(args.records, "manifest.json")):
        check_files(args.records)
        check_determinism(args.records)
    else:
        ok(False, f"no manifest in {args.records}: run generate.py first")
    print(f"\n{'ALL PASSED' if not FAILS else f'{len(FAILS)} FAILED'}")
    sys.exit(1 if FAILS else 0)


if __name__ == "__main__":
    main()
