"""Prescribed drives: stage acceleration profiles (slip runs) and contact
displacement histories (hysteresis loops). Written blind from the papers."""
import numpy as np
from scipy.optimize import brentq


class StageDrive:
    """Piecewise stage acceleration a(t) [m/s^2] from rest at t = 0.

    Each segment (t0, t1, a0, a1, shape) moves a from a0 to a1 over [t0, t1]:
    shape "lin": a = a0 + (a1-a0)*s, s = (t-t0)/T (constant jerk);
    shape "cos": a = a0 + (a1-a0)*(1 - cos(pi*s))/2 (raised cosine, continuous
    jerk). Velocity and travel are the exact integrals, so x_stage(t) is exact.
    """

    def __init__(self, name, segments, horizon, meta):
        self.name, self.horizon, self.meta = name, float(horizon), meta
        segs, t = [], 0.0
        for (t0, t1, a0, a1, shape) in segments:
            if t0 > t:
                segs.append((t, t0, 0.0, 0.0, "lin"))
            segs.append((float(t0), float(t1), float(a0), float(a1), shape))
            t = t1
        if t < horizon:
            segs.append((t, float(horizon), 0.0, 0.0, "lin"))
        self.segs = segs
        v0, x0 = 0.0, 0.0
        self.start = []
        for s in segs:
            self.start.append((v0, x0))
            v0, x0 = self._integrals(s, s[1], v0, x0)

    def kinks(self):
        """Segment boundaries [s] (where the jerk may jump)."""
        return [s[0] for s in self.segs] + [self.horizon]

    @staticmethod
    def _integrals(seg, t, v0, x0):
        t0, t1, a0, a1, shape = seg
        T, tau, d = t1 - t0, t - t0, a1 - a0
        if shape == "lin":
            v = v0 + a0 * tau + d * tau**2 / (2 * T)
            x = x0 + v0 * tau + a0 * tau**2 / 2 + d * tau**3 / (6 * T)
        else:
            w = np.pi / T
            v = v0 + a0 * tau + d / 2 * (tau - np.sin(w * tau) / w)
            x = x0 + v0 * tau + a0 * tau**2 / 2 + d / 2 * (tau**2 / 2 - (1 - np.cos(w * tau)) / w**2)
        return v, x

    def _seg_index(self, t):
        t = np.atleast_1d(np.asarray(t, float))
        starts = np.array([s[0] for s in self.segs])
        return np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.segs) - 1), t

    def _eval(self, t, what):
        idx, t = self._seg_index(t)
        out = np.empty_like(t)
        for k in np.unique(idx):
            m = idx == k
            seg = self.segs[k]
            t0, t1, a0, a1, shape = seg
            T, tau, d = t1 - t0, t[m] - t0, a1 - a0
            if what == "a":
                s = tau / T
                out[m] = a0 + d * (s if shape == "lin" else (1 - np.cos(np.pi * s)) / 2)
            elif what == "j":
                out[m] = d / T if shape == "lin" else d * np.pi / (2 * T) * np.sin(np.pi * tau / T)
            else:
                v0, x0 = self.start[k]
                v, x = self._integrals(seg, t[m], v0, x0)
                out[m] = v if what == "v" else x
        return out

    def accel(self, t):
        """a(t) [m/s^2]."""
        return self._eval(t, "a")

    @staticmethod
    def seg_accel(seg, t):
        """a(t) [m/s^2] inside one segment (scalar, for ODE right-hand sides)."""
        t0, t1, a0, a1, shape = seg
        s = (t - t0) / (t1 - t0)
        return a0 + (a1 - a0) * (s if shape == "lin" else (1 - np.cos(np.pi * s)) / 2)

    @staticmethod
    def seg_jerk(seg, t):
        """da/dt [m/s^3] inside one segment (scalar)."""
        t0, t1, a0, a1, shape = seg
        if shape == "lin":
            return (a1 - a0) / (t1 - t0)
        return (a1 - a0) * np.pi / (2 * (t1 - t0)) * np.sin(np.pi * (t - t0) / (t1 - t0))

    def jerk(self, t):
        """da/dt [m/s^3]."""
        return self._eval(t, "j")

    def velocity(self, t):
        """Stage speed [m/s] (exact integral of a from rest)."""
        return self._eval(t, "v")

    def position(self, t):
        """Stage travel x_stage [m] (exact double integral of a from rest)."""
        return self._eval(t, "x")


def trapezoid(a_max=1.0):
    """wang2022 stage profile: 0.15 s linear ramps, +a_max held 0.25-0.60 s,
    -a_max held 1.65-2.00 s, v_max = 0.5 m/s, horizon 2.3 s."""
    segs = [(0.10, 0.25, 0, a_max, "lin"), (0.25, 0.60, a_max, a_max, "lin"),
            (0.60, 0.75, a_max, 0, "lin"), (1.50, 1.65, 0, -a_max, "lin"),
            (1.65, 2.00, -a_max, -a_max, "lin"), (2.00, 2.15, -a_max, 0, "lin")]
    meta = {"type": "trapezoid", "a_max_m_s2": a_max, "ramp_s": 0.15,
            "formula": "piecewise linear a(t); segments [t0_s, t1_s, a0, a1, shape]",
            "segments_s_m_s2": [[s[0], s[1], s[2], s[3], s[4]] for s in segs],
            "v_max_m_s": 0.5, "horizon_s": 2.3}
    return StageDrive("trapezoid", segs, 2.3, meta)


def scurve(a_max=1.0):
    """Jerk-limited S-curve: raised-cosine acceleration ramps of 0.10 s (peak
    jerk pi*a_max/0.2 = 15.7 m/s^3), holds 0.40 s, v_max = 0.5 m/s, horizon 2.3 s."""
    segs = [(0.10, 0.20, 0, a_max, "cos"), (0.20, 0.60, a_max, a_max, "lin"),
            (0.60, 0.70, a_max, 0, "cos"), (1.40, 1.50, 0, -a_max, "cos"),
            (1.50, 1.90, -a_max, -a_max, "lin"), (1.90, 2.00, -a_max, 0, "cos")]
    meta = {"type": "scurve", "a_max_m_s2": a_max, "ramp_s": 0.10,
            "formula": "a = a0 + (a1 - a0)(1 - cos(pi (t - t0)/(t1 - t0)))/2 on 'cos' segments",
            "ramp_shape": "raised cosine", "peak_jerk_m_s3": np.pi * a_max / 0.2,
            "segments_s_m_s2": [[s[0], s[1], s[2], s[3], s[4]] for s in segs],
            "v_max_m_s": 0.5, "horizon_s": 2.3}
    return StageDrive("scurve", segs, 2.3, meta)


class LoopDrive:
    """Displacement history u(t) [m] with analytic du/dt [m/s].

    kinds: "sine" u = A sin(wt); "sine3" u = A (sin wt - h sin 3wt)/(1+h)
    (monotone between the two reversals per period for h < 1/3);
    "rtri" rounded triangle u = A asin(rho sin wt)/asin(rho);
    "chirp" u = A env(t) sin(phi(t)), f from f0 to f1 over T, env = 0.35+0.65 sin(pi t/T);
    "decay" u = A sum_k c_k exp(-t/tau_k) sin(2 pi f_k t) / norm.
    """

    def __init__(self, kind, **p):
        self.kind, self.p = kind, p
        self.periodic = kind in ("sine", "sine3", "rtri")

    def _parts(self, t):
        p, t = self.p, np.asarray(t, float)
        if self.periodic:
            A, w = p["A"], 2 * np.pi * p["f"]
            th = w * t
            if self.kind == "sine":
                return A * np.sin(th), A * w * np.cos(th)
            if self.kind == "sine3":
                h = p["h"]
                return (A * (np.sin(th) - h * np.sin(3 * th)) / (1 + h),
                        A * w * (np.cos(th) - 3 * h * np.cos(3 * th)) / (1 + h))
            rho = p["rho"]
            s = rho * np.sin(th)
            return (A * np.arcsin(s) / np.arcsin(rho),
                    A * rho * w * np.cos(th) / np.sqrt(1 - s**2) / np.arcsin(rho))
        if self.kind == "chirp":
            A, f0, f1, T = p["A"], p["f0"], p["f1"], p["T"]
            ph = 2 * np.pi * (f0 * t + (f1 - f0) * t**2 / (2 * T))
            dph = 2 * np.pi * (f0 + (f1 - f0) * t / T)
            env = 0.35 + 0.65 * np.sin(np.pi * t / T)
            denv = 0.65 * np.pi / T * np.cos(np.pi * t / T)
            return A * env * np.sin(ph), A * (denv * np.sin(ph) + env * dph * np.cos(ph))
        A, u, du = p["A"], 0.0, 0.0
        for c, fk, tk in zip(p["c"], p["fk"], p["tau"]):
            e, w = np.exp(-t / tk), 2 * np.pi * fk
            u = u + c * e * np.sin(w * t)
            du = du + c * e * (w * np.cos(w * t) - np.sin(w * t) / tk)
        return A * u / p["norm"], A * du / p["norm"]

    def u(self, t):
        return self._parts(t)[0]

    def udot(self, t):
        return self._parts(t)[1]

    def reversals(self, t_end, n_fine=200000):
        """Times [s] in (0, t_end) where du/dt = 0 (brentq on a fine grid)."""
        tf = np.linspace(0.0, t_end, n_fine + 1)
        d = self.udot(tf)
        idx = np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0)[0]
        f = lambda x: float(self.udot(x))
        return np.array([brentq(f, tf[i], tf[i + 1], xtol=1e-15, rtol=1e-15) for i in idx])

    _UNITS = {"A": "A_m", "f": "f_Hz", "h": "h", "rho": "rho", "f0": "f0_Hz", "f1": "f1_Hz",
              "T": "T_s", "fk": "f_k_Hz", "c": "c_k", "tau": "tau_k_s", "norm": "norm"}
    _FORMULA = {"sine": "u = A sin(2 pi f t)",
                "sine3": "u = A (sin(2 pi f t) - h sin(6 pi f t)) / (1 + h)",
                "rtri": "u = A asin(rho sin(2 pi f t)) / asin(rho)",
                "chirp": "u = A (0.35 + 0.65 sin(pi t/T)) sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T)))",
                "decay": "u = A sum_k c_k exp(-t/tau_k) sin(2 pi f_k t) / norm"}

    def meta(self):
        """Drive description for the manifest (unit-suffixed keys)."""
        out = {"type": self.kind, "formula": self._FORMULA[self.kind]}
        for k, v in self.p.items():
            out[self._UNITS[k]] = list(v) if isinstance(v, (list, tuple)) else v
        return out


def decay_drive(A, fk, c, tau):
    """Decaying multi-tone normalised so that max|u| = A (found on a fine grid)."""
    d = LoopDrive("decay", A=1.0, fk=fk, c=c, tau=tau, norm=1.0)
    tf = np.linspace(0, 3 * max(tau), 400001)
    norm = float(np.max(np.abs(d.u(tf))))
    return LoopDrive("decay", A=A, fk=list(fk), c=list(c), tau=list(tau), norm=norm)


def chirp_drive(A, f0, f1, T):
    """Chirp normalised so that max|u| = A."""
    d = LoopDrive("chirp", A=1.0, f0=f0, f1=f1, T=T)
    tf = np.linspace(0, T, 400001)
    norm = float(np.max(np.abs(d.u(tf))))
    return LoopDrive("chirp", A=A / norm, f0=f0, f1=f1, T=T)
