"""`tribojax hysteresis`: K̄, C̄, K_eq, C_eq of a friction element over an amplitude range.

    tribojax hysteresis --element mindlin --mu 0.3 --N 2.94 --K-d 1.3e6 --abar 0.05 4.5 --n 100
    tribojax hysteresis --element lugre --mu 0.3 --N 2.94 --K-d 1.3e6 --C-tau 50   # time domain
    tribojax hysteresis --loop measured.csv --element mindlin      # also analyse and fit a loop

Writes hysteresis.csv and hysteresis.png (and, with --loop, loop_fit.json) into --out, which must
not be the folder of the loop file (inputs are never overwritten).
"""

from __future__ import annotations

import io
import math
import sys
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from .._dynamics._harmonic import harmonic_balance, harmonic_response
from .._friction._lugre import PreSlipLuGre
from .._friction._rate_independent import Jenkins, Mindlin
from .._io._files import write_text_atomic
from .._io._hysteresis_loop import read_loop
from .._limits import SAMPLE_LIMITS
from .._model import analyse_loop, fit_loop
from .._plot import figure, save_figure
from .._reproduce._wu2015 import wu2015_eq5_stiffness
from .._tables import read_json
from ._common import claim_outputs, error, warn, write_json_atomic

A_MIN_M = 1e-15  # the smallest amplitude worth a harmonic balance (a femtometre)


def run_hysteresis(args) -> int:
    """Run `tribojax hysteresis`: 0 done, 1 the loop fit did not converge, 2 bad input.

    Everything is computed (and a --loop read and fitted) before the first file is written, so
    a refused input leaves no output behind.
    """
    out = Path(args.out)
    if args.loop is not None and out.resolve() == Path(args.loop).resolve().parent:
        return error("--out must not be the folder of the --loop file")
    if args.n < 2:
        return error(f"--n = {args.n} must be at least 2")
    for flag, value, lo in (
        ("--omega", args.omega, 0.0),
        ("--mu", args.mu, 0.0),
        ("--N", args.N, 0.0),
        ("--K-d", args.K_d, 0.0),
        ("--C-tau", args.C_tau, None),
    ):
        ok = value is None or (math.isfinite(value) and (value >= 0 if lo is None else value > lo))
        if not ok:
            bound = "[0, inf)" if lo is None else "(0, inf)"
            return error(f"{flag} = {value:g} is outside the allowed range {bound}")
    if args.loop is not None and args.element == "lugre":
        return error("--loop fits a jenkins or mindlin element, not lugre")
    loop_result = _fit_loop(args) if args.loop is not None else None
    K_d = args.K_d if args.K_d is not None else float(wu2015_eq5_stiffness(args.N))
    if args.element == "lugre":
        element = PreSlipLuGre(args.mu * args.N, K_d, args.C_tau)
        A0 = float(element.z_max)
    else:
        element = {"jenkins": Jenkins, "mindlin": Mindlin}[args.element](args.mu, args.N, K_d)
        A0 = float(element.A0)
    lo, hi = args.A if args.A is not None else [a * A0 for a in (args.abar or (0.05, 4.5))]
    if not 0 < lo < hi < math.inf:
        return error(f"amplitude range ({lo:g}, {hi:g}) m must satisfy 0 < min < max < inf")
    if not (A_MIN_M <= lo and hi <= SAMPLE_LIMITS["u"][0]):  # femtometres to a kilometre
        scale = (
            ""
            if args.A is not None
            else (
                f" (= --abar x A0, A0 = {A0:.3g} m from mu = {args.mu:g}, N = {args.N:g} N, "
                f"K_d = {K_d:.3g} N/m)"
            )
        )
        return error(
            f"amplitude range ({lo:.3g}, {hi:.3g}) m{scale} is outside the physical "
            f"range [{A_MIN_M:g}, {SAMPLE_LIMITS['u'][0]:g}] m"
        )
    outputs = [out / "hysteresis.csv", out / "hysteresis.png", out / "loop_fit.json"]
    targets = outputs[:3] if loop_result is not None else outputs[:2]
    earlier = [p for p in outputs if p.exists()]
    if earlier and not args.force:
        return error(
            f"{out} holds an earlier result ({', '.join(p.name for p in earlier)}); "
            "refusing to replace it (use --force or another --out)"
        )
    with claim_outputs(args.loop, targets, force=True):
        for p in earlier:  # --force: no file of an earlier run stays beside this run's
            if p in targets:
                continue
            if _written_here(p):
                p.unlink()
            else:
                warn(f"{p} was not written by tribojax hysteresis; left as it is")
        A = jnp.linspace(lo, hi, args.n)
        if args.element == "lugre":
            hb = _lugre_response(element, A, args.omega, K_d, A0)
        else:
            hb = jax.jit(jax.vmap(harmonic_balance, in_axes=(None, 0, None)))(
                element, A, args.omega
            )
        cols = ("A", "A_bar", "K_eq", "C_eq", "K_bar", "C_bar", "W")
        header = "A_m,A_bar,K_eq_N_per_m,C_eq_Ns_per_m,K_bar,C_bar,W_J"
        table = np.stack([np.asarray(getattr(hb, c)) for c in cols], axis=1)
        bad = [c for c, col in zip(cols, table.T) if not np.all(np.isfinite(col))]
        if bad:  # inputs beyond float64 (omega = 1e-300 rad/s: C_eq = W/(pi omega A^2) overflows)
            return error(
                f"{', '.join(bad)} not finite at some amplitude: the inputs (omega = "
                f"{args.omega:g} rad/s, mu = {args.mu:g}, N = {args.N:g} N, K_d = "
                f"{K_d:g} N/m) are outside float64's range"
            )
        comment = (
            f"# tribojax hysteresis: {args.element}, mu = {args.mu:g}, N = {args.N:g} N, "
            f"K_d = {K_d:.6g} N/m, A0 = {A0:.6g} m, omega = {args.omega:.6g} rad/s"
        )
        csv_path = out / "hysteresis.csv"
        text = io.StringIO()
        np.savetxt(text, table, delimiter=",", header=header, comments=comment + "\n", fmt="%.12g")
        write_text_atomic(csv_path, text.getvalue())
        print(comment[2:])
        print(f"K_bar {float(hb.K_bar[0]):.4f} .. {float(hb.K_bar[-1]):.4f}; C_bar max ", end="")
        print(f"{float(hb.C_bar.max()):.4f} at A_bar {float(hb.A_bar[int(hb.C_bar.argmax())]):.3f}")
        print(f"wrote {csv_path}")
        if _plot(hb, args.element, out / "hysteresis.png"):
            print(f"wrote {out / 'hysteresis.png'}")
        if loop_result is None:
            return 0
        write_json_atomic(out / "loop_fit.json", loop_result)
    print(f"wrote {out / 'loop_fit.json'}")
    return 0 if loop_result["fit"]["converged"] else 1


def _lugre_response(element, A, omega, K_d, A0):
    """K̄, C̄ of the LuGre pre-slip element (wang2022 Eq 27) by the time-domain route.

    The start-up transient of the bristle state contracts by exp(−4A/z_max) per cycle (α = 1), so
    the number of cycles is chosen from the smallest amplitude (transient below 1e-8, at most 400).
    """
    cycles = min(400, max(3, math.ceil(math.log(1e8) * A0 / (4 * float(A.min()))) + 1))
    if cycles == 400:
        print("note: 400 cycles do not settle the smallest amplitudes to 1e-8", file=sys.stderr)
    one = partial(
        harmonic_response, element, omega=omega, cycles=cycles, steps_per_cycle=1024, K_d=K_d, A0=A0
    )
    return jax.jit(jax.vmap(one))(A)


def _fit_loop(args) -> dict:
    """Read, analyse and fit the --loop file; the loop_fit.json content (printed summary)."""
    loop = read_loop(args.loop)
    a = analyse_loop(loop)
    fit = fit_loop(loop, args.element, model=args.fit_model, throw=False)
    result = {
        "written_by": WRITER,
        "loop": str(args.loop),
        "analysis": a.as_dict(),
        "fit": {**fit.as_dict(), "element": args.element, "model": args.fit_model},
    }
    print(
        f"loop: A = {a.A:.4g} m, muN = {a.mu_N:.4g} N, K_d (Eq 6) = {a.K_d:.4g} N/m, "
        f"K_eq = {a.K_eq:.4g} N/m, C_eq = {a.C_eq:.4g} N s/m"
    )
    values = zip(fit.names, fit.values, fit.std_errors)
    print(
        f"fit ({args.element}): "
        + ", ".join(f"{n} = {v:.5g} ± {s:.2g}" for n, v, s in values)
        + f" (converged: {fit.converged}, {fit.steps} steps)"
    )
    return result


WRITER = "tribojax hysteresis"
"""loop_fit.json's "written_by": `--force` removes an earlier loop fit only when it says so."""


def _written_here(path: Path) -> bool:
    try:
        d, _ = read_json(path)
    except (OSError, ValueError):
        return False
    return isinstance(d, dict) and d.get("written_by") == WRITER


def _plot(hb, element: str, path: Path) -> bool:
    fig = figure("figure", figsize=(6, 4), constrained_layout=True)
    if fig is None:
        return False
    ax = fig.subplots()
    ax.plot(hb.A_bar, hb.K_bar, "C0-", label="K̄ = K_eq / K_d")
    ax.plot(hb.A_bar, hb.C_bar, "C3-", label="C̄ = πωC_eq / K_d")
    ax.set_xlabel("Ā = A / A0")
    ax.set_title(f"{element}: dimensionless equivalent stiffness and damping (wu2015)")
    ax.grid(alpha=0.3)
    ax.legend()
    save_figure(fig, path)
    return True
