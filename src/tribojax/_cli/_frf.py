"""`tribojax frf CONFIG.toml --out DIR`: forced response of a structure with friction contacts.

The configuration (TOML, SI units: `SCHEMA`, and `NEEDS` per contact type), an example, the
outputs and the exit status (2 on bad input): docs/cli.md, "`frf` configuration".
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from .._dynamics._continuation import frequency_response
from .._dynamics._mhb import FrictionSystem
from .._dynamics._structure import (
    DryFrictionContact2D,
    Excitation,
    FrictionContact,
    Structure,
)
from .._friction._elastic2d import ElasticDryFriction2D
from .._friction._rate_independent import Jenkins, Mindlin
from .._io._config import read_config
from .._io._files import write_text_atomic
from .._plot import figure, save_figure
from .._tables import DataFileError
from ._common import claim_outputs, error, progress, write_json_atomic

SCHEMA = {
    "structure": {"M": "matrix", "C": "matrix", "K": "matrix"},
    "contact[]": {
        "type": "string",
        "dof": "int?",
        "ref_dof": "int?",
        "mu": "number",
        "N": "number?",
        "K_d": "number?",
        "tangential_dof": "int?",
        "normal_dof": "int?",
        "k_t": "number?",
        "k_n": "number?",
        "n0": "number?",
    },
    "excitation": {"static": "vector?", "cosine": "vector?", "sine": "vector?", "base": "vector?"},
    "harmonics": {"H": "int?", "set": "vector?", "n_time": "int?"},
    "range": {"omega": "vector", "max_points": "int?", "ds_max": "number?"},
}

NEEDS = {
    "jenkins": ("dof", "N", "K_d"),
    "mindlin": ("dof", "N", "K_d"),
    "elastic2d": ("tangential_dof", "normal_dof", "k_t", "k_n"),
}


def _contact(i: int, c: dict):
    kind = c["type"].lower()
    if kind not in NEEDS:
        raise ValueError(f"contact {i + 1}: type {c['type']!r} is not one of {', '.join(NEEDS)}")
    missing = [k for k in NEEDS[kind] if k not in c]
    if missing:
        raise ValueError(f"contact {i + 1} ({kind}) needs {', '.join(missing)}")
    if kind == "elastic2d":
        el = ElasticDryFriction2D(c["k_t"], c["k_n"], c["mu"], c.get("n0", 0.0))
        return DryFrictionContact2D(el, c["tangential_dof"], c["normal_dof"])
    el = (Jenkins if kind == "jenkins" else Mindlin)(c["mu"], c["N"], c["K_d"])
    return FrictionContact(el, c["dof"], c.get("ref_dof"))


def build(cfg: dict):
    """(FrictionSystem, (ω_start, ω_end), continuation options) from a checked configuration."""
    s = cfg["structure"]
    structure = Structure(s["M"], s["C"], s["K"])
    contacts = [_contact(i, c) for i, c in enumerate(cfg["contact"])]
    ex = Excitation(structure.n_dof, **cfg["excitation"])
    h = cfg["harmonics"]
    hs = None if "set" not in h else [int(k) for k in h["set"]]
    H = h.get("H", None if hs else 5)
    system = FrictionSystem(structure, contacts, ex, H=H, harmonics=hs, n_time=h.get("n_time"))
    r = cfg["range"]
    if len(r["omega"]) != 2:
        raise ValueError(f"range omega = {r['omega']} must be [start, end] in rad/s")
    if min(r["omega"]) <= 0 or r["omega"][0] == r["omega"][1]:
        raise ValueError(f"frequency range omega = {r['omega']} rad/s must be > 0 and non-empty")
    opts = {"max_points": r.get("max_points", 400), "ds_max": r.get("ds_max", 0.3)}
    return system, tuple(r["omega"]), opts


def run_frf(args) -> int:
    try:
        cfg = read_config(args.config, SCHEMA)
        system, (w0, w1), opts = build(cfg)
    except (DataFileError, ValueError, TypeError) as err:
        return error(
            f"{args.config}: {err}" if not str(err).startswith(str(args.config)) else str(err)
        )
    out = Path(args.out)
    with claim_outputs(
        args.config, [out / "frf.json", out / "frf.csv", out / "frf.png"], force=False
    ):
        t0 = time.perf_counter()
        with progress(args, "frf: continuation"):
            fr = frequency_response(system, w0, w1, **opts)
        elapsed = time.perf_counter() - t0
        n = system.n_dof
        lines = ["omega_rad_per_s," + ",".join(f"amplitude_dof{i}_m" for i in range(n)) + ",stable"]
        for w, a, st in zip(fr.omega, fr.amplitude, fr.stable):
            lines.append(f"{w:.10g}," + ",".join(f"{x:.10g}" for x in a) + f",{int(st)}")
        write_text_atomic(out / "frf.csv", "\n".join(lines) + "\n")
        result = fr.to_dict()
        peaks = [dict(zip(("omega", "amplitude"), fr.peak(i))) for i in range(n)]
        result.update(elapsed_s=elapsed, n_points=len(fr.omega), config=cfg, peaks=peaks)
        write_json_atomic(out / "frf.json", result, exclusive=True)
        _plot(fr, out / "frf.png")
    print(f"{len(fr.omega)} points, {result['result']} ({elapsed:.2f} s); wrote {out}/frf.*")
    for i, p in enumerate(result["peaks"]):
        print(f"  DOF {i}: peak amplitude {p['amplitude']:.5g} m at {p['omega']:.5g} rad/s")
    if not fr.converged:
        print(f"continuation stopped early: {fr.message}")
        return 1
    return 0


def _plot(fr, path) -> None:
    fig = figure("frf.png", figsize=(7, 4.5), constrained_layout=True)
    if fig is None:
        return
    ax = fig.subplots()
    for i in range(fr.amplitude.shape[1]):
        a = np.where(fr.stable, fr.amplitude[:, i], np.nan)
        ax.plot(fr.omega, a, f"C{i}-", label=f"DOF {i}")
        ax.plot(fr.omega, np.where(fr.stable, np.nan, fr.amplitude[:, i]), f"C{i}--")
    ax.set_xlabel("excitation frequency ω (rad/s)")
    ax.set_ylabel("first-harmonic amplitude (m)")
    ax.set_yscale("log")
    ax.legend(title="dashed: unstable (Hill)")
    save_figure(fig, path)
