"""`tribojax contact`: a surface (topography file, or D and G) → F_s, K_τ, C_τ at each load.

    tribojax contact --D 2.88 --G 4.36e-8 --load 3 10 [--json out.json]
    tribojax contact --topography profile.csv --unit um --load 5 [--method psd] [--band LO HI]

D and G of a topography come from `estimate_fractal`; a surface without a clean scaling band:
`surface_estimate` and `_no_fractal_band`.
"""

from __future__ import annotations

import math
import re
from contextlib import nullcontext
from pathlib import Path

import numpy as np

from .._contact._contact import FractalContact
from .._contact._presets import wang2022_pair
from .._contact._surface import FractalSurface
from .._roughness._estimate import METHODS, estimate_fractal
from .._roughness._topography import read_topography
from ._arguments import CONTACT_DEFAULTS as CONTACT_DEFAULTS
from ._common import CommandError, claim_outputs, warn, write_json_atomic

_LOWER = {"gamma": 1.0}  # the frequency-density ratio γ > 1; the others > 0


def _check_arguments(args) -> None:
    for load in args.load:
        if not (math.isfinite(load) and load > 0):
            raise CommandError(f"--load = {load:g} N is outside the allowed range (0, inf)")
    for k in CONTACT_DEFAULTS:
        v, lo = getattr(args, k), _LOWER.get(k, 0.0)
        if not (math.isfinite(v) and v > lo):
            flag = "--" + k.replace("_", "-")
            raise CommandError(f"{flag} = {v:g} is outside the allowed range ({lo:g}, inf)")
    if args.band is not None:
        lo, hi = args.band
        if not (math.isfinite(hi) and 0 < lo < hi):
            raise CommandError(f"--band = {lo:g} {hi:g} m must satisfy 0 < LO < HI < inf")
    if args.topography is not None and (args.D is not None or args.G is not None):
        raise CommandError("give either --topography or --D/--G, not both")
    if args.topography is None and (args.D is None or args.G is None):
        raise CommandError("give --topography FILE, or both --D and --G")


def surface_estimate(topo, args):
    """(estimate, []) of D, G of `topo` by `args.method`; without a clean scaling band, the
    best band with 2 < D < 3 of that method or, failing that, of another method (the estimate's
    `warning` says so). (None, every method's finding) when no band gives 2 < D < 3 (or the
    given `--band` does not)."""
    kw = dict(band=args.band, M=int(args.M), min_decades=args.min_decades)
    try:
        return estimate_fractal(topo, args.method, **kw), []
    except ValueError as err:
        if "no fractal scaling band" not in str(err):
            raise
        first = str(err)
    if args.band is not None:
        return None, [_finding(first)]
    order = [args.method] + [m for m in METHODS if m != args.method]
    found, failures = [], {args.method: first}
    for method in order:
        try:
            found.append(estimate_fractal(topo, method, best_band=True, **kw))
        except ValueError as err:
            failures.setdefault(method, str(err))
    if found:
        return min(found, key=lambda e: (e.method != args.method, e.rms_residual)), []
    return None, [_finding(failures[m]) for m in order]


def _finding(text: str) -> str:
    """'method: D = ... over LO-HI m (rms log10 residual ...)' from an estimator's message."""
    m = re.search(
        r"by '(\w+)': \w+ \w+ band (\S+ m) has slope \S+ \(D = ([-\d.]+).*?"
        r"residual ([\d.]+)",
        text,
    )
    return f"{m[1]}: D = {m[3]} over {m[2]} (rms log10 residual {m[4]})" if m else text


def run_contact(args) -> int:
    """`tribojax contact`: 0 when every contact solve converged, else 1 (2 bad input)."""
    _check_arguments(args)
    result = {"assumed": {}}
    with (
        claim_outputs(args.topography, [Path(args.json)], force=args.force)
        if args.json
        else nullcontext()
    ):
        if args.topography is not None:
            topo = read_topography(args.topography, unit=args.unit, dx=args.dx)
            est, findings = surface_estimate(topo, args)
            if est is None:
                return _no_fractal_band(topo, findings, result, args)
            D, G = est.D, est.G
            result["surface"] = est.as_dict()
            print(
                f"{topo.source}: D = {D:.4f} ± {est.D_std:.4f}, G = {G:.4g} m (± "
                f"{est.log10G_std:.2f} in log10) by {est.method}, band {est.band[0]:.3g}-"
                f"{est.band[1]:.3g} m"
            )
            if est.warning:
                if est.method != args.method:
                    warn(f"no fractal scaling band by {args.method!r}; used {est.method!r}")
                warn(f"{topo.source}: {est.warning}; --band LO HI fixes the band")
        else:
            D, G = args.D, args.G
            result["surface"] = {"D": D, "G": G, "method": "given"}
        rows = _contact_rows(args, D, G, result)
        result["contact"] = rows
        if args.json:
            write_json_atomic(Path(args.json), result)
            print(f"wrote {args.json}")
    return 0 if all(r["converged"] and r["in_range"] for r in rows) else 1


def _no_fractal_band(topo, findings, result, args) -> int:
    """The answer for a surface with no band of 2 < D < 3: every method's D and band, no
    contact numbers (the model needs 2 < D < 3), a warning that says what to do; exit 0."""
    where = "over the given band" if args.band is not None else "over any band searched"
    smooth = any(re.search(r"D = 1\.|D = 0\.|D = -", f) for f in findings)
    text = (
        f"{topo.source}: no fractal scaling {where} ({'; '.join(findings)})"
        + (
            "; a D below 2 means the surface is smoother than a fractal one over the measured range"
            if smooth
            else ""
        )
        + "; the contact model needs 2 < D < 3, so no contact numbers are given: pass "
        "--D and --G (e.g. from a longer or finer measurement), or --band LO HI"
    )
    warn(text)
    print(f"{topo.source}: no band with 2 < D < 3; estimates: {'; '.join(findings)}")
    result["surface"] = {
        "D": None,
        "G": None,
        "method": args.method,
        "findings": findings,
        "band": args.band,
        "warning": text,
    }
    result["contact"] = []
    if args.json:
        write_json_atomic(Path(args.json), result)
        print(f"wrote {args.json}")
    return 0


_PHYSICAL = ("Fs_N", "Ktau_N_per_m", "Ctau_Ns_per_m", "zmax_m")  # finite and >= 0


def _contact_rows(args, D, G, result) -> list:
    assumed = {k: getattr(args, k) for k in CONTACT_DEFAULTS}
    print(
        "assumed: "
        + ", ".join(f"{k} = {v:g}" for k, v in assumed.items())
        + "; wang2022 Table 2 materials"
    )
    result["assumed"] = {
        **assumed,
        "materials": "wang2022 Table 2 pair (E* 41.28 GPa, G' 9.158 GPa, H 1.372 GPa)",
    }
    pair = wang2022_pair(sigma_s=args.sigma_s)
    model = FractalContact(
        FractalSurface(D, G, args.M, gamma=args.gamma),
        pair,
        mu_t=args.mu_t,
        tangential_load=args.tangential_load,
        mass=args.mass,
        throw=False,
    )
    rows = []
    print(f"{'load/N':>9} {'F_s/N':>10} {'K_tau/(N/m)':>12} {'C_tau/(Ns/m)':>12} {'z_max/nm':>9}")
    for load in args.load:
        out = model(load)
        row = {
            "load_N": load,
            "Fs_N": float(out.F_s),
            "Ktau_N_per_m": float(out.K_tau),
            "Ctau_Ns_per_m": float(out.C_tau),
            "zmax_m": float(out.z_max),
            "load_share": np.asarray(out.load_share).tolist(),
            "converged": bool(out.converged),
            "all_plastic": bool(out.all_plastic),
        }
        bad = [k for k in _PHYSICAL if not (math.isfinite(row[k]) and row[k] >= 0)]
        row["in_range"] = not bad
        rows.append(row)
        if bad:
            warn(
                f"load {load:g} N: {', '.join(f'{k} = {row[k]:g}' for k in bad)} is outside the "
                f"physical range [0, inf): the model (wang2022 Eqs 8-24) breaks down at D = "
                f"{D:g}, G = {G:g} m and this load, so this is not a result (exit 1); it is "
                "checked against the paper at 3.7-21 N (Table 3)"
            )
        if row["all_plastic"]:
            warn(
                f"load {load:g} N: every asperity is fully plastic (a'_l <= a'_pc): F_s, K_tau, "
                "C_tau are 0 in this model; check G (too large?), M and the load"
            )
        elif row["Fs_N"] == 0.0:
            warn(
                f"load {load:g} N: no asperity is elastic or first elastic-plastic (a'_l <= "
                "a'_epc), so F_s = z_max = 0 in this model (wang2022 Eqs 14, 16)"
            )
        if not row["converged"]:
            warn(f"load {load:g} N: the load balance did not converge (wang2022 Eqs 8-15)")
        print(
            f"{load:9.4g} {row['Fs_N']:10.4g} {row['Ktau_N_per_m']:12.4g} "
            f"{row['Ctau_Ns_per_m']:12.4g} {1e9 * row['zmax_m']:9.4g}"
        )
    return rows
