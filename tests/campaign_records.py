"""Synthetic two-campaign rig records of one friction damper (test helper).

A displacement-controlled rig imposes u(t) (m) and a load cell measures f(t) (N). The damper
is an ideal elasto-plastic (Jenkins) element: a linear spring of stiffness k (N/m) in series
with a Coulomb slider of slip force F (N), i.e. the classic stop operator -- the force follows
k*du while |force| < F and stays at +-F while slipping, starting from zero force at the first
sample. The load cell adds a constant offset c (N) and white Gaussian noise of sd 2 N;
sampling is 200 Hz. Each campaign runs three sine tests u = a*sin(2*pi*f_d*t) over 2.25
cycles: (f_d, a) = (1 Hz, 4 mm), (0.5 Hz, 6 mm), (2 Hz, 3 mm). Campaign A has k = 4.0e5 N/m,
F = 800 N, c = 5 N; campaign B differs in exactly one property (`change`) or none:
"slip_force" (F 20 % lower), "stiffness" (k halved), "offset" (c = 150 N), "none".

The physics is written here in NumPy and shares no code with tribojax's friction elements;
tribojax is used only to wrap the arrays as `HysteresisLoop` records.
"""

import numpy as np

import tribojax as tj

FS, NOISE_SD, CYCLES = 200.0, 2.0, 2.25
TESTS = ((1.0, 4e-3), (0.5, 6e-3), (2.0, 3e-3))  # (f_d Hz, a m)
BASE = {"k": 4.0e5, "F": 800.0, "c": 5.0}
CHANGES = {
    "slip_force": {"F": 0.8 * 800.0},
    "stiffness": {"k": 2.0e5},
    "offset": {"c": 150.0},
    "none": {},
}


def _stop_operator(u: np.ndarray, k: float, F: float) -> np.ndarray:
    """Jenkins element force for the displacement history u, from zero force at u[0]."""
    f = np.zeros_like(u)
    for i in range(1, u.size):
        f[i] = min(max(f[i - 1] + k * (u[i] - u[i - 1]), -F), F)
    return f


def campaign_records(change: str, seed: int = 0) -> dict[str, list]:
    """{"A": [3 HysteresisLoop], "B": [3 HysteresisLoop]}; B differs from A per `change`."""
    if change not in CHANGES:
        raise ValueError(f"unknown change {change!r}; expected one of {sorted(CHANGES)}")
    props = {"A": dict(BASE), "B": {**BASE, **CHANGES[change]}}
    out: dict[str, list] = {}
    for ci, (camp, p) in enumerate(props.items()):
        recs = []
        for ti, (fd, a) in enumerate(TESTS):
            t = np.arange(int(round(CYCLES * FS / fd)) + 1) / FS
            u = a * np.sin(2 * np.pi * fd * t)
            rng = np.random.default_rng([seed, ci, ti])
            f = _stop_operator(u, p["k"], p["F"]) + p["c"] + rng.normal(0.0, NOISE_SD, t.size)
            src = f"{camp}_{fd:g}Hz_{a * 1e3:g}mm"
            recs.append(tj.HysteresisLoop(t, u, f, frequency=fd, source=src))
        out[camp] = recs
    return out
